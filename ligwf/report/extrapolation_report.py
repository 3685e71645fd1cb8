"""The extrapolated CG1 reference in a study's report: its inputs read from the case
folders (the drum's d / D, the planner's CG1 cost per level), ``extrapolation.csv`` and
the report section that shows it (the extrapolated CG1 beside the measured one where CG1
ran, the form's checks, the two rules' disagreement)."""

from __future__ import annotations

import json
import math

import pandas as pd

from ligwf.inference.reference import planned_cg1_speedup, size_ratio
from ligwf.report.sections import Section
from ligwf.study import layout
from ligwf.study.study import Study


def extrapolation_inputs(study: Study) -> tuple[float, dict]:
    """(d / D of the study's drum, (group, cg, rule) -> the planner's CG1 cost over the
    level's): read from the usable cases' scene records (nan / empty without one)."""
    ratio, speedups = math.nan, {}
    for case in study.usable_cases()[0]:
        try:
            scene = json.loads((case.path / layout.SCENE_FILE).read_text())["scene"]
        except (OSError, ValueError, KeyError):
            continue
        if not math.isfinite(ratio):
            ratio = size_ratio(scene)
        key = (case.group, float(case.cg), str(case.rule))
        if case.cg > 1.0 and key not in speedups:
            speedups[key] = planned_cg1_speedup(scene, case.cg, case.rule)
    return ratio, speedups


def _num(v, fmt: str = ".3g") -> str:
    try:
        v = float(v)
    except (TypeError, ValueError):
        return "–"
    return format(v, fmt) if math.isfinite(v) else "–"


def extrapolation_section(table: pd.DataFrame, ratio: float) -> list[Section]:
    """The report section of ``extrapolation.csv`` (none when no rule has two CG levels)."""
    if table.empty:
        return []
    lines = [f"The CG1 value of each signed criterion extrapolated from the CG-n levels of "
             f"each rule: a line in n through the level means, its 95 % interval carrying the "
             f"levels' run-to-run noise and a model term for the line's curvature (drum d / D "
             f"= {_num(ratio)}; ligwf.inference.extrapolation). Where CG1 ran, the measured "
             f"mean is beside it. A rule whose levels fail the lack-of-fit check does not "
             f"extrapolate; two levels cannot check the form.", "",
             "| group | rule | criterion column | levels (runs) | extrapolated CG1 [95 %] | "
             "model term | form | lack of fit p | observed order | measured CG1 | inside |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for _, r in table.iterrows():
        levels = (f"{r['levels']} ({r['replicas']})" if isinstance(r["levels"], str)
                  else "–")
        inside = {True: "yes", False: "**no**"}.get(r["cg1_inside"], "–") if not pd.isna(
            r["cg1_inside"]) else "–"
        lines.append(
            f"| {r['group']} | {r['rule']} | {r['column']} | {levels} | "
            f"{_num(r['extrapolated'])} [{_num(r['lo'])}, {_num(r['hi'])}] | "
            f"{_num(r['model_term'])} | {r['form']} | {_num(r['lack_of_fit_p'], '.2g')} | "
            f"{_num(r['observed_order'], '.2g')} | {_num(r['cg1_measured'])} | {inside} |")
    return [Section("Extrapolated CG1", "extrapolated-cg1", "\n".join(lines))]
