"""The extrapolated CG1 reference (ligwf.inference.extrapolation): the fit's arithmetic on
hand-checkable ladders, the form's checks on lines and on curves, and the verdict's
contrast (the level judged is part of its own reference)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ligwf.inference import extrapolation as ex


def ladder(means: dict[float, float], spread: float = 0.3, runs: int = 4) -> dict:
    """Run values around each level's mean, the same symmetric spread at every level."""
    offsets = np.linspace(-spread, spread, runs)
    return {n: m + offsets for n, m in means.items()}


def test_two_levels_is_the_richardson_line():
    """CG2 and CG3: theta_1 = 2 m2 - m3, and the form cannot be checked."""
    e = ex.extrapolate(ladder({2: 40.5, 3: 42.1}), 0.02)
    assert e.value == pytest.approx(2 * 40.5 - 42.1)
    assert e.weights == pytest.approx((2.0, -1.0))
    assert e.slope == pytest.approx(1.6)
    assert e.form == ex.UNCHECKED and math.isnan(e.lack_of_fit_p)
    assert "unchecked" in e.form_text


def test_weights_reproduce_a_line_exactly():
    """Any line through the levels is extrapolated to its own value at n = 1."""
    for ns in ((2.0, 3.0, 4.0), (3.0, 4.0, 6.0), (2.0, 5.0)):
        w = ex.weights(np.array(ns))
        assert w.sum() == pytest.approx(1.0)
        assert np.dot(w, np.array(ns) - 1.0) == pytest.approx(0.0, abs=1e-12)


def test_three_levels_on_a_line_pass_the_check():
    e = ex.extrapolate(ladder({3: 39.0, 4: 39.5, 6: 40.5}), 1 / 200, alpha=0.025)
    assert e.value == pytest.approx(38.0)
    assert e.form == ex.CHECKED and e.lack_of_fit_p > 0.5
    assert e.observed_order == pytest.approx(1.0, abs=1e-4)
    assert e.lo < 38.0 < e.hi


def test_a_curve_fails_the_check():
    """A relation that saturates (Bond's rigid block) is not a line: rejected."""
    e = ex.extrapolate(ladder({2: 46.0, 3: 47.5, 4: 47.7}, spread=0.1), 0.02)
    assert e.form == ex.REJECTED and e.lack_of_fit_p < 0.01
    assert "rejected" in e.form_text


def test_observed_order_of_a_power_law():
    means = {n: 38.0 + 2.0 * (n - 1.0) ** 1.5 for n in (2.0, 3.0, 4.0)}
    e = ex.extrapolate(ladder(means, spread=0.01), 0.02)
    assert e.observed_order == pytest.approx(1.5, abs=1e-3)


def test_one_run_a_level_has_no_interval():
    e = ex.extrapolate({2: [40.0], 3: [41.0, 41.4]}, 0.02)
    assert math.isfinite(e.value) and not e.has_interval


def test_fewer_than_two_levels_is_no_extrapolation():
    assert not math.isfinite(ex.extrapolate({2: [40.0, 40.5]}, 0.02).value)
    # CG1 is never one of the levels it extrapolates from
    assert not math.isfinite(ex.extrapolate({1: [38.0, 38.2], 2: [40, 40.5]}, 0.02).value)


def test_the_model_term_grows_with_the_extrapolation_distance():
    """The same noise and slope: the source drum (d / D = 1/200) against a small drum (1/25)
    extrapolating from CG2-4: the prior's bias term is larger where x spans more."""
    small = ex.extrapolate(ladder({2: 41.0, 3: 44.0, 4: 47.0}), 1 / 25)
    large = ex.extrapolate(ladder({3: 39.0, 4: 39.5, 6: 40.5}), 1 / 200)
    assert small.model_term > 5 * large.model_term > 0
    # the angle passes the size relation's slope: the prior no longer follows the fit
    flat = ex.extrapolate(ladder({2: 41.0, 3: 41.0, 4: 41.0}), 1 / 25, slope_scale=4.0)
    assert flat.model_term > 0 and ex.extrapolate(ladder({2: 41.0, 3: 41.0, 4: 41.0}),
                                                  1 / 25).model_term == 0


def test_level_difference_is_the_contrast_with_its_own_level():
    values = ladder({2: 40.5, 3: 42.1}, spread=0.4)
    d = ex.level_difference(values, 3, 0.02)
    e = ex.extrapolate(values, 0.02)
    assert d.value == pytest.approx(42.1 - e.value)
    # m3 - (2 m2 - m3) = 2 (m3 - m2): its noise is twice the two levels' difference's
    v = sum(np.var(values[n], ddof=1) / len(values[n]) for n in (2, 3))
    assert d.se == pytest.approx(math.hypot(2 * math.sqrt(v), e.model_term))
    assert not math.isfinite(ex.level_difference(values, 4, 0.02).value)


def test_disagreement_of_two_rules():
    a = ex.extrapolate(ladder({2: 40.5, 3: 42.1}), 0.02)
    b = ex.extrapolate(ladder({2: 46.3, 3: 47.7}), 0.02)
    d = ex.disagreement(a, b)
    assert d.value == pytest.approx(a.value - b.value)
    assert d.hi < 0   # Bond's line does not reach Weber's CG1
    same = ex.disagreement(a, a)
    assert same.lo < 0 < same.hi
