"""The analysis record (``analysis.json`` in the study's analysis folder), read and written
only here.

An analysis writes its tables into a staging folder and this record last
(:meth:`AnalysisRecord.commit`): the settings it ran with, its provenance (per case the
scene hash and the dump record's digest, :func:`~ligwf.analysis.records.provenance.study_provenance`),
the cases and frames it skipped, the cases without granule data and why, and the size and
SHA-256 of every table it wrote. Every reader (the report, its problems list, the field
section, the API) goes through :meth:`AnalysisRecord.read`, and the checks a reader makes
before it trusts a table (the study still the one analysed, the tables still those
written) are methods here.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from ligwf.analysis.outputs import OutputSet
from ligwf.analysis.records.provenance import damaged_outputs, provenance_mismatch
from ligwf.study import layout


class UnreadableRecord(ValueError):
    """The record exists but is not a JSON object ligwf wrote (its message says why)."""


@dataclass(frozen=True)
class AnalysisRecord:
    """One analysis record: the JSON object as written (``data``) and where it lies."""

    folder: Path
    data: dict = field(default_factory=dict)

    @property
    def path(self) -> Path:
        return Path(self.folder) / layout.ANALYSIS_RECORD

    # ------------------------------------------------------------------ reading
    @classmethod
    def load(cls, folder: Path) -> "AnalysisRecord":
        """The record of the analysis folder ``folder``: FileNotFoundError when there is
        none, :class:`UnreadableRecord` when it is not a JSON object."""
        path = Path(folder) / layout.ANALYSIS_RECORD
        try:
            data = json.loads(path.read_text())
        except FileNotFoundError:
            raise
        except (OSError, ValueError) as exc:
            raise UnreadableRecord(str(exc)) from None
        if not isinstance(data, dict):
            raise UnreadableRecord("not a JSON object")
        return cls(Path(folder), data)

    @classmethod
    def read(cls, folder: Path) -> "AnalysisRecord | None":
        """The record of ``folder``, or None when it is missing or unreadable."""
        try:
            return cls.load(folder)
        except (FileNotFoundError, UnreadableRecord):
            return None

    def items(self, key: str) -> list:
        """``data[key]`` when it is a list (a damaged record may hold anything there)."""
        value = self.data.get(key)
        return value if isinstance(value, list) else []

    @property
    def outputs(self) -> dict:
        """Table name -> [size, SHA-256] of every table the analysis wrote."""
        value = self.data.get("outputs")
        return value if isinstance(value, dict) else {}

    def wrote(self, name: str) -> bool:
        """Whether the analysis wrote the table ``name``."""
        return name in self.outputs

    @property
    def analysed_granules(self) -> bool:
        """Whether granules were analysed (the record lists analysed cases)."""
        return bool(self.data.get("cases"))

    @property
    def granules_absent(self) -> tuple[dict, ...]:
        """``{case_id, reason}`` of every case the analysis wrote no granule data for."""
        return tuple(a for a in self.items("granules_absent") if isinstance(a, dict))

    # ------------------------------------------------------------------ checks
    def stale(self, study, settings) -> str | None:
        """What changed since the analysis (study, dumps, settings), in words; None when
        it still holds (:func:`~ligwf.analysis.records.provenance.provenance_mismatch`)."""
        return provenance_mismatch(study, settings, self.data)

    def damaged(self) -> list[str]:
        """Tables of the analysis folder that differ from what the analysis wrote."""
        return damaged_outputs(self.folder, self.data)

    # ------------------------------------------------------------------ writing
    @staticmethod
    def commit(outputs: OutputSet, record: dict, obsolete: tuple[str, ...] = ()) -> None:
        """Stage the record (``record`` plus the size and SHA-256 of every staged table)
        and move the whole set into place, the record last, so that a reader can tell a
        truncated or replaced table from the one written here; ``obsolete``: outputs of an
        earlier analysis to remove with the set when this one did not write them."""
        record = {**record, "outputs": outputs.digests()}
        outputs.write(layout.ANALYSIS_RECORD,
                      (json.dumps(record, indent=2, sort_keys=True) + "\n").encode())
        outputs.commit(layout.ANALYSIS_RECORD, obsolete)
