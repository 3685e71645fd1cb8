"""The profile's simulated fail test (issue 45 item 2, the fifth verdict_rates run,
``docs/results/verdict_rates/profiles_2.txt``): a seeded parametric bootstrap of the bins'
F ratio under the runs' own covariance of bins, where the two-moment noncentral F with an
estimated k_e failed profiles wrongly on correlated bins."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from benchmarks.profile_designs import profile_runs, shifted_studies
from ligwf.inference import equivalence as eq
from tests.inference.test_never_crash import CRASH, forty_six_against_forty_six
from ligwf.inference.deciding import profile_plan


def test_one_bin_of_equal_variances_is_the_noncentral_f():
    """One bin, equal arms with equal variances: the ratio is exactly noncentral
    F(1, 2 (R - 1)); the simulated fail p agrees with scipy's within its Monte Carlo error."""
    x = np.array([[0.0], [1.0], [2.0]]) + 1.5
    y = np.array([[0.0], [1.0], [2.0]])
    v = 2 * 1.0 / 3                                  # each arm's variance 1, 3 runs
    ref = 1.0                                        # |mean(y)|
    for budget in (0.2, 0.6, 1.0):
        nc = (budget * ref) ** 2 / v
        exact = float(stats.ncf.sf(1.5 ** 2 / v, 1, 4, nc))
        got = eq.norm_fail_p(x, y, budget, eq.BINS_SIMULATED)
        assert got == pytest.approx(exact, abs=4 * math.sqrt(exact * (1 - exact) / 2000) + 1e-3)


def test_the_same_runs_give_the_same_bounds_and_the_fail_p_agrees_with_them():
    rng = np.random.default_rng(4)
    for _ in range(20):
        x = 1.0 + 0.3 + profile_runs(rng, 1, 4, 1.0, 12)[0]
        y = 1.0 + profile_runs(rng, 1, 4, 1.0, 12)[0]
        e = eq.norm_estimate(x, y, bins=eq.BINS_SIMULATED)
        assert e == eq.norm_estimate(x, y, bins=eq.BINS_SIMULATED)
        assert 0.0 <= e.lo <= e.hi and math.isfinite(e.hi)
        # the upper bound is the correlated rule's
        assert e.hi == eq.norm_estimate(x, y, bins=eq.BINS_CORRELATED).hi
        for budget in (0.5 * e.lo, 0.999 * e.lo, 1.001 * e.lo + 1e-9, 2 * e.lo + 0.05):
            p = eq.norm_fail_p(x, y, budget, eq.BINS_SIMULATED)
            if e.lo < e.hi:   # (a lower bound clipped to the upper says nothing here)
                assert (p <= eq.ALPHA) == (budget < e.lo), (budget, e.lo, p)


def test_correlated_bins_on_the_budget_fail_wrongly_less_often_than_the_old_rule():
    """3 and 3 runs whose bins share their errors (the measured kernel width 12), the true
    distance on the budget: the correlated rule's fail p is below alpha more often than
    alpha (the fourth run: up to 0.065), the simulated one's is not."""
    rng = np.random.default_rng(20261207)
    trials = 600
    a, b, truth = shifted_studies(rng, trials, 3, 3, 3.0, 12)
    old = sum(eq.norm_fail_p(a[i], b[i], truth, eq.BINS_CORRELATED) <= eq.ALPHA
              for i in range(trials))
    new = sum(eq.norm_fail_p(a[i], b[i], truth, eq.BINS_SIMULATED) <= eq.ALPHA
              for i in range(trials))
    assert old / trials > eq.ALPHA
    assert new / trials <= eq.ALPHA and new < old


def test_the_crash_inputs_give_bounds_a_fail_p_and_a_plan():
    d = np.load(CRASH)
    x, y, k = d["x"], d["y"], int(d["k"])
    p = eq.norm_estimate(x, y, 0.05, add=(k, k), bins=eq.BINS_SIMULATED)
    assert p.has_interval and p.lo <= p.hi
    assert 0.0 <= eq.norm_fail_p(x, y, 0.1, eq.BINS_SIMULATED) <= 1.0
    assert profile_plan(x, y, 0.1, 0.05, (3600.0, 7200.0)).get("decide_by") == "replicas"
    x, y = forty_six_against_forty_six()
    e = eq.norm_estimate(x, y, 0.05, bins=eq.BINS_SIMULATED)
    assert e.has_interval and e.lo <= e.raw <= e.hi
    assert 0.0 <= eq.norm_fail_p(x, y, 0.1, eq.BINS_SIMULATED) <= 1.0


def test_no_noise_and_identical_profiles_never_give_nan():
    x = np.tile(np.arange(16.0, 0.0, -1.0), (3, 1))     # no noise at all, exactly
    e = eq.norm_estimate(x, x + 1.0, bins=eq.BINS_SIMULATED)
    assert e.lo == e.hi == pytest.approx(e.raw)
    rng = np.random.default_rng(1)
    y = x + 0.01 * rng.standard_normal(x.shape)
    e = eq.norm_estimate(y, y, bins=eq.BINS_SIMULATED)
    assert e.lo == 0.0 and math.isfinite(e.hi)
    assert eq.norm_fail_p(y, y, 0.1, eq.BINS_SIMULATED) == 1.0


def test_the_verdict_uses_the_simulated_fail_test_and_says_so():
    from ligwf.inference.verdict_statistics import method_text, statistics_record
    stats_record = statistics_record(0.05, eq.WELCH_BF)
    assert stats_record["profile_bins"] == eq.PROFILE_BINS == eq.BINS_SIMULATED_FIDUCIAL
    text = method_text(stats_record)
    assert "null simulated" in text and "profiles_4.txt" in text
