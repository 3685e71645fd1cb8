"""The study-level plots of the API: the report's own figure functions on a study's tables.

Each function draws into the matplotlib ``Axes`` it is given and returns it; without one
it makes a figure of its own (through pyplot, so a notebook shows it and a script can
``plt.savefig``; pyplot picks a non-interactive backend where there is no display). The
drawing is :mod:`ligwf.report.figures` / :mod:`ligwf.report.granule_figures`, the same
functions the report's PNGs come from, so a notebook plot and the report's figure agree.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from matplotlib.axes import Axes

from ligwf.analysis.records.flow import FlowRecord
from ligwf.errors import LigwfError
from ligwf.report import figures as figs
from ligwf.report import granule_figures as gfigs
from ligwf.report.write import size_limits

#: size of a figure the API makes itself (inches)
FIGSIZE = (7.5, 5.2)


def axes(ax: Axes | None) -> Axes:
    """``ax``, or the Axes of a new pyplot figure."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    return plt.figure(figsize=FIGSIZE).subplots()


def metric_title(flow: FlowRecord | None, metric: str) -> str:
    """The title of an error plot: the metric's label from the flow record, else its name."""
    spec = next((m for m in (flow.metrics if flow else ()) if m.name == metric), None)
    return f"{spec.label if spec else metric} vs CG1"


def error_vs_cost(ax: Axes | None, conditions: pd.DataFrame, metric: str,
                  flow: FlowRecord | None = None) -> Axes:
    """One error of every CG-n condition against its production cost, with its 95 %
    interval and the CG1 noise floor (:func:`ligwf.report.figures.error_ax`)."""
    return figs.error_ax(axes(ax), conditions, metric, metric_title(flow, metric))


def run_cost(ax: Axes | None, conditions: pd.DataFrame) -> Axes:
    """Core-seconds per phase of every condition (:func:`ligwf.report.figures.run_cost_ax`)."""
    return figs.run_cost_ax(axes(ax), conditions)


def gsd(ax: Axes | None, table: pd.DataFrame, volume: str, analysis_dir: Path) -> Axes:
    """The steady-window GSD of every condition with the size limits the analysis located
    (:func:`ligwf.report.figures.gsd_ax`); ``volume``: the study's ``gsd_volume``."""
    return figs.gsd_ax(axes(ax), table, volume, size_limits(analysis_dir))


def profiles(ax: Axes | None, cases: pd.DataFrame, flow: FlowRecord) -> Axes:
    """Velocity profiles of every case (:func:`ligwf.report.figures.velocity_profiles_ax`)."""
    return figs.velocity_profiles_ax(axes(ax), cases, flow.cases)


def kinetics(ax: Axes | None, summary: pd.DataFrame, per_case: pd.DataFrame, quantity: str,
             starts: dict[str, float]) -> Axes:
    """One granule-kinetics quantity against the time from production start
    (:func:`ligwf.report.granule_figures.kinetics_ax`); ``starts``: case id -> s."""
    panels = {q: (title, label) for q, title, label in gfigs.KINETICS_PANELS}
    if quantity not in panels:
        raise LigwfError(f"plot_kinetics: quantity = {quantity!r} is not one of "
                         f"{', '.join(panels)}")
    title, label = panels[quantity]
    ax = gfigs.kinetics_ax(axes(ax), summary, quantity, title, label,
                           gfigs.production_origins(per_case, starts))
    figs.legend_below(ax, ncol=2, fontsize=7)
    return ax
