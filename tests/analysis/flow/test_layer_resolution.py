"""The flowing layer's thickness does not move with the grain size (issue 44 item 1).

Synthetic beds of 1, 2 and 3 mm grains carry one flow: touching spheres on a square lattice
whose centres lie below a flat 35 deg plane through the drum axis (the same mass per unit
area above any depth at every size), with a downhill speed falling linearly with the
centres' depth below the plane, through zero at LAYER = 6 mm; each size on three lattice
positions (moved by 0, 1/3 and 2/3 of a grain), since a lattice quantises the mass above a
depth by up to a grain.

Measured here: the former estimator (from the fitted surface down to a zero crossing
interpolated between depth-bin centres, ``scripts/layer_resolution.former_thickness``) read 6.38 / 6.57 / 6.65 mm
on the unmoved lattices: it measures from a surface fitted to the strip tops, which sits
0.38 / 0.57 / 0.58 mm above the centres' plane and so grows with the grains. Today's
estimator (:func:`ligwf.analysis.flow.frame.frame_flow`: the crossing at the bins' mean
particle depths, and the thickness mass-equivalent, the layer's grain volume over the bed's
own packing) has no surface in it. On real frames of two studies the same change shrinks
every coarser level's difference from the finest (docs/results/layer_resolution,
tests/report/test_committed_layer_resolution.py)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from ligwf.analysis.flow import frame as fl
from ligwf.analysis.frames.dumps import ParticleFrame
from tests.helpers import ROOT

sys.path.insert(0, str(ROOT / "scripts"))
from layer_resolution import former_thickness  # noqa: E402

R, LENGTH, OMEGA, ANGLE, LAYER, SPEED = 0.05, 0.012, 2.0, math.radians(35.0), 0.006, 0.3
STRIP = 0.006   # the study's one resolution: twice the coarsest (3 mm) diameter
SIZES = (0.001, 0.002, 0.003)


def bed(d: float, shift: float = 0.0) -> ParticleFrame:
    """Touching spheres of diameter d on a square lattice (moved by ``shift`` x d) whose
    centres lie below a plane through the drum axis at 35 deg, downhill speed
    SPEED (1 - depth / LAYER) at a centre's depth below the plane."""
    g = np.arange(-R + d / 2, R, d) + shift * d
    per = max(1, int(round(LENGTH / d)))
    ys = (np.arange(per) + 0.5) * LENGTH / per
    uu, vv = (a.ravel() for a in np.meshgrid(g, g))
    normal = -uu * math.sin(ANGLE) + vv * math.cos(ANGLE)
    keep = (uu ** 2 + vv ** 2 <= (R - d / 2) ** 2) & (normal <= 1e-12)
    u, v, depth = uu[keep], vv[keep], -normal[keep]
    p = np.stack([np.repeat(u, len(ys)), np.tile(ys, len(u)), np.repeat(v, len(ys))], axis=1)
    speed = SPEED * (1.0 - np.repeat(depth, len(ys)) / LAYER)
    vel = np.zeros_like(p)
    vel[:, 0], vel[:, 2] = speed * math.cos(ANGLE), speed * math.sin(ANGLE)
    n = len(p)
    return ParticleFrame(Path("bed.vtu"), 0, 0.0, np.arange(1, n + 1), np.ones(n, np.int32),
                         p, vel, np.full(n, d / 2), None)


def geometry(d: float) -> fl.DrumGeometry:
    return fl.DrumGeometry(radius=R, axis="y", omega=OMEGA, d_mean=d, strip=STRIP)


SHIFTS = (0.0, 1.0 / 3.0, 2.0 / 3.0)


def test_the_former_estimator_read_the_surface_into_the_layer():
    """What the docstring quotes, so the test below is shown able to fail."""
    former = [former_thickness(bed(d), geometry(d)) for d in SIZES]
    assert np.allclose(former, [6.38e-3, 6.57e-3, 6.65e-3], atol=0.02e-3)
    means = [np.mean([former_thickness(bed(d, sh), geometry(d)) for sh in SHIFTS])
             for d in SIZES]
    assert max(abs(m - LAYER) for m in means) > 0.35e-3


def test_one_layer_reads_the_same_at_every_grain_size():
    """Each size's mean over the lattice positions within 0.2 mm of the layer, each bed
    within 0.3 mm (a twelfth of the coarsest grain: the lattice's quantisation)."""
    thick = {d: [fl.frame_flow(bed(d, sh), geometry(d)).flowing_layer_thickness
                 for sh in SHIFTS] for d in SIZES}
    assert all(abs(np.mean(t) - LAYER) <= 0.2e-3 for t in thick.values()), thick
    assert all(abs(x - LAYER) <= 0.3e-3 for t in thick.values() for x in t), thick
    flows = [fl.frame_flow(bed(d), geometry(d)) for d in SIZES]
    assert all(abs(abs(f.angle_of_repose) - 35.0) < 0.5 for f in flows)
