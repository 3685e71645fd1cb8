"""ligwf.inference.sampling: what would decide an undecided criterion, and its cost.

The options are checked against the arithmetic of Welch's interval they rest on, the arm
they name against the arm whose scatter dominates, and the half-width they predict for a
longer production against the one measured after it on synthetic AR(1) runs (the issue's
+-30 %)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from benchmarks.bench_coverage import ar1_runs
from ligwf.inference import equivalence as eq
from ligwf.inference import sampling as sp


def test_replicas_of_the_wide_arm_decide_and_the_arithmetic_holds():
    cgn = sp.arm([41.5, 39.5, 43.5], replica_core_seconds=3600.0)       # wide
    cg1 = sp.arm([40.0, 40.2, 39.8], replica_core_seconds=36000.0)      # tight
    best = sp.cheapest(cgn, cg1, 1.5, 1.0)
    assert best.kind == sp.REPLICAS and best.arm == "CG-n"
    n = 3 + int(best.amount)
    vx, vy = np.var([41.5, 39.5, 43.5], ddof=1), np.var([40.0, 40.2, 39.8], ddof=1)
    se = math.sqrt(vx / n + vy / 3)
    assert stats.t.ppf(0.95, eq.welch_df(vx, n, vy, 3)) * se < 0.5      # decides ...
    se1 = math.sqrt(vx / (n - 1) + vy / 3)
    assert stats.t.ppf(0.95, eq.welch_df(vx, n - 1, vy, 3)) * se1 >= 0.5   # ... one fewer not
    assert best.core_hours == pytest.approx(best.amount)               # 1 core-h a replica
    assert sp.dominant_arm(cgn, cg1) == "CG-n"
    assert sp.cheapest(sp.arm([41.0]), cg1, 1.5, 1.0) is None


def test_the_issue_demo_angle_names_the_cg2_arm():
    """The demo's We-CG2 angle (issue 30): CG2 runs 50.4 and 43.5 deg, CG1 45.9 and 47.7:
    the width is the two CG2 replicas' scatter, not CG1 noise. A CG1 replica costs ~10
    CG2 ones."""
    cg2 = sp.arm([50.4, 43.5], replica_core_seconds=360.0)
    cg1 = sp.arm([45.9, 47.7], replica_core_seconds=3600.0)
    assert sp.dominant_arm(cg2, cg1) == "CG-n"
    best = sp.cheapest(cg2, cg1, 50.4 / 2 + 43.5 / 2 - 46.8, 1.0)
    # about 100 CG2 replicas (the issue's side-aware estimate), not 27 of CG1; CG1's one
    # degree of freedom takes a few CG1 runs beside them
    assert best.kind == sp.REPLICAS and best.amount >= 80, best
    assert best.amount > 5 * best.amount_cg1


def test_extension_when_the_frames_dominate_and_not_when_the_seeds_do():
    # run means scatter by 1.0 (variance); all of it within-run noise of 2 s windows
    values = [10.0, 11.0, 9.5, 10.5]
    noisy = sp.arm(values, within=[0.3] * 4, window=[2.0] * 4, steady_share=1.0,
                   replica_core_seconds=10 * 3600.0, production_core_seconds=3600.0)
    ref = sp.arm([10.1, 10.0, 9.9, 10.0], within=[0.01] * 4, window=[2.0] * 4,
                 steady_share=1.0, replica_core_seconds=10 * 3600.0,
                 production_core_seconds=3600.0)
    best = sp.cheapest(noisy, ref, 0.3, 1.0)
    assert best.kind == sp.EXTEND and best.arm == "CG-n"
    # the prediction: within part x W / (W + S)
    within, between = sp.components(noisy)
    assert within == pytest.approx(0.3) and between == pytest.approx(np.var(values, ddof=1) - 0.3)
    s = best.amount
    v = between + 0.3 * 2.0 / (2.0 + s)
    assert sp.run_variance(noisy, s) == pytest.approx(v)
    assert best.core_hours == pytest.approx(4 * s)        # 4 runs x s seconds x 1 core-h/s
    # the same scatter from the seeds (no within-run noise): only replicas help
    seeds = sp.arm(values, within=[0.0] * 4, window=[2.0] * 4, replica_core_seconds=3600.0,
                   production_core_seconds=3600.0)
    assert all(o.kind == sp.REPLICAS for o in sp.options(seeds, ref, 0.3, 1.0))


def test_predicted_half_width_after_an_extension_matches_the_measured_one():
    """AR(1) runs of 200 frames (phi 0.8, seed offsets of sd 0.3 frame sd), 3 runs an arm;
    the half-width predicted for 3x the production from the first 200 frames, against the
    one measured on the 800 frames: the median ratio within +-30 %, 4 in 5 studies too."""
    rng = np.random.default_rng(5)
    ratios = []
    for _ in range(60):
        x = ar1_runs(rng, 1, 3, 800, 0.8, 0.3)[0]
        y = ar1_runs(rng, 1, 3, 800, 0.8, 0.3)[0]

        def side(runs, frames):
            part = runs[:, :frames]
            return sp.arm(part.mean(axis=1), [sp.within_variance(r) for r in part],
                          [float(frames)] * 3, steady_share=1.0)
        predicted = sp.half_width(side(x, 200), side(y, 200), extend=(600.0, 600.0))
        measured = sp.half_width(side(x, 800), side(y, 800))
        ratios.append(predicted / measured)
    ratios = np.array(ratios)
    assert 0.7 <= np.median(ratios) <= 1.3, np.median(ratios)
    assert np.mean((ratios > 0.5) & (ratios < 2.0)) >= 0.8


def test_the_within_part_never_exceeds_the_scatter_of_the_run_means():
    """An oscillating frame series over-states each run's own variance (the ladder's angle:
    1.53 against a run-mean variance of 1.05): the within part is bounded by the sample
    variance, the between part is then 0, and extending every run cannot predict a wider
    interval than the present one (unbounded, it predicted 0.93 against 0.50 there)."""
    values = [38.63, 38.01, 38.57]                  # the ladder's 3 CG1 half-window means
    over = sp.arm(values, within=[1.24, 0.38, 0.56], window=[0.58, 0.5, 0.58],
                  steady_share=1.0)
    within, between = sp.components(over)
    assert within == pytest.approx(np.var(values, ddof=1)) and between == 0.0
    # each run keeps its share of the within part; doubling every window halves it
    assert sp.run_variance(over, 0.55) == pytest.approx(
        np.mean(np.array([1.24, 0.38, 0.56]) * within / np.mean([1.24, 0.38, 0.56])
                * np.array([0.58, 0.5, 0.58]) / (np.array([0.58, 0.5, 0.58]) + 0.55)))
    cg3 = sp.arm([41.2, 41.87, 41.17, 41.61, 42.2, 43.82], within=[0.95, 0.78, 1.2, 0.8, 1.8, 1.5],
                 window=[1.0] * 6, steady_share=1.0)
    assert sp.half_width(cg3, over, extend=(1.0, 0.55)) < sp.half_width(cg3, over)
    # below the bound nothing changes
    under = sp.arm(values, within=[0.01] * 3, window=[0.5] * 3)
    assert sp.components(under) == pytest.approx((0.01, np.var(values, ddof=1) - 0.01))


def test_hsu_degrees_of_freedom_are_the_smaller_arm_less_one():
    """A sequential study's looks (ligwf.study.rounds) use Hsu's min(R1, R2) - 1: never
    more than Welch's, so their intervals are never narrower."""
    x, y = [41.5, 39.5, 43.5, 40.0], [40.0, 40.2]
    welch = eq.difference_estimate(x, y, 0.05 / 3)
    hsu = eq.difference_estimate(x, y, 0.05 / 3, eq.HSU)
    assert hsu.df == 1.0 and welch.df > 1.0 and hsu.value == welch.value
    assert hsu.hi - hsu.lo > welch.hi - welch.lo
    assert hsu.hi - hsu.lo == pytest.approx(2 * stats.t.ppf(1 - 0.05 / 3, 1) * welch.se)
    a, b = sp.arm(x), sp.arm(y)
    assert sp.half_width(a, b, 0.05 / 3, df_rule=eq.HSU) == pytest.approx(
        0.5 * (hsu.hi - hsu.lo), rel=1e-3)


@pytest.mark.parametrize("sizes", [(6, 2), (24, 3), (4, 4)])
def test_the_planner_predicts_with_the_verdicts_reference_distribution(sizes):
    """Under the single-look rule (Welch for equal arms, Behrens-Fisher for unequal ones) the
    planner's half-width as the runs stand is the verdict interval's half-width (to the
    plan's rounding of theta / df), not Welch's, which is narrower for unequal arms."""
    rng = np.random.default_rng(7)
    x, y = rng.normal(0.0, 1.0, sizes[0]), rng.normal(0.0, 2.0, sizes[1])
    e = eq.difference_estimate(x, y, eq.ALPHA, eq.WELCH_BF)
    planned = sp.half_width(sp.arm(x), sp.arm(y), eq.ALPHA, df_rule=eq.WELCH_BF)
    assert planned == pytest.approx(0.5 * (e.hi - e.lo), rel=2e-3)
    if sizes[0] != sizes[1]:
        assert sp.half_width(sp.arm(x), sp.arm(y), eq.ALPHA, df_rule=eq.WELCH) < planned
