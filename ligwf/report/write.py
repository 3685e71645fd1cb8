"""Write the report folder of a study: tables, summary.md, index.html, figures, ParaView.

The study's report folder (:attr:`ligwf.study.study.Study.report_dir`):
``cases.csv`` and ``conditions.csv`` (the numbers), ``summary.md`` and ``index.html``
(the same tables with the figures), ``figures/*.png`` (error vs run time, GSD overlay,
velocity profiles, one snapshot per case coloured by speed and one by granule id) and
``paraview/<case>.pvd`` (particles + turning drum, open in ParaView). Whatever was not
used -- skipped cases, missing or refused frames, missing analysis outputs -- is listed
with its reason in ``summary.md`` and ``index.html`` (:mod:`ligwf.report.problems`).
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path

import pandas as pd

from ligwf import __version__
from ligwf.analysis.records.conditions import REFERENCE_CG
from ligwf.analysis.records.flow import FlowRecord
from ligwf.analysis.records.metrics import CASE_TABLE, CONDITION_TABLE, GRANULE_METRICS
from ligwf.analysis.records.provenance import (StaleAnalysis, changed_dumps, damaged_outputs,
                                               provenance_mismatch)
from ligwf.study.layout import MESH_NAME
from ligwf.errors import LigwfError
from ligwf.fsio import atomic_write_text
from ligwf.report import figures as figs
from ligwf.report.granule_figures import granule_figures
from ligwf.report.paraview import case_collection
from ligwf.report.problems import study_problems
from ligwf.report.controls import controls_html, controls_markdown
from ligwf.report.tables import build_tables
from ligwf.study import layout
from ligwf.study.case import CaseFolder
from ligwf.study.study import Study

#: the run columns of the case table in summary.md (the metrics follow, from the record)
RUN_COLUMNS = [("case_id", "case"), ("cg", "CG"), ("rule", "rule"), ("replica", "rep"),
               ("particles", "particles"), ("dt", "dt [s]"), ("steps", "steps"),
               ("wall_seconds", "wall [s]"), ("core_seconds", "core-s"),
               ("fill_core_seconds", "fill core-s"), ("settle_core_seconds", "settle core-s"),
               ("production_core_rate_k", "prod. core-s / sim. s / 1k orig. particles"),
               ("speedup_core", "speedup (core-s)"), ("steady_fraction", "steady from")]
RUN_METRICS = [("production_core_rate_k", "prod. core-s / sim. s / 1k orig. particles"),
               ("speedup_core", "speedup")]
GSD_COLUMNS = [("gsd_lower_limit", "GSD lower limit [m^3]"),
               ("gsd_error_below_lower", "GSD err below lower limit"),
               ("gsd_error_above_lower", "GSD err above lower limit"),
               ("gsd_error_all", "GSD err all bins")]


def shown(flow: FlowRecord, table: str) -> list[tuple[str, str]]:
    """(column, header) of the metrics a markdown table shows: the flow record's and the
    granule metrics marked for it, in order."""
    return [(m.name, m.header(table)) for m in (*flow.metrics, *GRANULE_METRICS)
            if table in m.tables]


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
    """Value [95 % interval], "(no replica interval)" for one replica, and for an error
    its mark against the CG1 noise floor."""
    m, lo, hi = row[col], row.get(f"{col}_lo"), row.get(f"{col}_hi")
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
            lines.append(f"| {r['group']} | {r['metric']} | {_fmt(r['cg1_value'])} | "
                         f"{_fmt(r['cg1_scatter'])} | {r['source']} |")
        lines.append("")
    errors = [m for m in flow.error_metrics if f"{m.name}_floor" in conditions]
    if not conditions.empty and errors:
        lines += ["| CG | rule | " + " ".join(f"{m.header(CONDITION_TABLE)} | floor | |"
                                              for m in errors),
                  "|---|---|" + "---|---|---|" * len(errors)]
        for _, r in conditions[conditions["cg"] != REFERENCE_CG].iterrows():
            cells = [f"{r['cg']:g}", r["rule"]]
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
    for _, r in cases.sort_values(["group", "cg", "rule", "replica"]).iterrows():
        lines.append("| " + " | ".join(_fmt(r[c]) for c, _ in columns) + " |")
    lines += ["", "## Conditions (value [95 % interval])", "",
              "Intervals: block bootstrap over frames (block = 2 x the measured "
              "autocorrelation time) and replicas, never narrower than the within-run error, "
              "bounded to the quantity's range (ligwf.analysis.records.intervals); run costs: t on the "
              "logarithm over replicas; one replica: no replica interval. GSD bands come from "
              "the GSD stage. Errors are marked `within` / `beyond` / `undecided` against the "
              "CG1 noise floor by their interval (section CG1 noise floor).", ""]
    head = "| CG | rule | replicas | particles | core-s | " + " | ".join(t for _, t in metrics) + " |"
    lines += [head, "|" + "---|" * (5 + len(metrics))]
    for _, r in conditions.iterrows():
        cells = [f"{r['cg']:g}", r["rule"], str(r["replicas"]), str(r["particles"]),
                 _ci(r, "core_seconds")] + [_ci(r, c) for c, _ in metrics]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write_report(study: Study, out: Path | None = None, snapshots: bool = True) -> Path:
    """Build the tables from the analysis outputs and write the report folder; returns it.
    Reads only: the flow metrics, steady windows and granule tables come from ``ligwf
    analyse`` (refused when missing or stale, :func:`checked_analysis`)."""
    out = Path(out) if out else study.report_dir
    flow = checked_analysis(study)
    nothing_to_report(study, flow)
    fig_dir, pv_dir = out / layout.FIGURES_DIR, out / layout.PARAVIEW_DIR
    fig_dir.mkdir(parents=True, exist_ok=True)
    cases, conditions, _, floors = build_tables(study, flow)
    problems = study_problems(study)
    atomic_write_text(out / layout.CASES_REPORT, cases.to_csv(index=False))
    atomic_write_text(out / layout.CONDITIONS_REPORT, conditions.to_csv(index=False))
    atomic_write_text(out / layout.NOISE_FLOOR_REPORT, floors.to_csv(index=False))

    figures: list[tuple[str, Path]] = []
    if not conditions.empty:
        figures.append(("Error vs run time", figs.pareto(
            conditions, fig_dir / layout.FIGURE_ERROR_VS_RUNTIME)))
        figures.append(("Velocity profiles", figs.velocity_profiles(
            cases, flow.cases, fig_dir / layout.FIGURE_VELOCITY_PROFILES)))
    gsd_path = study.analysis_dir / layout.GSD_TABLE
    if gsd_path.is_file() and gsd_path.stat().st_size > 1:
        gsd = pd.read_csv(gsd_path)
        if not gsd.empty:
            figures.append(("GSD overlay", figs.gsd_overlay(
                gsd, fig_dir / layout.FIGURE_GSD_OVERLAY, study.analysis.gsd_volume)))
    figures += granule_figures(study.analysis_dir, fig_dir)
    pvds = []
    by_id = {c.case_id: c for c in study.usable_cases()[0]}
    for case_id in cases.get("case_id", []):
        case: CaseFolder = by_id[case_id]
        record = flow.cases.get(case_id)
        pvd = case_collection(case, record.frames if record else (), study.analysis_dir, pv_dir)
        if pvd:
            pvds.append(pvd)
        last = record.snapshot if snapshots and record is not None else None
        if last is not None:
            step, dump = last
            axis, mesh = case.scaled.axis, case.path / MESH_NAME
            figures.append((f"{case_id}: speed", figs.snapshot(
                case.path / dump, mesh, axis, case.drum_angle(step), "speed",
                fig_dir / layout.snapshot_figure(case_id, "speed"),
                f"{case_id} step {step}: speed [m/s]")))
            labelled = last_labelled(study.analysis_dir / case_id, step)
            if labelled is not None:
                step, path = labelled
                figures.append((f"{case_id}: granules", figs.snapshot(
                    path, mesh, axis, case.drum_angle(step), "granule",
                    fig_dir / layout.snapshot_figure(case_id, "granules"),
                    f"{case_id} step {step}: granule id")))

    name = study.name
    md = "\n".join([
        f"# {name}: error against run time", "",
        f"Study folder `{study.path}`; report by ligwf {__version__}. Errors are relative to the "
        "CG1 cases of the same sweep group; speedup is CG1 production core-seconds per simulated "
        "second of production per 1,000 particles of the original (CG1) system over the case's, "
        "so a CG level run on a shorter slice compares on the same footing (fill and settle "
        "costs in their own columns).", "",
        f"Steady window: {steady_line(flow, cases)}.", "",
        markdown_tables(cases, conditions, flow) if not cases.empty else "No usable case.", "",
        *noise_markdown(conditions, floors, flow),
        *controls_markdown(study.analysis_dir),
        *pooling_markdown(study.analysis_dir, study.analysis.error_band),
        *problems.markdown(),
        "## Figures", "",
        *[f"![{t}]({layout.FIGURES_DIR}/{p.name})" for t, p in figures], "",
        "## ParaView", "",
        *[f"- `{layout.PARAVIEW_DIR}/{p.name}`" for p in pvds], ""])
    atomic_write_text(out / layout.SUMMARY_REPORT, md)
    atomic_write_text(out / layout.HTML_REPORT, _html(name, cases, conditions, figures, problems,
                                                      controls_html(study.analysis_dir), flow))
    return out


def last_labelled(case_out: Path, up_to: int) -> tuple[int, Path] | None:
    """(step, file) of the newest granule-labelled frame at or before ``up_to`` (the last
    frames of a ``granules: held`` run have no granules: their hold window is open)."""
    found = []
    for p in case_out.glob(layout.GRANULE_FRAME_GLOB) if case_out.is_dir() else []:
        step = layout.granule_frame_step(p.name)
        if step is not None and step <= up_to:
            found.append((step, p))
    return max(found) if found else None


class NothingToReport(LigwfError):
    """Usable cases, but not one frame of any of them could be used."""


class MissingAnalysis(LigwfError):
    """The study has no (complete) analysis outputs to report."""


def checked_analysis(study: Study) -> FlowRecord:
    """The flow record of the study's analysis once the analysis record is there and its
    provenance (scene hashes, dump records, settings) and tables (sizes, SHA-256) still
    match, and the dumps the flow stage read are still the run's. MissingAnalysis when
    there is no readable analysis (or no flow record in it); StaleAnalysis (one line
    naming what changed) when the outputs are of another study, of an earlier run, or were
    edited, or the dumps changed since."""
    where = study.analysis_dir
    try:
        record = json.loads((where / layout.ANALYSIS_RECORD).read_text())
    except (OSError, ValueError):
        record = None
    if not isinstance(record, dict):
        raise MissingAnalysis(f"{where}: no readable analysis record "
                              f"({layout.ANALYSIS_RECORD}): run `ligwf analyse` first (or "
                              "`ligwf study`, which does)")
    if (why := provenance_mismatch(study, study.analysis, record)) is not None:
        raise StaleAnalysis(f"{where}: the analysis outputs are stale: {why}; run `ligwf "
                            "analyse` again (or `ligwf study`, which does)")
    if damaged := damaged_outputs(where, record):
        raise StaleAnalysis(f"{where}/{damaged[0]}" + (f" (and {len(damaged) - 1} more)"
                            if len(damaged) > 1 else "") + "; run `ligwf analyse` again")
    try:
        flow = FlowRecord.read(where / layout.FLOW_PROFILES)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise MissingAnalysis(f"{where}/{layout.FLOW_PROFILES}: no flow record "
                              f"({type(exc).__name__}: {exc}): run `ligwf analyse` again") from exc
    if (why := changed_dumps(study, flow)) is not None:
        raise StaleAnalysis(f"nothing to report in {study.path}: {why} (the dumps changed since "
                            "the analysis); run `ligwf analyse` again")
    return flow


def nothing_to_report(study: Study, flow: FlowRecord) -> None:
    """NothingToReport when the study has usable cases but the flow stage could use no
    frame of any (every dump refused: e.g. ``post/`` folders swapped between cases)."""
    usable = study.usable_cases()[0]
    if not usable or flow.measured():
        return
    try:
        cid, reasons = next(iter(flow.skipped_frames.items()))
        first = f"{cid}: {reasons[0]}"
    except (StopIteration, IndexError):
        first = "no reason recorded"
    raise NothingToReport(f"nothing to report in {study.path}: no frame of the {len(usable)} "
                          f"usable case(s) could be used; first: {first}")


def steady_line(flow: FlowRecord, cases: pd.DataFrame) -> str:
    """The steady-window rule of the study and the fractions it gave."""
    setting = flow.steady_after
    fr = cases.get("steady_fraction", pd.Series(dtype=float)).dropna()
    if flow.steady_auto:
        span = (f"{100 * fr.min():.0f}-{100 * fr.max():.0f} %" if len(fr) else "–")
        return (f"`steady_after: auto` (the first frame after which running means of the flow "
                f"angle and kinetic energy stay within their steady scatter, "
                f"ligwf.analysis.flow.steady): {span} of production left out")
    return f"`steady_after: {setting}`: the first {100 * float(setting):.0f} % of production left out"


def _html(name, cases, conditions, figures, problems, controls: str, flow: FlowRecord) -> str:
    def table(df: pd.DataFrame) -> str:
        if df.empty:
            return "<p>none</p>"
        return df.to_html(index=False, float_format=lambda v: f"{v:.3g}", na_rep="–", border=0)
    imgs = "\n".join(f'<figure><img src="{layout.FIGURES_DIR}/{p.name}" alt="{html.escape(t)}">'
                     f"<figcaption>{html.escape(t)}</figcaption></figure>" for t, p in figures)
    cols = [c for c, _ in case_columns(flow)]
    return f"""<!doctype html><html><head><meta charset="utf-8"><title>{html.escape(name)}</title>
<style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse;font-size:12px}}
td,th{{padding:2px 6px;border-bottom:1px solid #ddd}}img{{max-width:720px}}</style></head><body>
<h1>{html.escape(name)}: error against run time</h1>
<h2>Cases</h2>{table(cases[cols] if not cases.empty else cases)}
<h2>Conditions (mean, 95 % CI bounds over replicas)</h2>{table(conditions)}
{controls}
{problems.html()}
<h2>Figures</h2>{imgs}</body></html>
"""
