"""Provenance of an analysis: what it was computed from, and whether it still holds.

The analysis record stores the settings' digest and, per case of the study, the scene
hash and the dump record's digest (:func:`study_provenance`), and the size and SHA-256 of
every table it wrote. A reader (the report) compares them with the study as it is now
(:func:`provenance_mismatch`) and with the tables on disk (:func:`damaged_outputs`) before
it uses any of them.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from ligwf.analysis.frames.dumps import dump_files
from ligwf.errors import ConfigError, LigwfError
from ligwf.fsio import file_sha256
from ligwf.study.case import folder_fingerprint


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
        elif file_sha256(path) != entry[1]:
            bad.append(f"{name}: content differs from what the analysis wrote (edited)")
    return bad


def changed_dumps(study, flow) -> str | None:
    """Why a dump the analysis read (``flow``: the
    :class:`~ligwf.analysis.records.flow.FlowRecord`; its read frames passed the record check
    for both their particle and their contact dump) is no longer the one the run left (size
    or SHA-256 against the case's dump record: post/ folders swapped, a dump edited, even
    at the same size), in words; None when every one still is (cases without a dump record
    are not checked). Every dump kind the analysis reads is re-hashed: particles and
    contacts."""
    for case in study.usable_cases()[0]:
        c = flow.cases.get(case.case_id)
        if c is None:
            continue
        try:
            record = case.dump_record()
        except ConfigError as exc:
            return str(exc)
        if record is None:
            continue
        files = dict(c.frames)
        contacts = dump_files(case.path)[1]
        for step in c.read_steps:
            read = [case.path / files[step]]
            if step in contacts:
                read.append(contacts[step])
            for path in read:
                if (why := record.mismatch(path)) is not None:
                    return why
    return None
