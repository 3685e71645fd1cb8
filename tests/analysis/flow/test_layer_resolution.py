"""The flowing layer's thickness is not yet size-invariant (issue 44 item 1, open): a known
8 mm layer on synthetic beds of 1, 2 and 3 mm grains (touching spheres on a square lattice
below a flat 35 deg surface, downhill speed falling linearly to zero 8 mm below the grain
tops) reads 8.76 / 7.70 / 7.52 mm today. Two parts, both measured here: the fitted surface
sits 0.07 / 0.41 / 0.65 mm below the grain tops (it fits strip tops, and a coarser bed's
tops lie further below its plane), and the zero crossing is interpolated between depth bins
that hold whole rows of grains. Over the ladder's CG1-CG3 that is -1.2 mm, against the
+1.1 mm the 80-min ladder measured (8.8 / 9.5 / 9.9 mm): on this lattice the estimator's
bias runs against the measured growth; a random bed's bias is not measured here, so the
size of that growth is not known to better than about a grain.

The test states the criterion a size-invariant estimator must meet and is marked as an
expected failure (strict: it fails the suite the day the estimator meets it, so the mark
and this docstring are updated with the fix)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ligwf.analysis.flow.frame import DrumGeometry, cross_section, frame_flow, rising_side
from ligwf.analysis.flow.surface import fit_surface
from ligwf.analysis.frames.dumps import ParticleFrame

R, LENGTH, OMEGA, ANGLE, LAYER, SPEED = 0.05, 0.01, 2.0, math.radians(35.0), 0.008, 0.3
STRIP = 0.006   # the study's one resolution: twice the coarsest (3 mm) diameter


def bed(d: float) -> ParticleFrame:
    """Touching spheres of diameter d on a square lattice below a plane through the drum
    axis at 35 deg (grain tops at the plane), flowing downhill above depth LAYER."""
    g = np.arange(-R + d / 2, R, d)
    ys = (np.arange(max(1, int(LENGTH / d))) + 0.5) * LENGTH / max(1, int(LENGTH / d))
    uu, vv = (a.ravel() for a in np.meshgrid(g, g))
    normal = -uu * math.sin(ANGLE) + vv * math.cos(ANGLE)
    keep = (uu ** 2 + vv ** 2 <= (R - d / 2) ** 2) & (normal + d / 2 <= 0)
    u, v, depth = uu[keep], vv[keep], -normal[keep]
    p = np.stack([np.repeat(u, len(ys)), np.tile(ys, len(u)), np.repeat(v, len(ys))], axis=1)
    depth = np.repeat(depth, len(ys))
    speed = np.where(depth < LAYER, SPEED * (1 - depth / LAYER), -0.02)
    vel = np.zeros_like(p)
    vel[:, 0], vel[:, 2] = speed * math.cos(ANGLE), speed * math.sin(ANGLE)
    n = len(p)
    return ParticleFrame(Path("bed.vtu"), 0, 0.0, np.arange(1, n + 1), np.ones(n, np.int32),
                         p, vel, np.full(n, d / 2), None)


def geometry(d: float) -> DrumGeometry:
    return DrumGeometry(radius=R, axis="y", omega=OMEGA, d_mean=d, strip=STRIP)


def test_the_synthetic_bed_is_what_the_docstring_says():
    """The numbers quoted above: the surface below the grain tops and today's thickness."""
    thick, offsets = [], []
    for d in (0.001, 0.002, 0.003):
        frame, geo = bed(d), geometry(d)
        u, v, _, _ = cross_section(frame, geo)
        s = fit_surface(u, v, frame.radii, R, d, rising_side(geo), strip=STRIP)
        offsets.append(s.offset)
        thick.append(frame_flow(frame, geo).flowing_layer_thickness)
        assert abs(abs(s.angle_deg) - 35.0) < 0.5
    assert np.allclose(offsets, [-0.07e-3, -0.41e-3, -0.65e-3], atol=0.02e-3)
    assert np.allclose(thick, [8.76e-3, 7.70e-3, 7.52e-3], atol=0.02e-3)


@pytest.mark.xfail(strict=True, reason="issue 44 item 1: the flowing layer's thickness "
                   "moves with the grain size (8.76 / 7.70 / 7.52 mm for one 8 mm layer)")
def test_one_layer_reads_the_same_at_every_grain_size():
    thick = [frame_flow(bed(d), geometry(d)).flowing_layer_thickness
             for d in (0.001, 0.002, 0.003)]
    assert max(thick) - min(thick) <= 0.3e-3 and all(abs(t - LAYER) <= 0.5e-3 for t in thick)
