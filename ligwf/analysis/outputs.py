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
folder that are not analysis outputs (a user's notes) are left alone.
"""

from __future__ import annotations

import os
import shutil
import uuid
from dataclasses import dataclass
from pathlib import Path

from ligwf.study import layout
from ligwf.fsio import file_sha256

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
        return self.out_dir / layout.staging_dir(self.token)

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
        return {p.name: [p.stat().st_size, file_sha256(p)] for p in sorted(self.stage.iterdir())
                if p.is_file()}

    def commit(self, record_name: str, obsolete: tuple[str, ...] = ()) -> None:
        """Move the staged set into ``out_dir`` (``record_name`` last) and drop the old
        (series folders, and the files named in ``obsolete`` this set does not hold)."""
        out, stage = self.out_dir, self.stage
        trash = out / layout.replaced_dir(self.token)
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
