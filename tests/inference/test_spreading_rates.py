"""CG-n / CG1 spreading rates (ligwf.inference.spreading): a known n^2 speed-up is found
with its exponent; a level that spreads like CG1 is not called faster; censored runs make
the ratio a bound; the Welch interval on log times covers near its level."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from ligwf.inference.spreading import (case_times, level_rates, replica_spread,
                                       welch_log_ratio)


def flow_case(case_id, cg, replica, tau, revs=6.0, frames=1201, group="g"):
    """A case whose dry share rises as 1 - exp(-t / tau) (reaches 0.25 at tau ln 4/3)."""
    r = np.linspace(0.0, revs, frames)
    share = 1.0 - np.exp(-r / tau)
    return SimpleNamespace(case_id=case_id, cg=cg, rule="weber" if cg > 1 else "none",
                           replica=replica, group=group,
                           spreading={"revolutions": list(r), "dry_content_share": list(share),
                                      "dry_wet_share": list(np.minimum(1, 2 * share)),
                                      "dry_particles": 90, "particles": 100})


def study(taus_by_level):
    return [flow_case(f"cg{cg:g}-r{k}", cg, k, tau)
            for cg, taus in taus_by_level.items() for k, tau in enumerate(taus)]


def test_an_n_squared_speedup_is_found_with_exponent_two():
    tau1 = np.array([2.0, 2.2, 1.9])
    cases = case_times(study({1.0: tau1, 2.0: tau1 / 4, 3.0: tau1[::-1] / 9}))
    assert cases.t_spread_rev.iloc[0] == pytest.approx(2.0 * math.log(4 / 3), rel=1e-3)
    levels = level_rates(cases).set_index("cg")
    assert levels.loc[2.0, "rate_ratio"] == pytest.approx(4.0, rel=0.01)
    assert levels.loc[3.0, "exponent"] == pytest.approx(2.0, abs=0.01)
    assert levels.contains_expected.all() and levels.above_one.all()
    assert not levels.is_bound.any()
    assert levels.loc[2.0, "cg1_spread"] == pytest.approx(2.2 / 1.9, rel=0.01)


def test_a_level_that_spreads_like_cg1_is_not_called_faster():
    cases = case_times(study({1.0: [2.0, 2.3, 1.8], 2.0: [2.1, 1.7, 2.4]}))
    row = level_rates(cases).iloc[0]
    assert row.rate_ratio_low < 1.0 < row.rate_ratio_high
    assert not row.above_one and not row.contains_expected


def test_a_run_that_never_reaches_the_level_makes_the_ratio_a_bound():
    cases = case_times(study({1.0: [200.0, 2.0, 2.0], 2.0: [0.5, 0.5, 0.6]}))
    assert cases[cases.cg == 1.0].censored.tolist() == [True, False, False]
    assert level_rates(cases).iloc[0].is_bound


def test_cases_without_placed_liquid_are_left_out():
    dry = SimpleNamespace(case_id="d", cg=1.0, rule="none", replica=0, group="g",
                          spreading={})
    assert case_times([dry]).empty
    assert level_rates(case_times([dry])).empty


def test_one_run_arms_give_no_interval_and_the_replica_spread_is_a_ratio():
    ratio, low, high, df = welch_log_ratio([2.0], [1.0, 1.1])
    assert ratio == pytest.approx(2.0 / math.sqrt(1.1)) and math.isnan(low)
    assert replica_spread([1.0, 3.0, 2.0]) == 3.0 and replica_spread([]) != replica_spread([])


def test_welch_interval_on_log_times_covers_near_its_level_with_three_runs_each():
    """Log-normal run-to-run noise, 3 against 3 runs, a true ratio of 4: the 95 % interval
    covers it in 0.93-0.97 of 4,000 studies (Welch is slightly liberal there)."""
    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(4000):
        a = np.exp(rng.normal(math.log(2.0), 0.15, 3))
        b = np.exp(rng.normal(math.log(0.5), 0.3, 3))
        _, low, high, _ = welch_log_ratio(a, b)
        hits += low <= 4.0 <= high
    assert 0.93 <= hits / 4000 <= 0.97
