"""Report figures: plotting functions that draw into a matplotlib ``Axes`` and return it.

Each ``*_ax`` function takes tables already computed by :mod:`ligwf.inference.study_tables` (or read
from the analysis folder) and an ``Axes``; the report's figure functions (:func:`pareto`,
:func:`gsd_overlay`, :func:`velocity_profiles`) lay them out on a
:class:`matplotlib.figure.Figure` and :func:`save` writes the PNG atomically. No backend is
switched at import: a ``Figure`` made directly renders to PNG without pyplot, so a notebook
that imports ligwf keeps its own backend.

Conventions every figure keeps: legends outside the data (below the axes), log axes with a
tick label at every 1-2-5 (or every integer) step so a short span still reads, granule
sizes as equivalent diameters in mm.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from ligwf.study.condition import REFERENCE_CG, Condition
from ligwf.fsio import atomic_write_bytes
from ligwf.study.case import group_label

#: phases of a run's cost, as the conditions table names them (``<phase>_core_seconds``)
PHASES = ("fill", "settle", "production")
#: relative x offset between the CG-n points of an error plot (their costs are often equal)
DODGE = 0.04


def save(fig: Figure, path: Path, dpi: int = 110) -> Path:
    """Write ``fig`` as PNG to ``path`` atomically (rendered in memory, then renamed)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    atomic_write_bytes(path, buf.getvalue())
    return path


def legend_below(ax: Axes, ncol: int = 3, fontsize: int = 8) -> None:
    """The legend under the axes (never over the data or its error bars)."""
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        ax.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, -0.2),
                  ncol=min(ncol, len(handles)), fontsize=fontsize, frameon=False)


def log_ticks(ax: Axes, axis: str = "x") -> None:
    """Readable tick labels on a log axis: every decade on a wide span, 1-2-5 on one to
    three decades, every integer multiple on less than a decade (plain numbers, no
    overlapping minor labels)."""
    lo, hi = ax.get_xlim() if axis == "x" else ax.get_ylim()
    decades = math.log10(hi / lo) if lo > 0 and hi > lo else 1.0
    subs = (1.0,) if decades > 3 else (1.0, 2.0, 5.0) if decades > 1 else tuple(range(1, 10))
    target = ax.xaxis if axis == "x" else ax.yaxis
    target.set_major_locator(LogLocator(base=10, subs=subs))
    target.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    target.set_minor_formatter(NullFormatter())


def log_scale(ax: Axes, axis: str, values, empty: str) -> None:
    """A log ``axis`` with :func:`log_ticks` when some of ``values`` is positive; otherwise
    the axis stays linear and says ``empty`` (matplotlib cannot place log ticks on no data:
    a study without recorded run costs would end its report in a traceback)."""
    v = np.asarray(values, float)
    if np.any(np.isfinite(v) & (v > 0)):
        (ax.set_xscale if axis == "x" else ax.set_yscale)("log")
        log_ticks(ax, axis)
    else:
        ax.text(0.5, 0.5, empty, transform=ax.transAxes, ha="center", va="center",
                color="grey", fontsize=9)


def group_suffix(group) -> str:
    """" (cohesionless control)" for a sweep group recorded as JSON, "" for the study's
    main group (``{}``); the words are :func:`ligwf.study.case.group_label`'s."""
    return "" if group in ("{}", "", None) or pd.isna(group) else f" ({group_label(group)})"


def condition_label(cg: float, rule: str, group="") -> str:
    """CG1, CG2 weber, CG1 (cohesionless control): a condition as the figures name it."""
    return ("CG1" if cg == REFERENCE_CG else f"CG{cg:g} {rule}") + group_suffix(group)


def _label(r) -> str:
    return condition_label(r["cg"], r["rule"], r.get("group", ""))


def table_label(name: str, rows: pd.DataFrame) -> str:
    """The figure label of a condition of a per-condition table (gsd.csv, kinetics): from
    its cg / rule / group columns when it has them, else the table's condition name."""
    if rows.empty or not {"cg", "rule"} <= set(rows.columns):
        return str(name)
    return _label(rows.iloc[0])


def floor_label(source) -> str:
    """Legend entry of a noise floor: short, "indicative" when it is."""
    return "CG1 noise floor" + (" (indicative)" if "indicative" in str(source) else "")


def error_ax(ax: Axes, conditions: pd.DataFrame, col: str, title: str) -> Axes:
    """One error against the production cost per CG-n condition: points with their 95 %
    interval (points of equal cost nudged apart by :data:`DODGE`), the CG1 noise floor of
    each compared group as a dotted line, each CG1 reference's own cost as a
    dashed vertical line (the distance to it is the speedup); x: production core-s per
    simulated s per 1,000 original particles (the speedup's footing), log scale."""
    compared = int((conditions["cg"] != REFERENCE_CG).sum())
    j = 0
    for i, (_, r) in enumerate(conditions.iterrows()):
        y, x = r[col], r["production_core_rate_k"]
        if not np.isfinite(x):
            continue
        if r["cg"] == REFERENCE_CG:
            ax.axvline(x, ls="--", lw=1, color=f"C{i}", label=f"{_label(r)} cost (reference)")
            continue
        x *= 1 + DODGE * (j - (compared - 1) / 2)   # nudged apart: overlapping bars stay legible
        j += 1
        if not np.isfinite(y):
            continue
        lo, hi = r.get(f"{col}_lo", np.nan), r.get(f"{col}_hi", np.nan)
        yerr = (100 * np.array([[max(y - lo, 0)], [max(hi - y, 0)]])
                if np.isfinite(lo) and np.isfinite(hi) else None)
        ax.errorbar(x, 100 * y, yerr=yerr, fmt="o", capsize=3, color=f"C{i}", label=_label(r))
    if f"{col}_floor" in conditions:   # one floor per sweep group (its CG1 replicas)
        with_floor = conditions[conditions[f"{col}_floor"].notna()
                                & (conditions["cg"] != REFERENCE_CG)]
        groups = with_floor.drop_duplicates("group") if "group" in with_floor else with_floor[:1]
        for k, (_, r) in enumerate(groups.iterrows()):
            suffix = group_suffix(r.get("group", "")) if len(groups) > 1 else ""
            ax.axhline(100 * r[f"{col}_floor"], ls=":", color="grey", lw=1 + k / 2,
                       label=floor_label(r[f"{col}_floor_source"]) + suffix)
    ax.margins(x=0.15)
    log_scale(ax, "x", conditions["production_core_rate_k"], "no production cost recorded")
    ax.set_ylim(bottom=0)
    ax.set_xlabel("production core-s / simulated s / 1k original particles")
    ax.set_ylabel("error [%]")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=1)
    return ax


def run_cost_ax(ax: Axes, conditions: pd.DataFrame) -> Axes:
    """Core-seconds of each phase per condition as grouped bars (each from the axis, so a
    small phase never vanishes under a large one on the log scale), the value on top."""
    labels = [_label(r).replace(" (", "\n(") for _, r in conditions.iterrows()]
    x = np.arange(len(labels))
    width = 0.8 / len(PHASES)
    recorded = []
    for k, phase in enumerate(PHASES):
        vals = conditions.get(f"{phase}_core_seconds",
                              pd.Series(np.nan, index=conditions.index)).to_numpy(float)
        recorded.extend(vals)
        bars = ax.bar(x + (k - 1) * width, np.where(vals > 0, vals, np.nan), width,
                      label=phase, color=f"C{k}")
        ax.bar_label(bars, labels=[f"{v:.3g}" if v > 0 else "" for v in vals], fontsize=6,
                     padding=1)
    ax.set_xticks(x, labels, fontsize=8)
    log_scale(ax, "y", recorded, "no run cost recorded")
    ax.set_ylabel("core-seconds per run (mean over replicas)")
    ax.set_title("run cost by phase", fontsize=10)
    ax.grid(alpha=0.3, axis="y")
    legend_below(ax)
    return ax


def criterion_error_ax(ax: Axes, conditions: pd.DataFrame, verdict_rows: pd.DataFrame,
                       criterion: str) -> Axes | None:
    """One criterion of the verdict against the production cost per CG-n level: the
    verdict's estimate and interval in its unit (degrees for the angle, the same numbers
    as the verdict table: ``verdict_rows`` is :func:`ligwf.report.forest.forest_rows`),
    the budget shaded, each CG1 reference's cost as a dashed line; x as :func:`error_ax`.
    Each point is a line with ``gid`` ``"<condition>|<criterion>"`` (its interval) and
    ``...|value`` (its estimate). None (nothing drawn) when the verdict has no value of it."""
    rows = verdict_rows[verdict_rows["criterion"] == criterion] if not verdict_rows.empty \
        else verdict_rows
    if rows.empty or not np.isfinite(rows["value"].to_numpy(float)).any():
        return None
    cost = {}
    for _, r in conditions.iterrows():
        name = Condition(str(r.get("group", "{}")), float(r["cg"]), str(r["rule"])).name
        cost[name] = float(r["production_core_rate_k"])
        if r["cg"] == REFERENCE_CG and np.isfinite(cost[name]):
            ax.axvline(cost[name], ls="--", lw=1, color="grey",
                       label=f"{_label(r)} cost (reference)")
    first = rows.iloc[0]
    budget = float(np.nanmax(rows["budget"])) if rows["budget"].notna().any() else math.nan
    if math.isfinite(budget):
        ax.axhspan(-budget if first["signed"] else 0.0, budget, color="tab:green", alpha=0.12,
                   lw=0, label=f"budget {'+-' if first['signed'] else '<= '}{budget:g}")
    compared = len(rows)
    for j, (_, r) in enumerate(rows.iterrows()):
        x = cost.get(r["condition"], math.nan) * (1 + DODGE * (j - (compared - 1) / 2))
        if not (np.isfinite(x) and math.isfinite(r["value"])):
            continue
        tag = f"{r['condition']}|{criterion}"
        if math.isfinite(r["lo"]) and math.isfinite(r["hi"]):
            ax.plot([x, x], [r["lo"], r["hi"]], color=f"C{j}", lw=1.5, gid=tag)
        ax.plot([x], [r["value"]], "o", color=f"C{j}", gid=tag + "|value",
                label=f"{r['condition']} ({r['state']})")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.margins(x=0.15)
    log_scale(ax, "x", conditions["production_core_rate_k"], "no production cost recorded")
    unit = f" [{first['unit']}]" if first["unit"] else ""
    what = "CG-n - CG1" if first["signed"] else "error vs CG1"
    ax.set_xlabel("production core-s / simulated s / 1k original particles")
    ax.set_ylabel(f"{first['label']}, {what}{unit}")
    ax.set_title(f"{first['label']}: the verdict's interval and budget", fontsize=10)
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=1)
    return ax


def pareto_figure(conditions: pd.DataFrame, verdict_rows: pd.DataFrame | None = None
                  ) -> Figure:
    """Error vs run time (angle of repose, velocity profile) and the run cost by phase.
    With the verdict's rows (:func:`ligwf.report.forest.forest_rows`) the two error panels
    show the verdict's criteria, so the figure and the verdict table show the same numbers
    in the same units; without a verdict the conditions table's relative errors."""
    fig = Figure(figsize=(15, 4.8))
    axes = fig.subplots(1, 3)
    rows = verdict_rows if verdict_rows is not None else pd.DataFrame()
    for ax, criterion, col, title in (
            (axes[0], "angle_deg", "angle_error", "angle of repose error vs CG1"),
            (axes[1], "profile_error", "profile_error", "velocity profile error (rel. L2) vs CG1")):
        if criterion_error_ax(ax, conditions, rows, criterion) is None:
            error_ax(ax, conditions, col, title)
    run_cost_ax(axes[2], conditions)
    fig.subplots_adjust(wspace=0.32)
    return fig


def pareto(conditions: pd.DataFrame, path: Path, verdict_rows: pd.DataFrame | None = None
           ) -> Path:
    """The error-vs-run-time figure of the report (:func:`pareto_figure`) as PNG."""
    return save(pareto_figure(conditions, verdict_rows), path)


#: axis label and title part of each analysis.gsd_volume convention
GSD_VOLUME_LABELS = {
    "physical": ("granule equivalent diameter [mm]", "physical granule volumes"),
    "primary": ("granule equivalent diameter, primary-particle scale [mm]",
                "CG-n volumes / n$^3$"),
}


def equivalent_diameter_mm(volume_m3) -> np.ndarray:
    """Diameter of the sphere of the given volume, in mm: (6 V / pi)^(1/3)."""
    return 1e3 * np.cbrt(6 * np.asarray(volume_m3, dtype=float) / np.pi)


def gsd_ax(ax: Axes, gsd: pd.DataFrame, volume: str = "physical",
           size_limits: dict[str, float] | None = None) -> Axes:
    """Volume-weighted GSD of each condition with its bootstrap band against the
    equivalent diameter (mm, log axis); ``size_limits`` (condition -> granule volume, m^3,
    gsd_summary.csv's located ``lower_limit``) marked as dashed lines of the condition's colour,
    an absent one said in the legend."""
    xlabel, what = GSD_VOLUME_LABELS[volume]
    limits = size_limits or {}
    for name, sub in gsd.groupby("condition", sort=True):
        sub = sub.sort_values("v_mid")
        d = equivalent_diameter_mm(sub["v_mid"])
        line, = ax.plot(d, sub["volume_fraction"], marker=".", label=table_label(name, sub))
        ax.fill_between(d, sub["volume_lo"], sub["volume_hi"], alpha=0.2, color=line.get_color())
        limit = limits.get(name)
        if limit is not None and np.isfinite(limit) and limit > 0:
            at = float(equivalent_diameter_mm(limit))
            ax.axvline(at, ls="--", lw=1, color=line.get_color(),
                       label=f"{table_label(name, sub)}: lower size limit {at:.2g} mm")
        elif name in limits:
            ax.plot([], [], ls="--", color=line.get_color(),
                    label=f"{table_label(name, sub)}: no lower size limit located")
    ax.set_xscale("log")
    log_ticks(ax, "x")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("volume fraction per bin")
    ax.set_title(f"GSD, {what}, against CG1 (95 % bootstrap bands)", fontsize=10)
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=2, fontsize=7)
    return ax


def gsd_overlay(gsd: pd.DataFrame, path: Path, volume: str = "physical",
                size_limits: dict[str, float] | None = None) -> Path:
    """The GSD figure of the report (:func:`gsd_ax`)."""
    fig = Figure(figsize=(7.5, 5.2))
    gsd_ax(fig.subplots(), gsd, volume, size_limits)
    return save(fig, path)


def velocity_profiles_ax(ax: Axes, cases: pd.DataFrame, profiles: dict) -> Axes:
    """Mean downhill velocity against the normalised depth below the free surface, per case
    (the coordinate the profile error compares on); ``profiles``: case id ->
    :class:`~ligwf.analysis.records.flow.CaseFlow`."""
    for _, r in cases.sort_values(["cg", "rule", "replica"]).iterrows():
        p = profiles.get(r["case_id"])
        if p is None or not p.measured:
            continue
        ax.plot(np.array(p.profile_v_mean, dtype=float), np.array(p.profile_s),
                label=r["case_id"], lw=1.2,
                ls="-" if r["cg"] == 1 else ("--" if r["rule"] == "weber" else ":"))
    ax.axvline(0, color="k", lw=0.5)
    ax.invert_yaxis()
    ax.set_xlabel("velocity down the free surface [m/s]")
    ax.set_ylabel("depth below the free surface / bed depth")
    ax.set_title("velocity profiles (solid CG1, dashed weber, dotted bond)", fontsize=10)
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=3, fontsize=7)
    return ax


def velocity_profiles(cases: pd.DataFrame, profiles: dict, path: Path) -> Path:
    """The velocity-profile figure of the report (:func:`velocity_profiles_ax`)."""
    fig = Figure(figsize=(7.5, 5.2))
    velocity_profiles_ax(fig.subplots(), cases, profiles)
    return save(fig, path)
