"""Report figures (matplotlib, Agg) and off-screen pyvista snapshots, as PNG files.

Each function takes tables already computed by :mod:`ligwf.report.tables` and one output path,
and writes the PNG atomically (render to memory, then rename).
"""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import NullFormatter  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from ligwf.fsio import atomic_write_bytes  # noqa: E402


def _axes(ax, xlabel: str, ylabel: str, title: str, legend: int | None = None) -> None:
    """Axis labels, a small title, an optional legend (font size) and a light grid."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    if legend:
        ax.legend(fontsize=legend)
    ax.grid(alpha=0.3)


def _save(fig, path: Path) -> Path:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    atomic_write_bytes(path, buf.getvalue())
    return path


def _label(cg: float, rule: str) -> str:
    return "CG1" if cg == 1 else f"CG{cg:g} {rule}"


def pareto(conditions: pd.DataFrame, path: Path) -> Path:
    """Error vs run time on the table's footing: x is production core-seconds per simulated
    second of production per 1,000 particles of the original system (what the speedup
    column divides), errors with their intervals
    and the CG1 noise floor (dotted); a third panel shows each condition's fill, settle and
    production core-seconds, which the x axis leaves out."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    for ax, col, title in ((axes[0], "angle_error", "angle of repose error vs CG1"),
                           (axes[1], "profile_error", "velocity profile error (rel. L2) vs CG1")):
        for _, r in conditions.iterrows():
            y, x = r[col], r["production_core_rate_k"]
            if not np.isfinite(y) or not np.isfinite(x):
                continue
            lo, hi = r.get(f"{col}_lo"), r.get(f"{col}_hi")
            yerr = None
            if np.isfinite(lo) and np.isfinite(hi):
                yerr = 100 * np.array([[max(y - lo, 0)], [max(hi - y, 0)]])
            ax.errorbar(x, 100 * y, yerr=yerr, fmt="o", capsize=3)
            ax.annotate(_label(r["cg"], r["rule"]), (x, 100 * y),
                        textcoords="offset points", xytext=(4, 4), fontsize=8)
        floors = conditions.get(f"{col}_floor", pd.Series(dtype=float)).dropna()
        if len(floors):
            ax.axhline(100 * floors.iloc[0], ls=":", color="grey",
                       label=f"CG1 noise floor ({conditions[f'{col}_floor_source'].iloc[0]})")
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())   # minor labels overlap on short spans
        _axes(ax, "production core-s / simulated s / 1k original particles",
              "error [%]", title,
              legend=7 if len(floors) else None)
    ax = axes[2]
    labels = [_label(r["cg"], r["rule"]).replace(" ", "\n") for _, r in conditions.iterrows()]
    bottom = np.zeros(len(conditions))
    for phase in ("fill", "settle", "production"):
        vals = conditions.get(f"{phase}_core_seconds", pd.Series(np.nan, index=conditions.index))
        vals = np.nan_to_num(vals.to_numpy(float))
        ax.bar(labels, vals, bottom=bottom, label=phase)
        bottom += vals
    ax.set_yscale("log")
    _axes(ax, "condition", "core-seconds per run (mean over replicas)",
          "run cost by phase", legend=8)
    return _save(fig, path)


#: axis label and title part of each analysis.gsd_volume convention
GSD_VOLUME_LABELS = {
    "physical": ("granule volume [m$^3$]", "physical granule volumes"),
    "primary": ("granule volume, primary-particle equivalent [m$^3$]", "CG-n volumes / n$^3$"),
}


def gsd_overlay(gsd: pd.DataFrame, path: Path, volume: str = "physical") -> Path:
    """Volume-weighted GSD of each condition with bootstrap bands, on the volume axis of
    the study's ``gsd_volume`` convention (physical, or primary = CG-n volume / n^3)."""
    xlabel, what = GSD_VOLUME_LABELS[volume]
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for name, sub in gsd.groupby("condition", sort=True):
        sub = sub.sort_values("v_mid")
        line, = ax.plot(sub["v_mid"], sub["volume_fraction"], marker=".", label=name)
        ax.fill_between(sub["v_mid"], sub["volume_lo"], sub["volume_hi"], alpha=0.2,
                        color=line.get_color())
    ax.set_xscale("log")
    _axes(ax, xlabel, "volume fraction per bin",
          f"GSD, {what}, against CG1 (95 % bootstrap bands)", legend=8)
    return _save(fig, path)


def velocity_profiles(cases: pd.DataFrame, profiles: dict, path: Path) -> Path:
    """Mean downhill velocity against the normalised depth below the free surface, per case
    (the coordinate the profile error compares on); ``profiles``: case id ->
    :class:`~ligwf.analysis.records.flow.CaseFlow`."""
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for _, r in cases.sort_values(["cg", "rule", "replica"]).iterrows():
        p = profiles.get(r["case_id"])
        if p is None or not p.measured:
            continue
        v = np.array(p.profile_v_mean, dtype=float)
        ax.plot(v, np.array(p.profile_s), label=r["case_id"], lw=1.2,
                ls="-" if r["cg"] == 1 else ("--" if r["rule"] == "weber" else ":"))
    ax.axvline(0, color="k", lw=0.5)
    ax.invert_yaxis()
    _axes(ax, "velocity down the free surface [m/s]",
          "depth below the free surface / bed depth",
          "velocity profiles (solid CG1, dashed weber, dotted bond)", legend=7)
    return _save(fig, path)


def snapshot(particles_vtu: Path, drum_stl: Path, axis: str, drum_angle: float, scalar: str,
             path: Path, title: str) -> Path:
    """Off-screen pyvista picture of one frame seen along the drum axis, coloured by
    ``scalar`` (``speed`` or ``granule``), with the drum turned to ``drum_angle`` (rad)."""
    from ligwf.report.offscreen import granule_colours, pyvista_offscreen
    from ligwf.report.paraview import read_stl, rotation_matrix

    pv = pyvista_offscreen()
    cloud = pv.read(str(particles_vtu))
    note = ""
    if scalar == "granule":
        cloud["colour"], note = granule_colours(np.asarray(cloud["granule"]))
    if scalar == "speed":
        cloud["speed"] = np.linalg.norm(np.asarray(cloud["v"]), axis=1)
    if "radius" in cloud.array_names:
        cloud["diameter"] = 2 * np.asarray(cloud["radius"])
        spheres = cloud.glyph(scale="diameter", geom=pv.Sphere(theta_resolution=10,
                                                               phi_resolution=10), orient=False)
    else:
        spheres = cloud
    plotter = pv.Plotter(off_screen=True, window_size=(640, 640))
    if scalar == "granule":   # categorical: one colour per granule, no continuous bar
        plotter.add_mesh(spheres, scalars="colour", rgb=True)
    else:
        plotter.add_mesh(spheres, scalars=scalar, cmap="viridis", show_scalar_bar=True)
    tri = read_stl(drum_stl) @ rotation_matrix(axis, drum_angle).T
    drum = pv.PolyData(tri.reshape(-1, 3),
                       np.c_[np.full(len(tri), 3), np.arange(3 * len(tri)).reshape(-1, 3)].ravel())
    plotter.add_mesh(drum, style="wireframe", color="grey", opacity=0.3)
    plotter.add_text(title + (f"\n{note}" if note else ""), font_size=10)
    normal = {"x": (1, 0, 0), "y": (0, -1, 0), "z": (0, 0, 1)}[axis]
    plotter.view_vector(normal, viewup=(0, 0, 1) if axis != "z" else (0, 1, 0))
    png = plotter.screenshot(return_img=True)
    plotter.close()
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(png).save(buf, format="PNG")
    atomic_write_bytes(path, buf.getvalue())
    return path
