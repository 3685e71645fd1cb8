"""The extrapolated CG1 reference in a study's report: its inputs read from the case
folders (the drum's d / D, the planner's CG1 cost per level), ``extrapolation.csv`` and
the report section that shows it (the extrapolated CG1 beside the measured one where CG1
ran, the form's checks, the two rules' disagreement)."""

from __future__ import annotations

import json
import math

import pandas as pd

from ligwf.inference.reference import ANGLE_COLUMN, planned_cg1_speedup, size_ratio
from ligwf.inference.size_relation import expected_excess
from ligwf.report.sections import Section
from ligwf.study import layout
from ligwf.study.condition import Condition
from ligwf.study.study import Study


def extrapolation_inputs(study: Study) -> tuple[float, dict[Condition, float]]:
    """(d / D of the study's drum, condition -> the planner's CG1 cost over the level's):
    read from the usable cases' scene records (nan / empty without one)."""
    ratio, speedups = math.nan, {}
    for case in study.usable_cases()[0]:
        try:
            scene = json.loads((case.path / layout.SCENE_FILE).read_text())["scene"]
        except (OSError, ValueError, KeyError):
            continue
        if not math.isfinite(ratio):
            ratio = size_ratio(scene)
        if case.cg > 1.0 and case.condition not in speedups:
            speedups[case.condition] = planned_cg1_speedup(scene, case.cg, case.rule)
    return ratio, speedups


def _num(v, fmt: str = ".3g") -> str:
    try:
        v = float(v)
    except (TypeError, ValueError):
        return "–"
    return format(v, fmt) if math.isfinite(v) else "–"


def expected_lines(cases: pd.DataFrame, table: pd.DataFrame, ratio: float) -> list[str]:
    """Per Weber level: the angle excess the size relation expected before the run, beside
    the one measured (against the group's CG1 runs, else against the extrapolated CG1)."""
    if cases.empty or not math.isfinite(ratio) or ANGLE_COLUMN not in cases:
        return []
    lines = []
    for group, in_group in cases.groupby(cases["group"].astype(str), sort=True):
        angle = pd.to_numeric(in_group[ANGLE_COLUMN], errors="coerce")
        ref = angle[in_group["cg"] == 1.0].mean()
        source = "its CG1 runs"
        if not math.isfinite(ref):
            row = table[(table["group"] == group) & (table["rule"] == "weber")
                        & (table["column"] == ANGLE_COLUMN)]
            ref = float(row["extrapolated"].iloc[0]) if len(row) else math.nan
            source = "the extrapolated CG1"
        label = (str(in_group["group_label"].iloc[0]) if "group_label" in in_group
                 else group)
        weber = in_group["rule"].astype(str) == "weber"
        for cg in sorted(set(in_group.loc[weber & (in_group["cg"] > 1.0), "cg"])):
            e = expected_excess(float(cg), ratio)
            measured = angle[weber & (in_group["cg"] == cg)].mean() - ref
            lines.append(f"- {label}, CG{cg:g}: expected {e.value:.2g} deg [{e.lo:.2g}, "
                         f"{e.hi:.2g}] steeper (D / (n d) = {e.d_over_nd:.3g}, "
                         f"{'inside' if e.inside_fit else 'outside'} the fitted range); "
                         f"measured {_num(measured)} deg against {source}")
    return (["", "The size relation's expectation for each Weber level (what `ligwf check` "
             "printed before the runs) beside what was measured:", ""] + lines) if lines else []


def extrapolation_section(table: pd.DataFrame, ratio: float,
                          cases: pd.DataFrame | None = None) -> list[Section]:
    """The report section of ``extrapolation.csv`` and the size relation's expectations
    (none when no rule has two CG levels and no Weber level ran)."""
    expected = expected_lines(cases if cases is not None else pd.DataFrame(), table, ratio)
    if table.empty and not expected:
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
    if table.empty:
        lines = lines[:1]
    return [Section("Extrapolated CG1", "extrapolated-cg1",
                    "\n".join(lines + rules_disagree(table) + expected))]


def rules_disagree(table: pd.DataFrame) -> list[str]:
    """A sentence for each criterion whose two rules' extrapolated CG1 values differ (the
    ``weber - bond`` rows whose interval excludes 0): both rules target one CG1, so at
    least one of them does not extrapolate there, even where each line passes its check."""
    if table.empty or "rule" not in table:
        return []
    out = []
    for _, r in table[table["rule"] == "weber - bond"].iterrows():
        if pd.isna(r["lo"]) or pd.isna(r["hi"]) or r["lo"] <= 0 <= r["hi"]:
            continue
        out.append(f"- {r['column']} ({r['group']}): Weber's and Bond's extrapolated CG1 "
                   f"values differ by {_num(r['extrapolated'])} [{_num(r['lo'])}, "
                   f"{_num(r['hi'])}] (weber - bond): both rules target the same CG1, so at "
                   "least one of them does not extrapolate here, whatever its line's check "
                   "says")
    return [""] + out if out else []
