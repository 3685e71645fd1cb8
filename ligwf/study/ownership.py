"""A study's folder is its own: a workflow is written only into an empty folder, a folder
of its own earlier rendering, or one the user explicitly replaces.

snakemake refuses to run a rule into an output another rule owns; signac gives a job
another state point another folder. ligwf's rule: before anything is written, the study
record in ``--out`` (:mod:`ligwf.study.study_record`) is compared with the workflow about
to be written. Another name or other workflow values (scene, sweep, seeds, process: what
the runs are made from; not the analysis and verdict settings, which later stages record
themselves) is another study: refused in one line naming both studies and what differs.
``--replace`` writes it anyway; cases whose scene is unchanged keep their runs (identical
case folders are rewritten byte for byte), changed ones are run again.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable

from ligwf.errors import ConfigError
from ligwf.study.layout import OUTPUT_DIRS, SCENE_FILE, STUDY_FILE, is_study_folder
from ligwf.study.made_from import as_json, leaves
from ligwf.study.paths import check_case_id, check_inside
from ligwf.study.study_record import UNSEALED_WORKFLOW_KEYS, StudyRecord

#: differences named in the refusal at most (the rest are counted)
SHOWN_DIFFERENCES = 3


def _runs_made_from(workflow: Any) -> dict:
    """The workflow values the runs are made from (JSON form, name and later stages'
    settings left out)."""
    if not isinstance(workflow, dict):
        return {}
    return as_json({k: v for k, v in workflow.items()
                    if k not in UNSEALED_WORKFLOW_KEYS and k != "name"})


def _value(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 30 else text[:27] + "..."


def workflow_differences(old: dict, new: dict) -> list[str]:
    """Where the workflow values ``new`` differ from ``old`` (``path old -> new``,
    ``path added``, ``path removed``), in the order of the new workflow."""
    was, now = leaves(_runs_made_from(old)), leaves(_runs_made_from(new))
    out = [f"{p} {_value(was[p])} -> {_value(v)}" for p, v in now.items()
           if p in was and was[p] != v]
    out += [f"{p} = {_value(v)} added" for p, v in now.items() if p not in was]
    out += [f"{p} removed" for p in was if p not in now]
    return out


def other_study(out: Path, name: str, workflow: dict) -> str | None:
    """Why ``out`` holds another study than the workflow ``name`` / ``workflow`` (one
    line), None when it holds none or this one."""
    if not is_study_folder(out):
        return None
    try:
        record = StudyRecord.read(out)
    except ConfigError as exc:
        return (f"--out {out} holds a study record ligwf cannot take for this study's "
                f"({exc}); nothing written: name another folder, or pass --replace to "
                "replace it")
    diffs = ([f"name {record.name!r} -> {name!r}"] if record.name != name else []) + \
        workflow_differences(record.workflow, workflow)
    if not diffs:
        return None
    more = len(diffs) - SHOWN_DIFFERENCES
    shown = "; ".join(diffs[:SHOWN_DIFFERENCES]) + (f" (and {more} more)" if more > 0 else "")
    return (f"--out {out} holds another study: {record.name!r} ({len(record.cases)} "
            f"case(s)) there, {name!r} in this workflow; {shown}; nothing written: name "
            "another folder, or pass --replace to replace it (the runs of cases it does not "
            "change are kept)")


def check_own_folder(out: Path, name: str, workflow: dict, case_ids: Iterable[str],
                     files: Iterable[str], replace: bool = False) -> None:
    """Everything checked before a study is written into ``out`` (ConfigError, one line):
    the case ids are folder names, ``out`` holds no other study (unless ``replace``), and
    the study record, every case folder, its output folders and ``files`` in it are no
    symbolic links and resolve inside ``out``."""
    ids = list(case_ids)
    for case_id in ids:
        check_case_id(case_id, f"workflow {name!r}")
    paths = [out / STUDY_FILE]
    for case_id in ids:
        case = out / case_id
        paths += [case, *(case / sub for sub in OUTPUT_DIRS), case / SCENE_FILE,
                  *(case / f for f in files)]
    check_inside(out, paths)
    if not replace and (why := other_study(out, name, workflow)) is not None:
        raise ConfigError(why)
