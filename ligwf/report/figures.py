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
    """Error vs run time: each condition's errors against its core-seconds (log x)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, col, title in ((axes[0], "angle_error", "angle of repose error vs CG1"),
                           (axes[1], "profile_error", "velocity profile error (rel. L2) vs CG1")):
        for _, r in conditions.iterrows():
            y = r[col]
            if not np.isfinite(y) or not np.isfinite(r["core_seconds"]):
                continue
            lo, hi = r.get(f"{col}_lo"), r.get(f"{col}_hi")
            yerr = None
            if np.isfinite(lo) and np.isfinite(hi):
                yerr = [[max(y - lo, 0)], [max(hi - y, 0)]]
            ax.errorbar(r["core_seconds"], 100 * y, yerr=None if yerr is None else 100 * np.array(yerr),
                        fmt="o", capsize=3, label=_label(r["cg"], r["rule"]))
            ax.annotate(_label(r["cg"], r["rule"]), (r["core_seconds"], 100 * y),
                        textcoords="offset points", xytext=(4, 4), fontsize=8)
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())   # minor labels overlap on short spans
        _axes(ax, "run time [core-seconds]", "error [%]", title)
    return _save(fig, path)


def gsd_overlay(gsd: pd.DataFrame, path: Path) -> Path:
    """Volume-weighted GSD of each condition (CG-n volumes / n^3) with bootstrap bands."""
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for name, sub in gsd.groupby("condition", sort=True):
        sub = sub.sort_values("v_mid")
        line, = ax.plot(sub["v_mid"], sub["volume_fraction"], marker=".", label=name)
        ax.fill_between(sub["v_mid"], sub["volume_lo"], sub["volume_hi"], alpha=0.2,
                        color=line.get_color())
    ax.set_xscale("log")
    _axes(ax, "granule volume, primary-particle equivalent [m$^3$]", "volume fraction per bin",
           "GSD: CG-n volumes / n$^3$ against CG1 (95 % bootstrap bands)", legend=8)
    return _save(fig, path)


def velocity_profiles(cases: pd.DataFrame, profiles: dict, path: Path) -> Path:
    """Mean velocity profile along the normal to the free surface, per case."""
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for _, r in cases.sort_values(["cg", "rule", "replica"]).iterrows():
        p = profiles.get(r["case_id"])
        if not p:
            continue
        v = np.array(p["v_mean"], dtype=float)
        ax.plot(v, 1000 * np.array(p["s"]), label=r["case_id"], lw=1.2,
                ls="-" if r["cg"] == 1 else ("--" if r["rule"] == "weber" else ":"))
    ax.axvline(0, color="k", lw=0.5)
    _axes(ax, "velocity along the free surface [m/s]",
           "distance from drum centre along the surface normal [mm]",
           "velocity profiles (solid CG1, dashed weber, dotted bond)", legend=7)
    return _save(fig, path)


def snapshot(particles_vtu: Path, drum_stl: Path, axis: str, drum_angle: float, scalar: str,
             path: Path, title: str) -> Path:
    """Off-screen pyvista picture of one frame seen along the drum axis, coloured by
    ``scalar`` (``speed`` or ``granule``), with the drum turned to ``drum_angle`` (rad)."""
    from ligwf.report.paraview import rotation_matrix
    import pyvista as pv

    pv.OFF_SCREEN = True
    cloud = pv.read(str(particles_vtu))
    if scalar == "speed":
        cloud["speed"] = np.linalg.norm(np.asarray(cloud["v"]), axis=1)
    if "radius" in cloud.array_names:
        cloud["diameter"] = 2 * np.asarray(cloud["radius"])
        spheres = cloud.glyph(scale="diameter", geom=pv.Sphere(theta_resolution=10,
                                                               phi_resolution=10), orient=False)
    else:
        spheres = cloud
    plotter = pv.Plotter(off_screen=True, window_size=(640, 640))
    cmap = "viridis" if scalar == "speed" else "tab20"
    plotter.add_mesh(spheres, scalars=scalar, cmap=cmap, show_scalar_bar=True)
    drum = pv.read(str(drum_stl))
    drum.points = np.asarray(drum.points) @ rotation_matrix(axis, drum_angle).T
    plotter.add_mesh(drum, style="wireframe", color="grey", opacity=0.3)
    plotter.add_text(title, font_size=10)
    normal = {"x": (1, 0, 0), "y": (0, -1, 0), "z": (0, 0, 1)}[axis]
    plotter.view_vector(normal, viewup=(0, 0, 1) if axis != "z" else (0, 1, 0))
    png = plotter.screenshot(return_img=True)
    plotter.close()
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(png).save(buf, format="PNG")
    atomic_write_bytes(path, buf.getvalue())
    return path
