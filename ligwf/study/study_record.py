"""The study record (``study.json`` in a study folder), read and written only here.

Written once per rendering (:func:`ligwf.pipeline.prepare.write_study`): the ligwf version,
the study's name and description, the workflow as validated (``--set`` overrides applied),
its analysis settings and error budget as dumped by their models, one entry per case
(index, id, CG level, rule, replica, scene hash) and the seal of what the runs are made
from (:mod:`ligwf.study.made_from`): a record edited by hand is refused on read, naming
the field; a case id that is no plain folder name too (``../victim``). :class:`~ligwf.study.study.Study`, the
rounds of a sequential study and the API read it through :meth:`StudyRecord.read`.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

from ligwf.errors import ConfigError
from ligwf.fsio import atomic_write_json
from ligwf.study.layout import STUDY_FILE
from ligwf.study.made_from import SEAL_KEY, edit_summary, edited_fields, seal
from ligwf.study.paths import check_case_id

#: the sweep's maps keyed by CG level (JSON stores their keys as text)
CG_KEYED = ("replicas", "per_cg")


@dataclass(frozen=True)
class CaseEntry:
    """One case as the study record lists it."""

    index: int
    case_id: str
    cg: float
    rule: str
    replica: int
    scene_hash: str


@dataclass(frozen=True)
class StudyRecord:
    """What ``study.json`` holds (``analysis`` and ``accept``: the models' dumps; None in a
    record from before they were stored)."""

    name: str
    workflow: dict = field(default_factory=dict)
    analysis: dict | None = None
    accept: dict | None = None
    cases: tuple[CaseEntry, ...] = ()
    description: str = ""
    ligwf_version: str = ""

    @property
    def case_ids(self) -> tuple[str, ...]:
        """The case ids in case-index order."""
        return tuple(c.case_id for c in sorted(self.cases, key=lambda c: c.index))

    def write(self, folder: Path) -> None:
        """Write the record into the study folder ``folder`` atomically, sealed
        (:func:`sealed_content`)."""
        cases = [asdict(c) for c in self.cases]
        atomic_write_json(Path(folder) / STUDY_FILE, {
            "ligwf_version": self.ligwf_version, "name": self.name,
            "description": self.description, "workflow": self.workflow,
            "analysis": self.analysis, "accept": self.accept, "cases": cases,
            SEAL_KEY: seal(sealed_content(self.name, self.workflow, cases))})

    @classmethod
    def read(cls, folder: Path) -> "StudyRecord":
        """The record of the study folder ``folder``; ConfigError (one line) when it is
        unreadable or lists a case twice. The workflow's CG-keyed sweep maps get their
        numeric keys back (:func:`numeric_cg_keys`)."""
        path = Path(folder) / STUDY_FILE
        try:
            rec = json.loads(path.read_text())
            cases = tuple(CaseEntry(int(c["index"]), str(c["case_id"]), float(c.get("cg", 1.0)),
                                    str(c.get("rule", "")), int(c.get("replica", 0)),
                                    str(c.get("scene_hash", "")))
                          for c in rec["cases"])
        except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
            raise ConfigError(f"{folder}: unreadable study record ({exc})") from None
        ids = [c.case_id for c in cases]
        twice = sorted({i for i in ids if ids.count(i) > 1})
        if twice:
            raise ConfigError(f"{path}: lists case {', '.join(twice)} more than once (edited "
                              "or merged by hand?): render the study again")
        for case_id in ids:
            check_case_id(case_id, str(path))
        edited = edited_fields(sealed_content(rec.get("name"), rec.get("workflow"),
                                              rec["cases"]), rec.get(SEAL_KEY))
        if edited:
            raise ConfigError(f"{path}: edited after ligwf wrote it ({edit_summary(edited)}); "
                              "ligwf runs, analyses and reports only the study it wrote: undo "
                              "the edit, or render the workflow you mean into the folder "
                              "(--replace)")
        workflow = rec.get("workflow")
        workflow = numeric_cg_keys(workflow) if isinstance(workflow, dict) else {}
        accept = rec["accept"] if "accept" in rec else workflow.get("accept")
        return cls(str(rec.get("name", Path(folder).name)), workflow, rec.get("analysis"),
                   accept, cases, str(rec.get("description") or ""),
                   str(rec.get("ligwf_version", "")))


#: keys of the stored workflow the seal leaves out: the settings of the later stages and
#: prose (the analysis and the report record the settings they used themselves)
UNSEALED_WORKFLOW_KEYS = ("analysis", "accept", "description")


def sealed_content(name, workflow, cases) -> dict:
    """What the study record's seal covers: the name, the workflow without
    :data:`UNSEALED_WORKFLOW_KEYS` and the case list (what the runs are made from)."""
    kept = ({k: v for k, v in workflow.items() if k not in UNSEALED_WORKFLOW_KEYS}
            if isinstance(workflow, dict) else workflow)
    return {"name": name, "workflow": kept, "cases": cases}


def _number(key):
    """A JSON object key back as the number it was written from ("2" -> 2, "1.5" -> 1.5);
    any other text as it is (the workflow's validation names it)."""
    if not isinstance(key, str):
        return key
    for kind in (int, float):
        try:
            return kind(key)
        except ValueError:
            continue
    return key


def numeric_cg_keys(raw: dict) -> dict:
    """The stored workflow with the CG levels of the sweep's per-level maps
    (:data:`CG_KEYED`) as numbers again: JSON turned ``replicas: {1: 2}`` into ``{"1": 2}``,
    which the workflow's strict validation refuses as text."""
    sweep = raw.get("sweep")
    if not isinstance(sweep, dict):
        return raw
    fixed = {name: {_number(k): v for k, v in sweep[name].items()}
             for name in CG_KEYED if isinstance(sweep.get(name), dict)}
    return {**raw, "sweep": {**sweep, **fixed}} if fixed else raw
