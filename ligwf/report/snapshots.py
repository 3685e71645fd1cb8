"""Snapshots of one frame seen along the drum axis: pyvista renders the particles and the
turned drum off-screen, matplotlib lays out the picture with its title, colour bar and the
drum's direction of rotation.

Speed snapshots of the cases of one report share one colour scale (:func:`speed_scale`:
the 99th percentile of every particle speed of every snapshot frame, so one fast particle
cannot wash out the others and the cases can be compared by colour); faster particles get
the top colour, which the colour bar's pointed end says. Granule snapshots are categorical
(:func:`ligwf.report.offscreen.granule_colours`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

import numpy as np
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure

from ligwf.report.figures import save
from ligwf.scene.axis import Axis

#: colour map of speed snapshots
SPEED_CMAP = "viridis"
#: percentile of all snapshot speeds at the top of the shared colour scale
SPEED_PERCENTILE = 99.0
#: where the camera sits (seen from the focal point) and which way is up, per drum axis
VIEW = {Axis.X: ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)), Axis.Y: ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
        Axis.Z: ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0))}


@dataclass(frozen=True)
class SpeedScale:
    """The colour scale speed snapshots share: 0 to ``vmax`` m/s."""

    vmax: float
    cases: int

    @property
    def label(self) -> str:
        return (f"speed [m/s]; one scale for all {self.cases} case(s): top = "
                f"{SPEED_PERCENTILE:g}th percentile of their particles ({self.vmax:.3g} m/s)")


def particle_speeds(particles_vtu: Path) -> np.ndarray:
    """|v| (m/s) of every particle of a dump."""
    from ligwf.report.offscreen import pyvista_offscreen

    cloud = pyvista_offscreen().read(str(particles_vtu))
    return np.linalg.norm(np.asarray(cloud["v"], dtype=float), axis=1)


def speed_scale(dumps: Iterable[Path]) -> SpeedScale | None:
    """The shared scale of the snapshot frames ``dumps`` (None: no particle in them)."""
    dumps = list(dumps)
    speeds = [particle_speeds(p) for p in dumps]
    pooled = np.concatenate(speeds) if speeds else np.empty(0)
    pooled = pooled[np.isfinite(pooled)]
    if not len(pooled):
        return None
    vmax = float(np.percentile(pooled, SPEED_PERCENTILE))
    return SpeedScale(vmax if vmax > 0 else float(pooled.max() or 1.0), len(dumps))


def rotation_sense(axis: Axis, omega: float) -> int:
    """+1 when the drum turns counter-clockwise in the snapshot's view, -1 clockwise (0:
    at rest). The drum turns right-handedly about +axis at ``omega`` (rad/s, signed); the
    camera looks along -view vector with screen right = direction x up (VTK's camera)."""
    if omega == 0:
        return 0
    k = np.zeros(3)
    k[axis.index] = 1.0
    view, up = (np.asarray(v) for v in VIEW[axis])
    right = np.cross(-view, up)
    top_moves = np.sign(omega) * np.cross(k, up)   # velocity of the drum's top point
    return -1 if float(top_moves @ right) > 0 else 1


def render_frame(particles_vtu: Path, drum_stl: Path, axis: Axis, drum_angle: float,
                 scalar: str, vmax: float | None = None) -> tuple[np.ndarray, str]:
    """(RGB image, note) of one frame along the drum axis, coloured by ``scalar``
    (``speed`` on 0..vmax, or ``granule``), with the drum turned to ``drum_angle`` (rad)."""
    from ligwf.report.offscreen import granule_colours, pyvista_offscreen
    from ligwf.report.paraview import read_stl, rotation_matrix

    pv = pyvista_offscreen()
    cloud = pv.read(str(particles_vtu))
    note = ""
    if scalar == "granule":
        cloud["colour"], note = granule_colours(np.asarray(cloud["granule"]))
    else:
        cloud["speed"] = np.linalg.norm(np.asarray(cloud["v"]), axis=1)
    spheres = cloud
    if "radius" in cloud.array_names:
        cloud["diameter"] = 2 * np.asarray(cloud["radius"])
        spheres = cloud.glyph(scale="diameter", orient=False,
                              geom=pv.Sphere(theta_resolution=10, phi_resolution=10))
    plotter = pv.Plotter(off_screen=True, window_size=(640, 640))
    if scalar == "granule":
        plotter.add_mesh(spheres, scalars="colour", rgb=True)
    else:
        top = vmax if vmax else float(np.max(cloud["speed"], initial=0.0)) or 1.0
        plotter.add_mesh(spheres, scalars="speed", cmap=SPEED_CMAP, clim=(0.0, top),
                         show_scalar_bar=False)
    tri = read_stl(drum_stl) @ rotation_matrix(axis, drum_angle).T
    drum = pv.PolyData(tri.reshape(-1, 3),
                       np.c_[np.full(len(tri), 3), np.arange(3 * len(tri)).reshape(-1, 3)].ravel())
    plotter.add_mesh(drum, style="wireframe", color="grey", opacity=0.3)
    view, up = VIEW[axis]
    plotter.view_vector(view, viewup=up)
    image = plotter.screenshot(return_img=True)
    plotter.close()
    return np.asarray(image), note


def snapshot_ax(ax: Axes, image: np.ndarray, title: str, sense: int = 0,
                scale: SpeedScale | None = None, note: str = "") -> Axes:
    """The rendered frame with its title, the rotation arrow (``sense`` from
    :func:`rotation_sense`) and, for speed, the shared colour bar."""
    ax.imshow(image)
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)
    h, w = image.shape[:2]
    if sense:   # an arc over the drum's top, pointing the way the top moves
        left, right = (0.38 * w, 0.07 * h), (0.62 * w, 0.07 * h)
        start, end = (left, right) if sense < 0 else (right, left)
        ax.annotate("", xy=end, xytext=start, arrowprops=dict(
            arrowstyle="-|>", lw=2, color="crimson",
            connectionstyle=f"arc3,rad={-0.35 if sense < 0 else 0.35}"))
        ax.text(0.65 * w, 0.07 * h, "drum turns\n" + ("counter-clockwise" if sense > 0
                                                     else "clockwise"),
                ha="left", va="center", fontsize=8, color="crimson")
    if scale is not None:
        bar = ax.figure.colorbar(ScalarMappable(Normalize(0.0, scale.vmax), SPEED_CMAP), ax=ax,
                                 orientation="horizontal", fraction=0.05, pad=0.02,
                                 extend="max")
        bar.set_label(scale.label, fontsize=7)
        bar.ax.tick_params(labelsize=7)
    if note:
        ax.text(0.5 * w, h, note, ha="center", va="top", fontsize=7, wrap=True)
    return ax


def snapshot(particles_vtu: Path, drum_stl: Path, axis: Axis, drum_angle: float, scalar: str,
             path: Path, title: str, omega: float = 0.0,
             scale: SpeedScale | None = None) -> Path:
    """One snapshot PNG: :func:`render_frame` laid out by :func:`snapshot_ax`."""
    image, note = render_frame(particles_vtu, drum_stl, axis, drum_angle, scalar,
                               scale.vmax if scale else None)
    fig = Figure(figsize=(5.6, 6.2))
    snapshot_ax(fig.subplots(), image, title, rotation_sense(axis, omega),
                scale if scalar == "speed" else None, note)
    return save(fig, path)
