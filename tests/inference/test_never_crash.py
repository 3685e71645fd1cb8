"""Inputs that crashed the verdict (issue 45 item 4) give a verdict: scipy's ``ncf.cdf`` returns
nan at a noncentrality near 7,000, where the profile bounds' ``brentq`` raised.

- ``tests/data/profile_planner_crash.npz``: two arms of 3 per-run velocity profiles (16 depth
  bins; ``x`` CG-n, ``y`` CG1) near the profile budget 0.1 and undecided; copied from the
  review's regression material (``../shared/repro``): planning ``k`` = 62 more replicas of
  each arm raised ValueError.
- 46 runs against 46: equal per-bin variances (0.03^2, exactly: standardised noise) and a
  difference that puts the bound search's first bracket at a noncentrality where scipy
  returns nan.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from ligwf.inference import equivalence as eq
from ligwf.inference.deciding import profile_plan
from tests.helpers import ROOT

CRASH = ROOT / "tests" / "data" / "profile_planner_crash.npz"


def forty_six_against_forty_six() -> tuple[np.ndarray, np.ndarray]:
    """(CG-n, CG1) arms of 46 runs whose profile bounds raised: k_e = 16 bins, df_e = 1440,
    an observed F ratio of 96 (first bracket at noncentrality 6,144, inside scipy's nan
    band at these degrees of freedom)."""
    rng = np.random.default_rng(0)

    def arm(mean: np.ndarray) -> np.ndarray:
        z = rng.standard_normal((46, 16))
        return mean + 0.03 * (z - z.mean(axis=0)) / z.std(axis=0, ddof=1)

    ref = np.linspace(1.0, -0.5, 16)
    v = 2 * 0.03 ** 2 / 46                     # each bin's noise of the difference
    shift = math.sqrt(96.0 * 16 * v / 16)      # per bin: ss / c / k_e = 96
    return arm(ref + shift), arm(ref)


def test_scipy_gives_nan_where_the_bounds_search():
    # the failure this guards against; our cdf is finite and tiny there
    assert math.isnan(stats.ncf.cdf(96.0, 16.0, 1440.0, 6144.0))
    value = eq.noncentral_f_cdf(96.0, 16.0, 1440.0, 6144.0)
    assert 0.0 <= value < 1e-20          # (the normal stand-in: far below any alpha)
    # and it agrees with scipy where scipy answers
    for nc in (10.0, 500.0, 1600.0):
        assert eq.noncentral_f_cdf(100.0, 16.0, 1440.0, nc) == stats.ncf.cdf(100.0, 16.0,
                                                                             1440.0, nc)


def test_the_repro_input_plans_without_raising():
    d = np.load(CRASH)
    x, y, k = d["x"], d["y"], int(d["k"])
    assert x.shape == y.shape == (3, 16) and k == 62
    p = eq.norm_estimate(x, y, 0.05, add=(k, k))
    assert p.has_interval and p.lo <= p.value <= p.hi
    now = eq.norm_estimate(x, y, 0.05)
    assert eq.norm_decision(now, 0.1) == eq.UNDECIDED     # the repro is near the budget
    plan = profile_plan(x, y, 0.1, 0.05, (3600.0, 7200.0))
    assert plan.get("decide_by") == "replicas" and plan["decide_amount"] >= 1


def test_forty_six_runs_against_forty_six_get_bounds_and_a_decision():
    x, y = forty_six_against_forty_six()
    e = eq.norm_estimate(x, y, 0.05)
    assert e.has_interval and e.lo <= e.raw <= e.hi
    assert eq.norm_decision(e, 0.1) in (eq.PASS, eq.FAIL, eq.UNDECIDED)
    assert 0.0 <= eq.norm_fail_p(x, y, 0.1) <= 1.0


@pytest.mark.parametrize("rule", [eq.BINS_SIMULATED_UPPER, eq.BINS_SIMULATED_FIDUCIAL])
def test_the_crash_inputs_and_no_noise_give_bounds_under_the_simulated_upper_bounds(rule):
    """The measured upper-bound rules (the sixth run's smaller bound, the seventh run's
    fiducial one) on the same inputs: the repro and 46 against 46 get bounds, and two arms
    without noise get the observed distance as both bounds."""
    d = np.load(CRASH)
    x, y, k = d["x"], d["y"], int(d["k"])
    p = eq.norm_estimate(x, y, 0.05, add=(k, k), bins=rule)
    assert p.has_interval and p.lo <= p.hi
    x, y = forty_six_against_forty_six()
    e = eq.norm_estimate(x, y, 0.05, bins=rule)
    assert e.has_interval and e.lo <= e.raw <= e.hi
    x = np.tile(np.arange(16.0, 0.0, -1.0), (3, 1))
    e = eq.norm_estimate(x, x + 1.0, bins=rule)
    assert e.lo == e.hi == pytest.approx(e.raw)
