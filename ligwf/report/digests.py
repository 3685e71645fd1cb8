"""The report's own record of what it wrote: size and SHA-256 of every top-level file of
the report folder (tables, verdict record, pages), so a reader of the tables (the Python
API's :meth:`ligwf.api.results.StudyResults.check`) can tell an edited or emptied table
(``: > report/conditions.csv``) from the report's, as the analysis record does for the
analysis tables."""

from __future__ import annotations

import json
from pathlib import Path

from ligwf.fsio import atomic_write_json, file_sha256
from ligwf.study.layout import REPORT_FILES_RECORD

#: the record, in the report folder (never listed in itself)
DIGEST_RECORD = REPORT_FILES_RECORD


def file_digest(path: Path) -> dict:
    """``{"size": bytes, "sha256": hex}`` of one file."""
    return {"size": path.stat().st_size, "sha256": file_sha256(path)}


def record_digests(report_dir: Path) -> None:
    """Write the record of every top-level file of ``report_dir`` (after the report)."""
    report_dir = Path(report_dir)
    files = {p.name: file_digest(p) for p in sorted(report_dir.iterdir())
             if p.is_file() and not p.is_symlink() and p.name != DIGEST_RECORD
             and not p.name.startswith(".")}
    atomic_write_json(report_dir / DIGEST_RECORD, files)


def damaged_report_files(report_dir: Path) -> list[str]:
    """Why each recorded file of the report no longer is what the report wrote (edited,
    emptied, removed); ["... no record ..."] for a report without the record (written
    before ligwf recorded it, or the record itself damaged); [] when all match."""
    report_dir = Path(report_dir)
    try:
        record = json.loads((report_dir / DIGEST_RECORD).read_text())
    except (OSError, ValueError):
        record = None
    if not isinstance(record, dict):
        return [f"{report_dir / DIGEST_RECORD}: no readable record of the report's files"]
    out = []
    for name, want in sorted(record.items()):
        path = report_dir / name
        if not path.is_file():
            out.append(f"{path}: removed since the report wrote it")
        elif not isinstance(want, dict) or file_digest(path) != want:
            out.append(f"{path}: changed since the report wrote it")
    return out
