"""Write the report folder of a study: tables, summary.md, index.html, figures, ParaView.

The study's report folder (:attr:`ligwf.study.study.Study.report_dir`):
``cases.csv`` and ``conditions.csv`` (the numbers), ``summary.md`` and ``index.html``
(the same sections, :mod:`ligwf.report.sections`, in the same order: the verdict first),
``figures/*.png`` (the verdict's forest plot, error vs run time, GSD overlay, velocity
profiles, one snapshot per case coloured by speed and one by granule id) and
``paraview/<case>.pvd`` (particles + turning drum, open in ParaView). Whatever was not
used -- skipped cases, missing or refused frames, missing analysis outputs -- is listed
with its reason (:mod:`ligwf.report.problems`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from ligwf import __version__
from ligwf.study.condition import REFERENCE_CG
from ligwf.analysis.records.flow import FlowRecord
from ligwf.analysis.records.gsd import LOWER_LIMIT
from ligwf.analysis.records.analysis_record import AnalysisRecord
from ligwf.analysis.records.provenance import StaleAnalysis, changed_dumps
from ligwf.errors import LigwfError
from ligwf.fsio import atomic_write_text
from ligwf.report import figures as figs
from ligwf.report.controls import controls_markdown
from ligwf.report.fields import fields_report
from ligwf.report.forest import forest, forest_rows
from ligwf.report.granule_figures import granule_figures
from ligwf.report.html import render_page
from ligwf.report.paraview import case_collection
from ligwf.report.problems import Problems, study_problems
from ligwf.report.snapshots import snapshot, speed_scale
from ligwf.report.sections import (Figure, Section, figure_section, ordered, render_markdown,
                                   split_markdown)
from ligwf.report.table_sections import (markdown_tables, noise_markdown, paraview_markdown,
                                         pooling_markdown, stability_markdown, steady_line)
from ligwf.report.extrapolation_report import extrapolation_section
from ligwf.report.scale_section import scale_section
from ligwf.report.spreading_section import spreading_section
from ligwf.report.rounds import rounds_sections
from ligwf.inference.verdict import Verdict
from ligwf.inference.decide import Decided, decide_study
from ligwf.report.verdict_text import verdict_section
from ligwf.study import layout
from ligwf.study.case import CaseFolder
from ligwf.study.layout import MESH_NAME
from ligwf.study.rounds import read_rounds
from ligwf.study.study import Study

NO_VERDICT = ("No acceptance budget was evaluated for this study, so there is no pass / fail "
              "verdict per CG level: read the errors against the CG1 noise floor in the "
              "conditions below.")

SNAPSHOTS = ("The last frame of each case seen along the drum axis (the arrow: the way the drum "
             "turns), coloured by speed on one scale shared by all cases, and by granule id "
             "(its newest labelled frame).")


@dataclass
class ReportFigures:
    """The figures of a report by the section that shows them, and the ParaView files."""

    verdict: Figure | None = None                           # the forest plot, first
    flow: list[Figure] = field(default_factory=list)        # error vs run time, profiles
    gsd: list[Figure] = field(default_factory=list)
    kinetics: list[Figure] = field(default_factory=list)    # kinetics, definition sensitivity
    snapshots: list[Figure] = field(default_factory=list)
    paraview: list[Path] = field(default_factory=list)


def write_report(study: Study, out: Path | None = None, snapshots: bool = True) -> Path:
    """Have the study decided (its tables and verdict:
    :func:`~ligwf.inference.decide.decide_study`, written first) and render the report
    folder around them; returns it. Reads only: the flow metrics, steady windows and granule tables come from ``ligwf
    analyse`` (refused when missing or stale, :func:`checked_analysis`)."""
    out = Path(out) if out else study.report_dir
    flow = checked_analysis(study)
    nothing_to_report(study, flow)
    (out / layout.FIGURES_DIR).mkdir(parents=True, exist_ok=True)
    decided = decide_study(study, flow, out)     # the numbers, written first
    cases, conditions, floors = decided.cases, decided.conditions, decided.floors
    verdict, extrapolated, ratio = decided.verdict, decided.extrapolated, decided.size_ratio
    problems = study_problems(study)
    spread_cases, spread_levels = decided.spreading_cases, decided.spreading_levels
    figures = report_figures(study, flow, cases, conditions, out, snapshots, verdict)
    sections = report_sections(study, flow, cases, conditions, floors, problems, figures,
                               verdict, [*extrapolation_section(extrapolated, ratio, cases),
                                         *scale_section(study, conditions),
                                         *spreading_section(spread_cases, spread_levels),
                                         *flow_field_sections(study, decided, out)])
    title = f"{study.name}: error against run time"
    preamble = (f"Study folder `{study.path}`; report by ligwf {__version__}. Errors are "
                "relative to the CG1 cases of the same sweep group; speedup is CG1 production "
                "core-seconds per simulated second of production per 1,000 particles of the "
                "original (CG1) system over the case's, so a CG level run on a shorter slice "
                "compares on the same footing (fill and settle costs in their own columns).")
    atomic_write_text(out / layout.SUMMARY_REPORT, render_markdown(title, preamble, sections))
    atomic_write_text(out / layout.HTML_REPORT, render_page(title, preamble, sections))
    return out


def report_sections(study: Study, flow: FlowRecord, cases: pd.DataFrame,
                    conditions: pd.DataFrame, floors: pd.DataFrame, problems: Problems,
                    figures: ReportFigures, verdict: Verdict | None = None,
                    fields: list[Section] = ()) -> list[Section]:
    """Every section of the report, in :data:`ligwf.report.sections.SECTION_ORDER`."""
    fig_dir = layout.FIGURES_DIR
    tables = (markdown_tables(cases, conditions, flow) if not cases.empty
              else "## Cases\n\nNo usable case.")
    parts = [*verdict_sections(verdict, figures.verdict),
             *rounds_sections(read_rounds(study.path), study.report_dir / fig_dir),
             *split_markdown(tables),
             *split_markdown(noise_markdown(conditions, floors, flow)),
             *split_markdown(pooling_markdown(study.analysis_dir, study.analysis.error_band)),
             Section("Steady window", "steady-window",
                     f"{steady_line(flow, cases)}. Flow metrics, GSDs and the noise floor "
                     "use the frames of this window only."),
             *split_markdown(controls_markdown(study.analysis_dir)),
             *([figure_section("GSD", "gsd", "Volume-weighted granule size distributions of "
                               "the steady window, each condition with its bootstrap band.",
                               figures.gsd, fig_dir)] if figures.gsd else []),
             *([figure_section("Granulation kinetics", "kinetics", "", figures.kinetics,
                               fig_dir)] if figures.kinetics else []),
             *fields,
             *split_markdown(problems.markdown()),
             figure_section("Figures", "figures", "", figures.flow, fig_dir),
             *([figure_section("Snapshots", "snapshots", SNAPSHOTS, figures.snapshots, fig_dir)]
               if figures.snapshots else []),
             *split_markdown(stability_markdown(study.usable_cases()[0])),
             *split_markdown(paraview_markdown(figures.paraview))]
    return ordered(parts)


def verdict_sections(verdict: Verdict | None, figure: Figure | None = None) -> list[Section]:
    """The verdict per sweep group (:mod:`ligwf.inference.verdict`), first in the report, its
    forest plot (``figure``) first in it."""
    if verdict is None:
        return [Section("Verdict", "verdict", NO_VERDICT)]
    where = f"{layout.FIGURES_DIR}/{figure.path.name}" if figure is not None else None
    return split_markdown(verdict_section(verdict, where))


def flow_field_sections(study: Study, decided: Decided, out: Path) -> list[Section]:
    """The flow-field maps, errors and null check (:mod:`ligwf.report.fields`: writes its
    figures into the report folder ``out``)."""
    return split_markdown(fields_report(study, decided.cases, decided.conditions,
                                        decided.field_null, decided.fields, out)[0])


def report_figures(study: Study, flow: FlowRecord, cases: pd.DataFrame,
                   conditions: pd.DataFrame, out: Path, snapshots: bool,
                   verdict: Verdict | None = None) -> ReportFigures:
    """Write every figure and ParaView collection of the report; what was written (the
    verdict's forest plot and the error-vs-run-time figure both from the verdict's rows)."""
    fig_dir, pv_dir = out / layout.FIGURES_DIR, out / layout.PARAVIEW_DIR
    found = ReportFigures()
    rows = forest_rows(verdict) if verdict is not None else None
    if verdict is not None and (path := forest(verdict, fig_dir / layout.FIGURE_VERDICT_FOREST)):
        found.verdict = Figure("Verdict", path)
    if not conditions.empty:
        found.flow.append(Figure("Error vs run time", figs.pareto(
            conditions, fig_dir / layout.FIGURE_ERROR_VS_RUNTIME, rows)))
        found.flow.append(Figure("Velocity profiles", figs.velocity_profiles(
            cases, flow.cases, fig_dir / layout.FIGURE_VELOCITY_PROFILES)))
    gsd_path = study.analysis_dir / layout.GSD_TABLE
    if gsd_path.is_file() and gsd_path.stat().st_size > 1:
        gsd = pd.read_csv(gsd_path)
        if not gsd.empty:
            found.gsd.append(Figure("GSD overlay", figs.gsd_overlay(
                gsd, fig_dir / layout.FIGURE_GSD_OVERLAY, study.analysis.gsd_volume,
                size_limits(study.analysis_dir))))
    starts = {c.case_id: c.production_start_step * c.scaled.numerics.dt
              for c in study.usable_cases()[0]}
    found.kinetics += [Figure(t, p) for t, p in granule_figures(study.analysis_dir, fig_dir,
                                                                starts)]
    by_id = {c.case_id: c for c in study.usable_cases()[0]}
    shots = []   # (case, step, dump) of each case's snapshot frame
    for case_id in cases.get("case_id", []):
        case: CaseFolder = by_id[case_id]
        record = flow.cases.get(case_id)
        pvd = case_collection(case, record.frames if record else (), study.analysis_dir, pv_dir)
        if pvd:
            found.paraview.append(pvd)
        if snapshots and record is not None and record.snapshot is not None:
            shots.append((case, *record.snapshot))
    found.snapshots = snapshot_figures(study, shots, fig_dir)
    return found


def size_limits(analysis_dir: Path) -> dict[str, float]:
    """condition -> located lower GSD size limit (m^3, nan: none located) of each CG-n
    condition in gsd_summary.csv (what the GSD errors below / above are measured at)."""
    path = analysis_dir / layout.GSD_SUMMARY_TABLE
    if not path.is_file() or path.stat().st_size <= 1:
        return {}
    summary = pd.read_csv(path)
    if LOWER_LIMIT not in summary:
        return {}
    compared = summary[summary["cg"] != REFERENCE_CG]    # CG1 has no limit against itself
    return dict(zip(compared["condition"].astype(str), compared[LOWER_LIMIT].astype(float)))


def snapshot_figures(study: Study, shots: list, fig_dir: Path) -> list[Figure]:
    """Speed snapshots of every case on one shared colour scale, and the granule snapshot
    of the newest labelled frame at or before it; titles give the time from the start of
    production (the drum starts turning), the arrow the drum's direction."""
    scale = speed_scale(case.path / dump for case, _, dump in shots) if shots else None
    out = []
    for case, step, dump in shots:
        axis, mesh, omega = case.scaled.drum.axis, case.path / MESH_NAME, case.scaled.drum.omega

        def title(at: int, what: str) -> str:
            t = (at - case.production_start_step) * case.scaled.numerics.dt
            return f"{case.case_id}, {t:.2f} s after production start: {what}"
        out.append(Figure(f"{case.case_id}: speed", snapshot(
            case.path / dump, mesh, axis, case.drum_angle(step), "speed",
            fig_dir / layout.snapshot_figure(case.case_id, "speed"), title(step, "speed"),
            omega, scale)))
        labelled = last_labelled(study.analysis_dir / case.case_id, step)
        if labelled is not None:
            at, path = labelled
            out.append(Figure(f"{case.case_id}: granules", snapshot(
                path, mesh, axis, case.drum_angle(at), "granule",
                fig_dir / layout.snapshot_figure(case.case_id, "granules"),
                title(at, "granule id"), omega)))
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
    record = AnalysisRecord.read(where)
    if record is None:
        raise MissingAnalysis(f"{where}: no readable analysis record "
                              f"({layout.ANALYSIS_RECORD}): run `ligwf analyse` first (or "
                              "`ligwf study`, which does)")
    if (why := record.stale(study, study.analysis)) is not None:
        raise StaleAnalysis(f"{where}: the analysis outputs are stale: {why}; run `ligwf "
                            "analyse` again (or `ligwf study`, which does)")
    if damaged := record.damaged():
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

