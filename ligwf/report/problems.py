"""Everything the report did not use, and why: skipped cases, missing or refused frames,
missing or unreadable analysis outputs.

A problem that sits only in a JSON file is a problem nobody sees, so the report gathers
them from every stage -- the study (cases not done, stale or unreadable), the granule
analysis record (cases without an analysable frame, frames missing, unexpected or
refused, see :mod:`ligwf.analysis.frames.checks`) and the flow stage (frames of the steady
window it could not use) -- and lists them in ``summary.md`` and ``index.html``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from ligwf.analysis.records.analysis_record import AnalysisRecord, UnreadableRecord
from ligwf.study import layout

#: The files of a complete granule analysis (the report reads all of them).
ANALYSIS_OUTPUTS = (layout.GRANULES_TABLE, layout.FRAMES_TABLE, layout.GSD_TABLE,
                    layout.GSD_SUMMARY_TABLE)


@dataclass(frozen=True)
class Problems:
    """What the report lists as not used, each with its reason."""

    cases: tuple[tuple[str, str], ...]              # (case_id, reason)
    frames: tuple[tuple[str, str, str, str], ...]   # (case_id, step, kind, reason)
    outputs: tuple[str, ...]                        # analysis outputs missing or unreadable
    granules_absent: tuple[tuple[str, str], ...] = ()   # (case_id, why): no granule data by design

    @property
    def count(self) -> int:
        return len(self.cases) + len(self.frames) + len(self.outputs)

    def markdown(self) -> list[str]:
        """The report's sections on skipped cases, frames and analysis outputs."""
        def cell(text: str) -> str:
            return text.replace("|", "\\|").replace("\n", " ")
        lines = ["## Skipped cases (not used anywhere in this report)", ""]
        lines += [f"- {cid}: {cell(why)}" for cid, why in self.cases] or ["none"]
        lines += ["", "## Skipped or missing frames", ""]
        if self.frames:
            lines += ["| case | step | kind | reason |", "|---|---|---|---|"]
            lines += [f"| {c} | {s} | {k} | {cell(r)} |" for c, s, k, r in self.frames]
        else:
            lines.append("none")
        lines += ["", "## Analysis outputs", ""]
        lines += [f"- {cell(o)}" for o in self.outputs] or ["complete"]
        lines += ["", *self.granule_lines()]
        return lines + [""]

    def granule_lines(self) -> list[str]:
        """The granule section: why granules, GSD and kinetics are absent for some cases
        (their flow metrics are in the tables above all the same)."""
        if not self.granules_absent:
            return []
        reasons = {why for _, why in self.granules_absent}
        head = ("Granules, GSD and kinetics were not analysed for these cases (their "
                "granule columns are empty; the flow metrics above are theirs):")
        if len(reasons) == 1:
            head = (f"Granules, GSD and kinetics were not analysed: {next(iter(reasons))}. "
                    "The granule columns (largest cluster, GSD errors) stay empty and the "
                    "GSD figures are left out; the flow metrics are complete. Cases:")
        return ["## Granules", "", head, "",
                *[f"- {cid}: {why}" for cid, why in self.granules_absent], ""]


def _read_json(path: Path, what: str, outputs: list[str]) -> dict:
    try:
        data = json.loads(path.read_text())
        if not isinstance(data, dict):
            raise ValueError("not a JSON object")
        return data
    except FileNotFoundError:
        outputs.append(f"{path.name} missing: {what}")
    except (OSError, ValueError) as exc:
        outputs.append(f"{path.name} unreadable ({exc}): {what}")
    return {}


def _analysis_record(analysis_dir: Path, outputs: list[str]) -> AnalysisRecord:
    """The analysis record (an empty one, with a line in ``outputs`` saying why, when it
    is missing or unreadable)."""
    what = "granules were not analysed (run `ligwf analyse`)"
    try:
        return AnalysisRecord.load(analysis_dir)
    except FileNotFoundError:
        outputs.append(f"{layout.ANALYSIS_RECORD} missing: {what}")
    except UnreadableRecord as exc:
        outputs.append(f"{layout.ANALYSIS_RECORD} unreadable ({exc}): {what}")
    return AnalysisRecord(analysis_dir)


def _items(record: dict, key: str) -> list:
    """``record[key]`` when it is a list (a damaged record may hold anything there)."""
    value = record.get(key)
    return value if isinstance(value, list) else []


def collect(study_skipped: list[dict], analysis_dir: Path) -> Problems:
    """The problems of a study: its own skipped cases, the analysis record's and the flow
    stage's (read from ``analysis_dir``), and missing analysis outputs."""
    outputs: list[str] = []
    record = _analysis_record(analysis_dir, outputs)
    if record.analysed_granules:   # granules were analysed: the tables must be there
        outputs += [f"{name} missing: rerun `ligwf analyse` (granule and GSD columns are empty)"
                    for name in ANALYSIS_OUTPUTS if not (analysis_dir / name).is_file()]
    absent = tuple((str(a.get("case_id", "?")), str(a.get("reason", "")))
                   for a in record.granules_absent)
    flow = _read_json(analysis_dir / layout.FLOW_PROFILES, "flow metrics missing", [])
    cases: dict[str, str] = {}
    for s in [*study_skipped, *record.items("skipped_cases"), *_items(flow, "skipped_cases")]:
        if isinstance(s, dict):
            cases.setdefault(str(s.get("case_id", "?")), str(s.get("reason", "")))
    frames = {(str(f.get("case_id")), str(f.get("step")), str(f.get("kind", "skipped")),
               str(f.get("reason"))) for f in record.items("skipped_frames")
              if isinstance(f, dict)}
    notes = flow.get("skipped_frames", {})
    for cid, reasons in (notes.items() if isinstance(notes, dict) else []):
        for why in reasons if isinstance(reasons, list) else []:
            if not any(why == r for c, _, _, r in frames if c == cid):
                frames.add((str(cid), "-", "flow", str(why)))
    return Problems(tuple(sorted(cases.items())),
                    tuple(sorted(frames, key=lambda f: (f[0], f[1].zfill(12), f[3]))),
                    tuple(outputs), absent)


def unlisted_cases(study) -> list[dict]:
    """Case folders (a scene record inside) below a study that its ``study.json`` does not
    list: no stage reads them, so they are named instead of dropped without a word (a
    record edited or merged by hand, a replica rendered into the folder by another
    workflow)."""
    if getattr(study, "single_case", False) or not Path(study.path).is_dir():
        return []
    listed = set(study.case_ids)
    return [{"case_id": p.name, "reason": f"a case folder not listed in {layout.STUDY_FILE}: "
             "not used (render the study again to include it)"}
            for p in sorted(Path(study.path).iterdir())
            if p.name not in listed and (p / layout.SCENE_FILE).is_file()]


def study_problems(study) -> Problems:
    """:func:`collect` for a :class:`~ligwf.study.study.Study` (its skipped cases, the
    case folders its record does not list, and its analysis folder)."""
    return collect([*study.usable_cases()[1], *unlisted_cases(study)], study.analysis_dir)
