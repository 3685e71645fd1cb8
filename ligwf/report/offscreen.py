"""Off-screen rendering set up properly, and the categorical colours of granule snapshots.

VTK's default render window on Linux is X11; without a display it prints "bad X server
connection" and only then falls back. Where no display is set, ligwf asks VTK for an EGL
window (GPU-less EGL via Mesa works) or OSMesa, whichever library is installed, before the
first window is made, so nothing is printed; a user's own ``VTK_DEFAULT_OPENGL_WINDOW`` or a
real display is left alone.
"""

from __future__ import annotations

import ctypes.util
import os

import numpy as np

# neutral colours (RGB 0-255) of the bed-spanning cluster and of single particles
SPANNING_RGB = (150, 150, 150)
SINGLE_RGB = (225, 225, 225)
SPANNING_SHARE = 0.5   # a granule holding more than this share of the particles spans the bed


def headless_window() -> str | None:
    """The VTK window class to use without a display (None: leave VTK's default)."""
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return None
    if ctypes.util.find_library("EGL"):
        return "vtkEGLRenderWindow"
    if ctypes.util.find_library("OSMesa"):
        return "vtkOSOpenGLRenderWindow"
    return None


def pyvista_offscreen():
    """pyvista, imported with off-screen rendering on a headless-capable window class."""
    window = headless_window()
    if window:
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", window)
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv


def granule_colours(labels: np.ndarray) -> tuple[np.ndarray, str]:
    """(N, 3) uint8 colours of particles by granule label, and a one-line legend.

    Categorical (tab20 by granule size rank, so neighbouring ids do not get similar
    shades); the bed-spanning cluster (> half the particles) and single particles get
    neutral greys, so one granule does not read as a continuous 0.00-0.00 colour bar.
    """
    from matplotlib import colormaps

    labels = np.asarray(labels).astype(np.int64)
    ids, inverse, sizes = np.unique(labels, return_inverse=True, return_counts=True)
    palette = (np.asarray(colormaps["tab20"].colors) * 255).astype(np.uint8)
    palette = palette[np.ptp(palette.astype(int), axis=1) > 30]   # greys are reserved
    rank = np.empty(len(ids), np.int64)
    rank[np.argsort(-sizes, kind="stable")] = np.arange(len(ids))
    colours = palette[rank % len(palette)]
    spanning = sizes > SPANNING_SHARE * len(labels)
    colours[spanning] = SPANNING_RGB
    colours[sizes == 1] = SINGLE_RGB
    many = int(np.sum(sizes > 1))
    note = f"{many} granule(s) of 2+ particles"
    if spanning.any():
        note += f"; grey: bed-spanning cluster ({100 * sizes[spanning].sum() / len(labels):.0f} %)"
    note += "; light grey: single particles"
    return colours[inverse], note
