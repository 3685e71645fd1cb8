"""The table sections of the report: cases, conditions, CG1 noise floor, GSD size limit,
steady window, stability (markdown; the page renders the same text).

Reads only tables the report stage built (:mod:`ligwf.inference.study_tables`) or the analysis wrote;
numbers are shown as value [95 % interval] with their mark against the CG1 noise floor.
"""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from ligwf.study.condition import REFERENCE_CG
from ligwf.analysis.records.flow import FlowRecord
from ligwf.analysis.records.metrics import CASE_TABLE, CONDITION_TABLE, GRANULE_METRICS
from ligwf.report.dictionary import gsd_note, header, shown_value
from ligwf.study import layout
from ligwf.study.case import group_label

#: the run columns of the case table in summary.md (the metrics follow, from the record);
#: headers (label [unit]) from the data dictionary (ligwf.report.dictionary)
RUN_COLUMNS = [(c, header(c)) for c in (
    "case_id", "group_label", "cg", "rule", "replica", "particles", "dt", "steps",
    "wall_seconds", "core_seconds", "fill_core_seconds", "settle_core_seconds",
    "production_core_rate_k", "speedup_core", "steady_fraction")]
RUN_METRICS = [(c, header(c)) for c in ("production_core_rate_k", "speedup_core")]
#: the GSD columns: the limit (as a diameter) and the errors, each naming its limit
GSD_COLUMNS = [(c, header(c)) for c in ("gsd_lower_limit_diameter", "gsd_error_below_lower",
                                        "gsd_error_above_lower", "gsd_error_all")]


def shown(flow: FlowRecord, table: str) -> list[tuple[str, str]]:
    """(column, header) of the metrics a markdown table shows: the flow record's and the
    granule metrics marked for it, in order (headers from the data dictionary, a plug-in
    metric's own label otherwise)."""
    return [(m.name, header(m.name, fallback=m.header(table)))
            for m in (*flow.metrics, *GRANULE_METRICS) if table in m.tables]


def case_columns(flow: FlowRecord) -> list[tuple[str, str]]:
    return RUN_COLUMNS + shown(flow, CASE_TABLE) + GSD_COLUMNS


def condition_metrics(flow: FlowRecord) -> list[tuple[str, str]]:
    return RUN_METRICS + shown(flow, CONDITION_TABLE) + GSD_COLUMNS


def _fmt(v) -> str:
    if isinstance(v, str):
        return v
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def _ci(row, col) -> str:
    """Value [95 % interval] in the shown unit, "(no replica interval)" for one replica,
    for an error its mark against the CG1 noise floor, for a GSD column without a lower
    limit what that means (:func:`ligwf.report.dictionary.gsd_note`)."""
    text = _interval(row, col)
    note = gsd_note(row, col)
    return text if note is None else (note if text == "–" else f"{text} {note}")


def _cell(row, col) -> str:
    """A case-table cell: the value in the shown unit (GSD: with its no-limit note)."""
    text = _fmt(shown_value(col, row[col]))
    note = gsd_note(row, col)
    return text if note is None else (note if text == "–" else f"{text} {note}")


def _interval(row, col) -> str:
    m, lo, hi = (shown_value(col, row.get(c)) for c in (col, f"{col}_lo", f"{col}_hi"))
    mark = row.get(f"{col}_vs_floor")
    if mark == "reference":   # CG1's error against itself
        return "reference"
    tail = f" {mark}" if isinstance(mark, str) and mark not in ("–", "reference") else ""
    if tail.startswith(" undecided"):   # what would decide it: in the noise-floor section
        tail = " undecided"
    if not (isinstance(m, float) and math.isfinite(m)):
        return _fmt(m)
    if isinstance(lo, float) and math.isfinite(lo):
        return f"{_fmt(m)} [{_fmt(lo)}, {_fmt(hi)}]{tail}"
    if row.get("replicas", 0) < 2 and not col.startswith("gsd_"):
        return f"{_fmt(m)} (no replica interval){tail}"
    return _fmt(m) + tail


def noise_markdown(conditions: pd.DataFrame, floors: pd.DataFrame, flow: FlowRecord
                   ) -> list[str]:
    """The CG1 noise floor: per metric the CG1-vs-CG1 scatter, per error the floor."""
    lines = ["## CG1 noise floor", "",
             "How far one CG1 run is from another (other seed). An error is `beyond` the "
             "floor (a CG effect) when its whole 95 % interval lies above it, `within` (not "
             "distinguishable from seed noise) when its whole interval lies at or below it, "
             "and `undecided` otherwise, with the CG1 replicas that would decide it. A floor "
             "estimated from one CG1 run's own scatter is indicative.", ""]
    if not floors.empty:
        lines += ["| group | metric | CG1 value | CG1 scatter | from |", "|---|---|---|---|---|"]
        for _, r in floors.iterrows():
            value, scatter = (shown_value(r["metric"], r[c])
                              for c in ("cg1_value", "cg1_scatter"))
            lines.append(f"| {group_label(r['group'])} | {header(r['metric'])} | "
                         f"{_fmt(value)} | {_fmt(scatter)} | {r['source']} |")
        lines.append("")
    errors = [m for m in flow.error_metrics if f"{m.name}_floor" in conditions]
    if not conditions.empty and errors:
        lines += ["| group | CG | rule | " + " ".join(
                      f"{header(m.name, fallback=m.header(CONDITION_TABLE))} | floor | |"
                      for m in errors), "|---|---|---|" + "---|---|---|" * len(errors)]
        for _, r in conditions[conditions["cg"] != REFERENCE_CG].iterrows():
            cells = [group_label(r["group"]), f"{r['cg']:g}", r["rule"]]
            for col in (m.name for m in errors):
                cells += [_fmt(r[col]), f"{_fmt(r[f'{col}_floor'])} ({r[f'{col}_floor_source']})",
                          str(r[f"{col}_vs_floor"])]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return lines


def pooling_markdown(analysis_dir: Path, band: float) -> list[str]:
    """The GSD size limit against replica pooling (ligwf.analysis.gsd.pooling): per
    condition and pool size K, the mean [min, max] over disjoint pools of the source
    study's upper limit and the errors below / above it; the CG1 noise floor first."""
    path = analysis_dir / layout.GSD_POOLING_SUMMARY_TABLE
    if not path.is_file() or path.stat().st_size <= 1:
        return []
    summary = pd.read_csv(path)
    if summary.empty:
        return []
    lines = ["## GSD size limit and replica pooling", "",
             f"Upper limit: the largest granule volume up to which every bin holding >= 1 % "
             f"of the CG1 granule volume is within {100 * band:g} % of CG1 (the source "
             f"study's limit; nan: the smallest bin is already outside). Errors: relative L1 "
             f"of the volume-weighted GSD below / above it. K replicas pooled, mean [min, max] "
             f"over disjoint pools; `noise floor`: one CG1 replica against the others.", "",
             "| condition | rule | K | pools | upper limit [m^3] | error below upper limit "
             "| error above upper limit | lower limit [m^3] |", "|---|---|---|---|---|---|---|---|"]

    def cell(r, v):
        m, lo, hi = r[f"{v}_mean"], r[f"{v}_min"], r[f"{v}_max"]
        text = _fmt(m) if r["pools"] < 2 else f"{_fmt(m)} [{_fmt(lo)}, {_fmt(hi)}]"
        nan = r[f"{v}_nan_pools"]
        return text + (f" ({int(nan)} nan)" if nan else "")

    order = summary.assign(first=summary["rule"] != "noise floor").sort_values(
        ["first", "condition", "k"])
    for _, r in order.iterrows():
        lines.append(f"| {r['condition']} | {r['rule']} | {int(r['k'])} | {int(r['pools'])} | "
                     + " | ".join(cell(r, v) for v in ("upper_limit", "error_below_upper",
                                                       "error_above_upper", "lower_limit"))
                     + " |")
    return lines + [""]


def markdown_tables(cases: pd.DataFrame, conditions: pd.DataFrame, flow: FlowRecord) -> str:
    columns, metrics = case_columns(flow), condition_metrics(flow)
    head = "| " + " | ".join(t for _, t in columns) + " |"
    sep = "|" + "---|" * len(columns)
    lines = ["## Cases", "", head, sep]
    cases = cases.assign(group_label=cases["group"].map(group_label))   # (readable group)
    for _, r in cases.sort_values(["group", "cg", "rule", "replica"]).iterrows():
        lines.append("| " + " | ".join(_cell(r, c) for c, _ in columns) + " |")
    lines += ["", "## Conditions (value [95 % interval])", "",
              "Intervals: block bootstrap over frames (block = 2 x the measured "
              "autocorrelation time) and replicas, never narrower than the within-run error, "
              "bounded to the quantity's range (ligwf.analysis.records.intervals); run costs: t on the "
              "logarithm over replicas; one replica: no replica interval. GSD bands come from "
              "the GSD stage; GSD errors are against the lower size limit (shown as its "
              "equivalent diameter: CG-n within the error band of CG1 from it on) or over "
              "all bins; with no limit located every bin is below it. Errors are marked "
              "`within` / `beyond` / `undecided` against the CG1 noise floor by their "
              "interval (section CG1 noise floor).", ""]
    head = (f"| group | CG | rule | replicas | particles | {header('core_seconds')} | "
            + " | ".join(t for _, t in metrics) + " |")
    lines += [head, "|" + "---|" * (6 + len(metrics))]
    for _, r in conditions.iterrows():
        cells = [group_label(r["group"]), f"{r['cg']:g}", r["rule"], str(r["replicas"]),
                 str(r["particles"]),
                 _ci(r, "core_seconds")] + [_ci(r, c) for c, _ in metrics]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def steady_line(flow: FlowRecord, cases: pd.DataFrame) -> str:
    """The steady-window rule of the study and the fractions it gave."""
    setting = flow.steady_after
    fr = cases.get("steady_fraction", pd.Series(dtype=float)).dropna()
    if flow.steady_auto:
        span = (f"{100 * fr.min():.0f}-{100 * fr.max():.0f} %" if len(fr) else "–")
        return (f"`steady_after: auto` (the measured spin-up of the flow angle and kinetic "
                f"energy, ligwf.analysis.flow.steady): {span} of production left out")
    return f"`steady_after: {setting}`: the first {100 * float(setting):.0f} % of production left out"


def stability_markdown(cases) -> list[str]:
    """The runtime stability of every case the report uses (``cases``: CaseFolder list):
    its status, attempts, particles after settling and at the end (a lost particle is an
    unstable contact or a leaking drum) and the health issues the runner found."""
    lines = ["## Stability", "",
             "The runner's verdict on each case used here (ligwf.engine.health): particles "
             "lost after settling or a health issue would make its numbers suspect.", "",
             "| case | status | attempts | particles after settle | particles at end "
             "| runtime issues |", "|---|---|---|---|---|---|"]
    for case in cases:
        m = case.manifest()
        if m is None:
            continue
        issues = "; ".join(f"{i.get('kind')} at step {i.get('step')}: {i.get('message')}"
                           for i in m.issues) or "none"
        lines.append(f"| {case.case_id} | {m.status} | {len(m.attempts)} | "
                     f"{_fmt(m.atoms_after_settle)} | {_fmt(m.atoms_end)} | "
                     f"{issues.replace('|', '/')} |")
    return lines + [""]


def paraview_markdown(pvds: list[Path]) -> list[str]:
    """Where the ParaView collections are (particles + turning drum, one per case)."""
    lines = ["## ParaView", "",
             "One collection per case: the particle series (granule ids where analysed) and "
             "the drum mesh turned to its angle at each frame; open the `.pvd` in ParaView "
             "and press play.", ""]
    return lines + ([f"- `{layout.PARAVIEW_DIR}/{p.name}`" for p in pvds] or ["none"]) + [""]
