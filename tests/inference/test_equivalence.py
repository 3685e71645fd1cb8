"""ligwf.inference.equivalence: Welch against scipy's own test, the two one-sided
tests at their edges, Holm's step-down, the noise-corrected profile distance, the
replicas that would decide, and the coverage the verdict relies on, measured on a few
cells of benchmarks/bench_coverage.py (the full grid is the benchmark)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from benchmarks.bench_coverage import cell, norm_cell
from ligwf.inference import equivalence as eq


def test_welch_interval_matches_scipy():
    x, y = np.array([42.0, 42.2, 41.9, 42.4]), np.array([40.0, 40.2, 39.8])
    e = eq.difference_estimate(x, y, alpha=0.025)
    res = stats.ttest_ind(x, y, equal_var=False)
    ci = res.confidence_interval(0.95)
    assert e.value == pytest.approx(x.mean() - y.mean())
    assert (e.lo, e.hi) == (pytest.approx(ci.low), pytest.approx(ci.high))
    assert e.df == pytest.approx(res.df)
    m = eq.mean_estimate(x, alpha=0.025)
    lo, hi = stats.t.interval(0.95, 3, loc=x.mean(), scale=stats.sem(x))
    assert (m.lo, m.hi) == (pytest.approx(lo), pytest.approx(hi))


def test_one_run_or_nan_gives_no_interval():
    assert not eq.difference_estimate([1.0], [1.0, 2.0]).has_interval
    assert not eq.mean_estimate([1.0, math.nan]).has_interval
    assert math.isnan(eq.difference_estimate([], [1.0, 2.0]).value)
    assert eq.equivalence(eq.difference_estimate([1.0], [1.0, 2.0]), 1.0).state == eq.UNDECIDED


def test_two_one_sided_tests_at_their_edges():
    e = eq.Estimate(0.5, -0.2, 1.2, 0.3, 10.0)
    assert eq.equivalence(e, 1.0).state == eq.UNDECIDED
    assert eq.equivalence(e, 1.3).state == eq.PASS
    assert eq.equivalence(eq.Estimate(-2.0, -2.5, -1.5, 0.2, 10.0), 1.0).state == eq.FAIL
    t = eq.equivalence(eq.Estimate(2.0, 1.5, 2.5, 0.2, 10.0), 1.0)
    # the fail test's p covers both tails of |delta| <= 1 (at delta = +1 and at -1)
    assert t.state == eq.FAIL and t.p_fail == pytest.approx(
        1 - stats.t.cdf(5.0, 10) + stats.t.cdf(-15.0, 10))
    assert eq.equivalence(eq.Estimate(2.0, 1.5, 2.5, 0.2, 10.0), 1.0, fail_sides=1
                          ).p_fail == pytest.approx(1 - stats.t.cdf(5.0, 10))
    # pass <=> the larger one-sided p is below alpha (the interval is the 90 % one)
    se, df = 0.3, 6.0
    half = stats.t.ppf(0.95, df) * se
    edge = eq.Estimate(1.0 - half, 1.0 - 2 * half, 1.0, se, df)
    assert eq.equivalence(edge, 1.0).p_pass == pytest.approx(0.05)
    # zero variance (all runs equal): decided by the value
    assert eq.equivalence(eq.difference_estimate([0, 0], [0, 0]), 0.05).state == eq.PASS


def test_holm_step_down():
    assert eq.holm_rejects([0.01, 0.04, math.nan]) == [True, True, False]   # 0.01 <= .025
    assert eq.holm_rejects([0.03, 0.04]) == [False, False]                  # 0.03 > 0.025
    assert eq.holm_rejects([0.001, 0.03, 0.2]) == [True, False, False]
    assert eq.holm_rejects([]) == []


def test_profile_distance_is_noise_corrected_and_its_bounds_hold_the_truth():
    rng = np.random.default_rng(3)
    base = np.array([1.0, 0.8, 0.5, 0.2])
    y = base + 0.05 * rng.standard_normal((3, 4))
    x = base + 0.05 * rng.standard_normal((3, 4))
    e = eq.norm_estimate(x, y)
    assert e.value < e.raw                     # the noise of both arms taken off
    assert e.lo == 0.0 and 0.0 <= e.hi < 0.1   # no difference: bounded well inside 0.1
    noisy = eq.norm_estimate(x + 0.2 * rng.standard_normal((3, 4)), y)
    assert noisy.lo == 0.0 < noisy.hi and noisy.hi >= noisy.value
    far = eq.norm_estimate(x + 0.5, y)
    truth = 0.5 * 2 / np.sqrt(np.sum(base**2))
    assert far.lo <= truth <= far.hi and eq.norm_decision(far, 0.1) == eq.FAIL
    assert math.isnan(eq.norm_estimate(x[:1], y).lo)
    assert math.isnan(eq.norm_estimate(np.zeros((2, 0)), y).value)


@pytest.mark.parametrize("R,frames,phi,offset", [(2, 50, 0.9, 3.0), (2, 10, 0.3, 0.0),
                                                 (3, 200, 0.6, 1.0)])
def test_coverage_on_synthetic_studies(R, frames, phi, offset):
    """400 synthetic studies a cell: the 95 % intervals cover within [0.92, 0.99] (binomial
    sd ~0.011), the TOST bound's one-sided coverage too, a difference on the budget passes
    at most ~5 %, and the profile distance's upper bound (noncentral F) covers within
    [0.92, 0.99] as well (the box of bin-wise intervals it replaced covered 1.00: too wide)."""
    rng = np.random.default_rng(11)
    c = cell(rng, 400, R, frames, phi, offset)
    for k in ("value", "diff", "tost"):
        assert 0.92 <= c[k] <= 0.99, (k, c[k])
    assert c["wrong pass"] <= 0.08
    n = norm_cell(rng, 400, R, frames, phi, offset)
    assert 0.92 <= n["norm"] <= 0.99 and n["norm bias"] < n["norm raw"], n
