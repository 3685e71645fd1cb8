"""Report figures of the granule analysis: granulation kinetics and definition sensitivity.

Read from the analysis folder (:mod:`ligwf.analysis.gsd.kinetics` writes the tables):
``kinetics_summary.csv`` -> granule count, d50, largest granule and bed share in granules
against the time from the start of production (the drum starts turning; the tables count
time from the start of the simulation, fill and settling included), one line per
condition with its band over replicas; ``sensitivity.csv`` -> granule count, d50 and
largest granule under each variant of the definition. Plotting functions draw into an
``Axes`` and return it (:mod:`ligwf.report.figures`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ligwf.report.figures import save, table_label
from ligwf.study import layout

#: (column, panel title, y label)
KINETICS_PANELS = [("granules", "granule count", "granules (count)"),
                   ("d50", "median granule size", "d50 [mm]"),
                   ("largest_granule", "largest granule", "largest granule [bed share]"),
                   ("granule_share", "bed in granules", "bed share in granules")]
SENSITIVITY_PANELS = [("granules", "granules (count)"), ("d50", "d50 [mm]"),
                      ("largest_granule", "largest granule [bed share]")]
TIME_LABEL = "time from production start [s]"


def _read(path: Path) -> pd.DataFrame:
    if not path.is_file() or path.stat().st_size <= 1:
        return pd.DataFrame()
    try:
        return pd.read_csv(path)
    except pd.errors.EmptyDataError:
        return pd.DataFrame()


def production_origins(kinetics: pd.DataFrame, starts: dict[str, float]) -> dict[str, float]:
    """condition -> simulated time (s) at which its production starts, from the per-case
    kinetics table (case_id, condition) and each case's start (case id -> s); the earliest
    of a condition's replicas (they share their scene's time line)."""
    if kinetics.empty or "case_id" not in kinetics:
        return {}
    pairs = kinetics[["case_id", "condition"]].drop_duplicates()
    out: dict[str, float] = {}
    for cid, cond in zip(pairs["case_id"], pairs["condition"]):
        if cid in starts:
            out[cond] = min(out.get(cond, starts[cid]), starts[cid])
    return out


def kinetics_ax(ax: Axes, summary: pd.DataFrame, quantity: str, title: str, ylabel: str,
                origins: dict[str, float] | None = None) -> Axes:
    """One kinetics quantity per condition against the time from production start (s;
    ``origins``: condition -> production start, s; a condition without one is drawn on
    the table's time and said in its label), with the band over replicas."""
    origins = origins or {}
    scale = 1e3 if quantity == "d50" else 1.0
    for name, d in summary.groupby("condition"):
        d = d.sort_values("time")
        t0 = origins.get(name)
        t = d["time"] - (t0 if t0 is not None else 0.0)
        label = table_label(name, d)
        line, = ax.plot(t, d[quantity] * scale,
                        label=label if t0 is not None else f"{label} (time from start)")
        ax.fill_between(t, d[f"{quantity}_lo"] * scale, d[f"{quantity}_hi"] * scale,
                        color=line.get_color(), alpha=0.2)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    return ax


def kinetics_figure(summary: pd.DataFrame, out: Path,
                    origins: dict[str, float] | None = None) -> Path:
    """The kinetics panels side by side, one legend under them; d50 in mm, bands: 95 %
    over replicas."""
    fig = Figure(figsize=(4 * len(KINETICS_PANELS), 3.8))
    axes = fig.subplots(1, len(KINETICS_PANELS))
    for ax, (q, title, label) in zip(axes, KINETICS_PANELS):
        kinetics_ax(ax, summary, q, title, label, origins)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(4, len(labels)), fontsize=8,
               frameon=False, bbox_to_anchor=(0.5, -0.08))
    fig.subplots_adjust(wspace=0.35, bottom=0.22)
    return save(fig, out)


def sensitivity_ax(ax: Axes, table: pd.DataFrame, quantity: str, label: str,
                   names: bool = True) -> Axes:
    """One bar per variant of the definition; the first (black) is the setting used; each
    bar says its value ("none": no granule counted, e.g. the whole bed one cluster)."""
    scale = 1e3 if quantity == "d50" else 1.0
    y = list(range(len(table)))
    values = pd.to_numeric(table[quantity], errors="coerce").to_numpy(float) * scale
    bars = ax.barh(y, np.nan_to_num(values), color=["k"] + ["C0"] * (len(table) - 1))
    ax.bar_label(bars, labels=[f"{v:.3g}" if np.isfinite(v) else "none" for v in values],
                 fontsize=7, padding=2)
    ax.set_yticks(y, list(table["variant"]) if names else [""] * len(table), fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel(label)
    ax.grid(alpha=0.3, axis="x")
    return ax


def sensitivity_figure(table: pd.DataFrame, out: Path) -> Path:
    """The definition-sensitivity panels of the report (:func:`sensitivity_ax`)."""
    fig = Figure(figsize=(4 * len(SENSITIVITY_PANELS), 3.6))
    axes = fig.subplots(1, len(SENSITIVITY_PANELS))
    for i, (ax, (q, label)) in enumerate(zip(axes, SENSITIVITY_PANELS)):
        sensitivity_ax(ax, table, q, label, names=i == 0)
    fig.suptitle(f"definition sensitivity ({table['case_id'].iloc[0]}, "
                 f"{int(table['frames'].iloc[0])} steady frames; black: the setting used)",
                 fontsize=9)
    fig.subplots_adjust(wspace=0.3)
    return save(fig, out)


def granule_figures(analysis_dir: Path, fig_dir: Path,
                    starts: dict[str, float] | None = None) -> list[tuple[str, Path]]:
    """(title, path) of the granule figures whose tables exist in ``analysis_dir``;
    ``starts``: case id -> production start (s), the kinetics' time origin."""
    out = []
    kin = _read(Path(analysis_dir) / layout.KINETICS_SUMMARY_TABLE)
    if not kin.empty:
        per_case = _read(Path(analysis_dir) / layout.KINETICS_TABLE)
        out.append(("Granulation kinetics", kinetics_figure(
            kin, fig_dir / layout.FIGURE_KINETICS, production_origins(per_case, starts or {}))))
    sens = _read(Path(analysis_dir) / layout.SENSITIVITY_TABLE)
    if not sens.empty:
        out.append(("Granule definition sensitivity",
                    sensitivity_figure(sens, fig_dir / layout.FIGURE_SENSITIVITY)))
    return out
