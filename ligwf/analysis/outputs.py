"""Analysis outputs written as one set: all new, or all old, never a mix or a half.

The tables, the analysis record and the per-case ParaView series of one ``ligwf analyse``
belong together (the series' granule ids are the table's). They are staged in a hidden
folder inside the output folder (on the same file system, so moving is a rename), and
only once everything is written does :meth:`OutputSet.commit` move them into place:
the old per-case series folders are moved aside first (a case analysed now without
``.vtu``, or not at all, keeps no stale series), the new ones moved in, the tables
replaced one by one (each rename is atomic) and the analysis record last, so a reader
who finds the new record finds the new set. A failed or refused analysis calls
:meth:`OutputSet.discard` and the previous outputs stay untouched. Files in the output
folder that are not analysis outputs (the flow tables, a user's notes) are left alone.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import uuid
from dataclasses import dataclass
from pathlib import Path

from ligwf.errors import LigwfError
from ligwf.study import layout
from ligwf.study.case import file_digest, folder_fingerprint

def is_series_dir(path: Path) -> bool:
    """Whether ``path`` is a per-case granule series folder written by the analysis (it
    holds the series file or labelled frames)."""
    return path.is_dir() and ((path / layout.GRANULE_SERIES).is_file()
                              or any(path.glob(layout.GRANULE_FRAME_GLOB)))


def new_token() -> str:
    """A token naming one analysis' staging folder (rank 0 makes it, MPI shares it)."""
    return uuid.uuid4().hex[:12]


@dataclass(frozen=True)
class OutputSet:
    """The staging folder of one analysis into ``out_dir`` (named by ``token``)."""

    out_dir: Path
    token: str

    @property
    def stage(self) -> Path:
        return self.out_dir / f".staging-{self.token}"

    def case_dir(self, case_id: str) -> Path:
        """Where the per-frame ``.vtu`` of a case are written while staging."""
        return self.stage / case_id

    def write(self, name: str, data: bytes) -> None:
        """Stage one file (relative name, e.g. a table or ``<case>/granules.pvd``)."""
        path = self.stage / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)

    def digests(self) -> dict[str, list]:
        """``{name: [size in bytes, SHA-256]}`` of every file staged so far at the top of
        the set (the tables; the per-case series are not listed)."""
        if not self.stage.is_dir():
            return {}
        return {p.name: [p.stat().st_size, file_digest(p)] for p in sorted(self.stage.iterdir())
                if p.is_file()}

    def commit(self, record_name: str, obsolete: tuple[str, ...] = ()) -> None:
        """Move the staged set into ``out_dir`` (``record_name`` last) and drop the old
        (series folders, and the files named in ``obsolete`` this set does not hold)."""
        out, stage = self.out_dir, self.stage
        trash = out / f".replaced-{self.token}"
        trash.mkdir()
        for old in sorted(out.iterdir()):
            if not old.name.startswith(".") and is_series_dir(old):
                os.replace(old, trash / old.name)
        for name in obsolete:
            if (out / name).is_file() and not (stage / name).exists():
                os.replace(out / name, trash / name)
        staged = sorted(stage.iterdir())
        for new in staged:
            if new.is_dir():
                os.replace(new, out / new.name)
        for new in staged:
            if new.is_file() and new.name != record_name:
                os.replace(new, out / new.name)
        os.replace(stage / record_name, out / record_name)
        shutil.rmtree(trash, ignore_errors=True)
        shutil.rmtree(stage, ignore_errors=True)

    def discard(self) -> None:
        """Drop the staged files; the outputs in place stay as they were."""
        shutil.rmtree(self.stage, ignore_errors=True)


# ------------------------------------------------------------------ provenance
# What an analysis was computed from, stored in its record: the analysis settings and, per
# case of the study, the scene hash and the dump record. A reader (the report) compares it
# with the study as it is now and with the tables on disk.


class StaleAnalysis(LigwfError):
    """The analysis outputs no longer match the study, or were changed after writing."""


def _json_digest(data) -> str:
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def study_provenance(study, settings) -> dict:
    """The inputs of an analysis of ``study`` (a :class:`~ligwf.study.study.Study`) with
    ``settings``: the settings' digest and per case its scene hash and the digest of its
    dump record (None where missing or unreadable)."""
    cases = {d.name: folder_fingerprint(d) for d in study.case_dirs}
    return {"settings": _json_digest(settings.model_dump(mode="json")), "cases": cases}


def provenance_mismatch(study, settings, record: dict) -> str | None:
    """What changed since ``record`` (an analysis record) was written, in words; None when
    the study, its dumps and the settings are still those the analysis used."""
    then = record.get("provenance")
    if not isinstance(then, dict) or not isinstance(then.get("cases"), dict):
        return ("it records no provenance (scene and dump hashes): written by an older ligwf "
                "or for another study")
    now = study_provenance(study, settings)
    old, new = then["cases"], now["cases"]
    if set(old) != set(new):
        added, gone = sorted(set(new) - set(old)), sorted(set(old) - set(new))
        return ("it was written for other cases ("
                + "; ".join(x for x in (f"not analysed: {', '.join(added)}" if added else "",
                                        f"not in the study: {', '.join(gone)}" if gone else "")
                            if x) + ")")
    for cid in new:
        if old[cid].get("scene_hash") != new[cid]["scene_hash"]:
            return f"case {cid}: its scene changed since the analysis (re-rendered)"
        if old[cid].get("dump_record") != new[cid]["dump_record"]:
            return f"case {cid}: its dumps changed since the analysis (run again)"
    if then.get("settings") != now["settings"]:
        return "the study's analysis settings changed since it was written"
    return None


def damaged_outputs(out_dir: Path, record: dict) -> list[str]:
    """Tables of ``out_dir`` that differ from what the analysis of ``record`` wrote (size or
    SHA-256), one line each; missing ones are not listed here."""
    bad = []
    for name, entry in sorted((record.get("outputs") or {}).items()):
        path = Path(out_dir) / name
        if not path.is_file():
            continue
        size = path.stat().st_size
        if size != entry[0]:
            bad.append(f"{name}: {size} bytes, the analysis wrote {entry[0]} (truncated or "
                       "replaced)")
        elif file_digest(path) != entry[1]:
            bad.append(f"{name}: content differs from what the analysis wrote (edited)")
    return bad
