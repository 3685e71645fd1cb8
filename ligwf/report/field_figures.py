"""Maps of the cross-section fields: per condition, and CG-n minus CG1, on shared scales.

Each plotting function draws on a matplotlib ``Axes`` and returns it (the object-oriented
API: no backend switch at import); :func:`ligwf.report.figures.save` writes a figure as
PNG atomically.
:func:`group_figures` lays out the report's two figures per sweep group: the maps of
every condition (rows; solid fraction, speed with in-plane arrows, granular temperature)
and their differences from CG1, each quantity on one colour scale across the rows, so
the rows compare by eye. The drum wall is outlined and its sense of rotation named.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ligwf.analysis.records.conditions import Conditions
from ligwf.inference.field_errors import MATERIAL_SOLID, condition_mean
from ligwf.analysis.records.fields import CaseFields, FieldGrid, fields_of
from ligwf.report.figures import save
from ligwf.scene.axis import Axis
from ligwf.study import layout

#: quantity -> (label, colour map) of the maps
QUANTITIES = {"solid_fraction": ("solid fraction [-]", "viridis"),
              "speed": ("speed [m/s]", "magma"),
              "temperature": ("granular temperature [m²/s²]", "cividis")}
#: colour scales end at this percentile of the values (one hot node does not squash them)
SCALE_PERCENTILE = 99.0
#: arrows per axis on a speed map
ARROWS = 15


def rotation_sense(axis: Axis, omega: float) -> str:
    """How the drum turns on the maps (u to the right, v up): clockwise or
    counter-clockwise."""
    ia, iu, iv = axis.frame
    eu, ev, ea = np.eye(3)[iu], np.eye(3)[iv], np.eye(3)[ia]
    towards_viewer = float(np.dot(np.cross(eu, ev), ea))
    return "counter-clockwise" if omega * towards_viewer > 0 else "clockwise"


def _scale(values: list[np.ndarray], symmetric: bool) -> tuple[float, float]:
    finite = np.concatenate([v[np.isfinite(v)].ravel() for v in values] or [np.empty(0)])
    if not len(finite):
        return (-1.0, 1.0) if symmetric else (0.0, 1.0)
    if symmetric:
        top = float(np.percentile(np.abs(finite), SCALE_PERCENTILE)) or 1.0
        return -top, top
    top = float(np.percentile(finite, SCALE_PERCENTILE))
    return 0.0, top if top > 0 else 1.0


def _frame(ax, grid: FieldGrid, title: str):
    radius = -grid.origin
    t = np.linspace(0, 2 * np.pi, 200)
    ax.plot(1e3 * radius * np.cos(t), 1e3 * radius * np.sin(t), color="0.3", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xlim(-1e3 * radius * 1.02, 1e3 * radius * 1.02)
    ax.set_ylim(-1e3 * radius * 1.02, 1e3 * radius * 1.02)
    ax.set_xlabel("u [mm]")
    ax.set_ylabel("v [mm] (up)")
    ax.set_title(title, fontsize=9)


def field_map(ax, grid: FieldGrid, values: np.ndarray, title: str, vmin: float, vmax: float,
              cmap: str, label: str, arrows: tuple[np.ndarray, np.ndarray] | None = None):
    """One field on the cross-section (``values`` on the grid nodes, nan: no material)
    with the drum wall, a colour bar labelled ``label`` and, with ``arrows`` (u, v
    velocity components), the in-plane velocity as arrows; returns ``ax``."""
    x = 1e3 * grid.coordinates()
    mesh = ax.pcolormesh(x, x, np.ma.masked_invalid(values), cmap=cmap, vmin=vmin, vmax=vmax,
                         shading="nearest")
    if arrows is not None:
        step = max(1, grid.nodes // ARROWS)
        sl = (slice(None, None, step), slice(None, None, step))
        xx, yy = np.meshgrid(x, x)
        ax.quiver(xx[sl], yy[sl], np.nan_to_num(arrows[0][sl]), np.nan_to_num(arrows[1][sl]),
                  color="white", width=0.004, pivot="mid")
    ax.figure.colorbar(mesh, ax=ax, label=label, shrink=0.85)
    _frame(ax, grid, title)
    return ax


def _fields(runs: list[CaseFields]) -> dict[str, np.ndarray]:
    """The condition's fields for the maps: velocity and temperature only where the solid
    fraction reaches MATERIAL_SOLID (the field error's support; the dilute spray above
    the bed, a few fast particles, would set the colour scale otherwise)."""
    f = fields_of(condition_mean(runs))
    dilute = ~(f["solid_fraction"] >= MATERIAL_SOLID)
    return {k: (np.where(dilute, np.nan, v) if k != "solid_fraction" else v)
            for k, v in f.items()}


def maps_figure(rows: list[tuple[str, list[CaseFields]]], sense: str) -> Figure:
    """Rows of (condition label, its cases): solid fraction, speed with arrows and
    granular temperature, one colour scale per quantity across the rows."""
    fields = [_fields(m) for _, m in rows]
    grid = rows[0][1][0].grid
    fig = Figure(figsize=(13, 3.6 * len(rows)), layout="constrained")
    axes = fig.subplots(len(rows), 3, squeeze=False)
    for k, (q, (label, cmap)) in enumerate(QUANTITIES.items()):
        lo, hi = _scale([f[q] for f in fields], symmetric=False)
        for r, ((name, _), f) in enumerate(zip(rows, fields)):
            arrows = (f["velocity_u"], f["velocity_v"]) if q == "speed" else None
            field_map(axes[r][k], grid, f[q], f"{name}: {label.split(' [')[0]}", lo, hi,
                      cmap, label, arrows)
    fig.suptitle(f"Window-mean fields (drum turns {sense} in these maps)", fontsize=10)
    return fig


def differences_figure(reference: list[CaseFields], rows: list[tuple[str, list[CaseFields]]],
                       sense: str) -> Figure:
    """Rows of (condition label, its cases) minus the CG1 ``reference`` fields: solid
    fraction, speed and temperature differences (the last two where both have material),
    each on one symmetric colour scale across the rows (red: more than CG1)."""
    ref = _fields(reference)
    diffs = [{q: _fields(m)[q] - ref[q] for q in QUANTITIES} for _, m in rows]
    grid = reference[0].grid
    fig = Figure(figsize=(13, 3.6 * len(rows)), layout="constrained")
    axes = fig.subplots(len(rows), 3, squeeze=False)
    for k, (q, (label, _)) in enumerate(QUANTITIES.items()):
        lo, hi = _scale([d[q] for d in diffs], symmetric=True)
        for r, ((name, _), d) in enumerate(zip(rows, diffs)):
            field_map(axes[r][k], grid, d[q], f"{name} minus CG1: {label.split(' [')[0]}",
                      lo, hi, "RdBu_r", "difference in " + label)
    fig.suptitle(f"Difference from CG1 (drum turns {sense} in these maps)", fontsize=10)
    return fig


def group_figures(cases, fields: dict[str, CaseFields], fig_dir: Path, sense: str,
                  twins: dict[str, list[str]]) -> list[tuple[str, Path]]:
    """The maps and difference figures of every sweep group with CG1 fields:
    (title, PNG path). ``cases``: the case table (case_id, group, cg, rule); ``twins``:
    per wet group the ids of its cohesionless CG1 twins (drawn in the wet group's
    figures; their own control groups get none)."""
    out: list[tuple[str, Path]] = []
    if not fields or cases.empty:
        return out
    groups = Conditions.of(cases.itertuples())
    controls = {groups.condition(c).group for ids in twins.values() for c in ids
                if c in set(cases["case_id"])}
    for k, group in enumerate(groups.groups()):
        ref = [fields[c] for c in groups.reference_cases(group) if c in fields]
        if not ref or group in controls:
            continue
        rows = [(cond.name, [fields[c] for c in ids if c in fields])
                for cond, ids in sorted(groups.cases.items(), key=lambda kv: kv[0].key)
                if cond.group == group and not cond.is_reference]
        rows.append(("cg1 cohesionless twin", [fields[c] for c in twins.get(group, [])
                                               if c in fields]))
        rows = [r for r in rows if r[1]]
        if not rows:
            continue
        tag = "study" if group in ("{}", "") else f"group{k}"
        where = "" if tag == "study" else f" ({group})"
        maps = maps_figure([("cg1", ref)] + rows, sense)
        out.append((f"Flow fields{where}", save(maps, fig_dir / layout.field_figure(tag, "maps"))))
        diff = differences_figure(ref, rows, sense)
        out.append((f"Flow fields minus CG1{where}",
                    save(diff, fig_dir / layout.field_figure(tag, "differences"))))
    return out
