"""ligwf.analysis.granules.bridge_law.relative_energy: the bridge's relative rupture work, the edge
weight of the default granule definition. Compiled and numpy paths agree; the quadrature
is exact where the answer is known in closed form; the weight is CG-neutral under both
scaling rules and grows with the bridge volume (what makes the granules respond to the
liquid content)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import toy_constant  # noqa: F401  (registers the constant-force toy model)
from ligwf.analysis.granules.bridge_law import Liquid, relative_energy, work_limits
from ligwf.analysis.frames.dumps import ParticleFrame

THETA = math.radians(30.0)


def frame(radii, content) -> ParticleFrame:
    n = len(radii)
    return ParticleFrame(Path("synthetic"), 0, float("nan"), np.arange(1, n + 1),
                         np.ones(n, np.int32), np.zeros((n, 3)), np.zeros((n, 3)),
                         np.asarray(radii, float), np.full(n, content))


def pairs(n_pairs: int, rng, scale: float = 1.0):
    """Random pairs of radii 0.5-2 mm x scale and gaps from overlap to beyond rupture."""
    radii = rng.uniform(0.5e-3, 2e-3, 2 * n_pairs) * scale
    i, j = np.arange(0, 2 * n_pairs, 2), np.arange(1, 2 * n_pairs, 2)
    gap = rng.uniform(-5e-6, 40e-6, n_pairs) * scale
    return radii, i, j, gap


def bonds(model: str, n_pairs: int, seed: int):
    """(frame, liquid, radii, i, j, gap, lo, hi) of the random pairs that hold a bridge
    (gap below the rupture gap of ``model``): only bonds are weighed."""
    radii, i, j, gap = pairs(n_pairs, np.random.default_rng(seed))
    liquid = Liquid(model, 0.024, THETA, 0.02)
    p = frame(radii, 0.02)
    lo, hi, _ = work_limits(p, i, j, gap, liquid)
    keep = gap < hi
    return p, liquid, radii, i[keep], j[keep], gap[keep], lo[keep], hi[keep]


@pytest.mark.parametrize("model", ["washino", "easo"])
def test_compiled_equals_numpy(model):
    p, liquid, _, i, j, gap, _, _ = bonds(model, 2000, 4)
    fast = relative_energy(p, i, j, gap, liquid, "fast")
    ref = relative_energy(p, i, j, gap, liquid, "reference")
    assert len(i) > 500 and np.all(fast > 0)
    np.testing.assert_allclose(fast, ref, rtol=1e-12, atol=0)


def test_constant_force_integrates_exactly():
    """F = 2 pi R* gamma cos(theta) up to rupture: e_rel = (s_rupture - max(gap, 0)) / R*."""
    p, liquid, radii, i, j, gap, _, hi = bonds("toy_constant", 300, 5)
    r_eff = radii[i] * radii[j] / (radii[i] + radii[j])
    expected = (hi - np.maximum(gap, 0.0)) / r_eff
    for impl in ("fast", "reference"):
        got = relative_energy(p, i, j, gap, liquid, impl)
        np.testing.assert_allclose(got, expected, rtol=1e-12)


def test_quadrature_converged():
    """16 nodes: within 1e-6 of the same integral on 4x finer sub-intervals (washino law)."""
    from ligwf.analysis.granules import bridge_law

    p, liquid, _, i, j, gap, lo, hi = bonds("washino", 500, 6)
    e16 = relative_energy(p, i, j, gap, liquid, "reference")
    # the same integral as four pieces [lo + k (hi - lo) / 4, ...], each from its own gap
    total = np.zeros(len(i))
    for k in range(4):
        a, b = lo + k * (hi - lo) / 4, lo + (k + 1) * (hi - lo) / 4
        total += (relative_energy(p, i, j, a, liquid, "reference")
                  - relative_energy(p, i, j, b, liquid, "reference"))
    np.testing.assert_allclose(e16, total, rtol=1e-6)
    assert bridge_law.WORK_NODES == 16


@pytest.mark.parametrize("rule, gamma_power", [("weber", 1), ("bond", 2)])
def test_cg_neutral_under_both_rules(rule, gamma_power):
    """CG-n: radii and gaps x n, surface tension x n (Weber) or x n^2 (Bond), the same
    contact angle and liquid content: the same relative work for every pair."""
    rng = np.random.default_rng(7)
    radii, i, j, gap = pairs(500, rng)
    base = Liquid("washino", 0.024, THETA, 0.02)
    e1 = relative_energy(frame(radii, 0.02), i, j, gap, base)
    for n in (2, 3):
        scaled = Liquid("washino", 0.024 * n ** gamma_power, THETA, 0.02)
        en = relative_energy(frame(radii * n, 0.02), i, j, gap * n, scaled)
        np.testing.assert_allclose(en, e1, rtol=1e-9)


def test_grows_with_liquid_content():
    """More liquid: a longer rupture gap and more work for the same touching pair, while the
    touching force stays 2 pi R* gamma cos(theta) (why the force weight cannot tell)."""
    radii, i, j, gap = np.full(2, 0.75e-3), np.array([0]), np.array([1]), np.zeros(1)
    works = [float(relative_energy(frame(radii, lc), i, j, gap,
                                   Liquid("washino", 0.024, THETA, lc))[0])
             for lc in (0.001, 0.01, 0.02, 0.04)]
    assert all(a < b for a, b in zip(works, works[1:])), works
    assert works[-1] / works[0] > 3.0


def test_dry_pairs_weigh_nothing():
    p = frame(np.full(2, 1e-3), 0.0)
    out = relative_energy(p, np.array([0]), np.array([1]), np.zeros(1),
                          Liquid("none", 0.0, THETA, 0.0))
    np.testing.assert_array_equal(out, [0.0])
