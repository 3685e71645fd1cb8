"""The field criterion's statistics (ligwf.inference.field_errors.layer_norm and the
drum frame): exact on noiseless fields, no bounds from one run, and bounds that hold at
least 95 % of the time on synthetic noisy fields whose true distance is known, for
independent nodes and for nodes that move together (the case the bound is built for)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ligwf.analysis.flow.frame import DrumGeometry, rigid_rotation_velocity
from ligwf.analysis.frames.dumps import ParticleFrame
from ligwf.inference.field_errors import layer_norm, rotation_velocity
from ligwf.analysis.records.fields import FieldGrid

TRIALS = 1000
NODES = 40


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_drum_frame_rotation_matches_the_rigid_block_share(axis):
    """omega x r on the grid is the rotation the rigid-block share subtracts (the (u, v)
    plane of axis y is left-handed: a 2-D formula would turn it the wrong way)."""
    grid = FieldGrid(origin=-0.02, spacing=0.01, nodes=5, width=0.01, length=0.01, axis=axis)
    ru, rv = rotation_velocity(grid, 3.0)
    c = grid.coordinates()
    uu, vv = np.meshgrid(c, c)
    ia, iu, iv = {"x": (0, 1, 2), "y": (1, 0, 2), "z": (2, 0, 1)}[axis]
    p = np.zeros((uu.size, 3))
    p[:, iu], p[:, iv] = uu.ravel(), vv.ravel()
    n = len(p)
    frame = ParticleFrame(Path("f.vtu"), 0, 0.0, np.arange(1, n + 1), np.ones(n, np.int32), p,
                          np.zeros((n, 3)), np.full(n, 1e-3), None)
    eu, ev = rigid_rotation_velocity(frame, DrumGeometry(0.02, axis, 3.0, 1e-3))
    assert np.allclose(ru.ravel(), eu) and np.allclose(rv.ravel(), ev)


def test_noiseless_distance_is_exact_and_one_run_has_no_bounds():
    w = np.array([1.0, 3.0])
    ref = np.zeros((2, 2, 2))
    runs = np.zeros((2, 2, 2))
    runs[:, 0, :] = [0.1, 0.3]          # u differs by 0.1 and 0.3 at the two nodes
    e = layer_norm(runs, ref, w, 2.0)
    exact = math.sqrt((1 * 0.1**2 + 3 * 0.3**2) / 4) / 2.0
    assert e.value == pytest.approx(exact) and e.raw == pytest.approx(exact)
    assert e.lo == pytest.approx(exact) and e.hi == pytest.approx(exact)
    one = layer_norm(runs[:1], ref, w, 2.0)
    assert one.raw == pytest.approx(exact) and not one.has_interval
    assert math.isnan(layer_norm(runs, ref, np.zeros(2), 2.0).value)


@pytest.mark.parametrize("replicas", [2, 3])
@pytest.mark.parametrize("together", [False, True])
@pytest.mark.parametrize("distance", [0.0, 0.05])
def test_bounds_hold_95_percent(replicas, together, distance):
    """Each bound misses the true distance in at most 5 % of synthetic studies (+ 3
    standard errors of the count); the CG-n arm 3x noisier than CG1's."""
    rng = np.random.default_rng(11 + replicas + 2 * together)
    w = rng.uniform(0.5, 1.5, NODES)
    delta = np.zeros((2, NODES))
    delta[0] = distance                    # a uniform difference of the u component
    true = math.sqrt(np.sum(w / w.sum() * delta**2))
    shape = (replicas, 1, 1) if together else (replicas, 2, NODES)
    low = high = 0
    for _ in range(TRIALS):
        x = delta + 0.03 * rng.normal(size=shape) * np.ones((replicas, 2, NODES))
        y = 0.01 * rng.normal(size=shape) * np.ones((replicas, 2, NODES))
        e = layer_norm(x, y, w, 1.0)
        low += e.lo > true + 1e-12
        high += e.hi < true - 1e-12
    limit = 0.05 + 3 * math.sqrt(0.05 * 0.95 / TRIALS)
    assert low / TRIALS <= limit and high / TRIALS <= limit
