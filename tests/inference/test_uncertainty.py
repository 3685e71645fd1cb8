"""ligwf.inference.uncertainty on hand-made series: condition intervals, errors against CG1
(pooled over replicas), the CG1 noise floor, the within / beyond decision, the scatter.

Every expected value is derived here from the definition (the module docstrings of
ligwf.inference.uncertainty and ligwf.analysis.records.intervals), on series built so the
answer is exact (runs constant over their frames: the bootstrap can only pick replicas) or
known in distribution (independent Gaussian frames); nothing is computed by calling the
code under test a second way.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ligwf.analysis.records import statistics as st
from ligwf.analysis.records.metrics import POSITIVE, UNIT, MetricSpec
from ligwf.inference.uncertainty import ConditionStats, Floor, mark, replicas_to_decide

#: 97.5 % point of the standard normal, and of Student's t with 1 degree of freedom
Z = 1.959963984540054
T1 = 12.706204736174704
DRAWS = 2000

ANGLE = MetricSpec("angle", "angle of repose", "angle", st.MEAN, POSITIVE)
ANGLE_ERROR = MetricSpec("angle_error", "angle error", "angle", st.RELATIVE_ERROR, POSITIVE)
SHARE = MetricSpec("share", "rigid share", "share", st.MEAN, UNIT)
PROFILE_ERROR = MetricSpec("profile_error", "profile error", "profile", st.RELATIVE_L2,
                           POSITIVE)
METRICS = {m.name: m for m in (ANGLE, ANGLE_ERROR, SHARE, PROFILE_ERROR)}


def constant(value, frames: int = 40) -> np.ndarray:
    return np.full(frames, float(value))


def stats_of(series: dict[str, dict], seed: int = 3) -> ConditionStats:
    return ConditionStats(series, DRAWS, seed, METRICS)


def runs(name: str, values: dict[str, np.ndarray]) -> dict[str, dict]:
    return {cid: {name: v} for cid, v in values.items()}


# -- within / beyond ----------------------------------------------------------------------

@pytest.mark.parametrize("error,lo,hi,floor,expected", [
    (0.05, 0.02, 0.08, 0.10, "within"), (0.10, 0.09, 0.10, 0.10, "within"),   # hi at the floor
    (0.20, 0.1000001, 0.3, 0.10, "beyond"), (0.0, 0.0, 0.0, 0.0, "within"),
    (1e-3, 1e-9, 2e-3, 0.0, "beyond"),
    # the demo's Bond-CG2 angle error 0.0957 [0, 0.338] against its floor: not "beyond"
    (0.0957, 0.0, 0.338, 0.0336, "undecided"),
    (0.05, 0.0, 0.2, 0.10, "undecided"),                 # a point within, an interval across
    (math.nan, 0.0, 1.0, 0.1, "–"), (0.1, 0.0, 1.0, math.nan, "–"), (math.inf, 0, 1, 0.1, "–")])
def test_the_interval_decides_against_the_floor(error, lo, hi, floor, expected):
    assert mark(error, floor, lo, hi, 2).split(":")[0] == expected


def test_without_an_interval_nothing_is_decided():
    """One CG-n replica (no replica interval): a point far above or below the floor is
    still undecided, and the mark says what is missing."""
    for error in (0.01, 10.0):
        assert mark(error, 0.1) == "undecided: 1 replica, no interval (add CG-n replicas)"


def test_replicas_that_would_decide():
    """Half-width 0.1, gap 0.05 to the floor, 2 CG1 replicas: 2 (0.1 / 0.05)^2 = 8; an
    error on the floor cannot be decided; a huge count is not suggested."""
    assert replicas_to_decide(0.15, 0.05, 0.25, 0.10, 2) == 8
    assert mark(0.15, 0.10, 0.05, 0.25, 2) == "undecided: about 8 CG1 replicas would decide"
    assert replicas_to_decide(0.10, 0.0, 0.2, 0.10, 2) is None
    assert mark(0.10, 0.10, 0.0, 0.2, 2) == "undecided: the error sits on the floor"
    assert replicas_to_decide(0.101, 0.0, 0.2, 0.10, 2) == 20000
    assert mark(0.101, 0.10, 0.0, 0.2, 2).startswith("undecided: the error is close to the floor")
    assert replicas_to_decide(0.3, 0.29, 0.31, 0.10, 3) == 4            # at least one more


# -- frame metrics: value and interval ------------------------------------------------------

def test_two_constant_replicas_interval_is_the_replica_spread_widened():
    """Runs constant over frames: the within-run error is 0, a draw's mean over 2 replicas
    picked with replacement is a, (a+b)/2 or b (1/4, 1/2, 1/4), so its 2.5/97.5 %
    quantiles are a and b; widened by sqrt(R/(R-1)) = sqrt(2) around the mean."""
    a, b = 30.0, 34.0
    s = stats_of(runs("angle", {"r0": constant(a), "r1": constant(b)}))
    iv = s.frame_metric(["r0", "r1"], "angle")
    v = 0.5 * (a + b)
    assert iv.value == pytest.approx(v, rel=1e-15)
    assert iv.lo == pytest.approx(v - math.sqrt(2) * (v - a), rel=1e-12)
    assert iv.hi == pytest.approx(v + math.sqrt(2) * (b - v), rel=1e-12)
    assert iv.se_within == pytest.approx(0.0, abs=1e-12)
    assert iv.replicas == 2


def test_interval_is_clipped_to_the_range_of_a_share():
    """A share's interval never leaves [0, 1] even when the widened spread would."""
    a, b = 0.05, 0.95
    s = stats_of(runs("share", {"r0": constant(a), "r1": constant(b)}))
    iv = s.frame_metric(["r0", "r1"], "share")
    assert iv.value == pytest.approx(0.5)
    assert 0.5 - math.sqrt(2) * 0.45 < 0.0 and 0.5 + math.sqrt(2) * 0.45 > 1.0
    assert (iv.lo, iv.hi) == (0.0, 1.0)


def test_one_replica_has_no_interval_but_a_within_run_error():
    """Independent Gaussian frames (sd 1, n frames): the within-run standard error of the
    mean is 1 / sqrt(n); one replica gets no replica interval."""
    n = 400
    x = 30.0 + np.random.default_rng(11).standard_normal(n)
    s = stats_of(runs("angle", {"r0": x}))
    iv = s.frame_metric(["r0"], "angle")
    assert iv.value == pytest.approx(float(np.mean(x)), rel=1e-14)
    assert math.isnan(iv.lo) and math.isnan(iv.hi)
    assert iv.se_within == pytest.approx(1.0 / math.sqrt(n), rel=0.12)
    assert iv.replicas == 1


def test_coinciding_replicas_keep_the_within_run_width():
    """Two replicas with the same mean (the replica spread says nothing): each side of
    the interval still reaches z x the within-run error, here 1 / sqrt(2 n) (two runs of
    n frames of sd 1). The width comes from the combined draws: two replicas picked with
    replacement, each with its own frame resample; the same replica twice (probability
    1/2) has variance 1 / n, two different ones 1 / (2 n): sd sqrt(3 / (4 n)), widened by
    sqrt(2)."""
    n = 400
    rng = np.random.default_rng(5)
    x = rng.standard_normal(n)
    r0, r1 = 30.0 + x, 30.0 + x[::-1]          # equal means, each sd ~1
    s = stats_of(runs("angle", {"r0": r0, "r1": r1}))
    iv = s.frame_metric(["r0", "r1"], "angle")
    assert iv.value == pytest.approx(30.0 + float(np.mean(x)), rel=1e-14)
    se = 1.0 / math.sqrt(2 * n)
    assert iv.se_within == pytest.approx(se, rel=0.12)
    assert iv.value - iv.lo >= Z * iv.se_within * (1 - 1e-12)
    assert iv.hi - iv.value >= Z * iv.se_within * (1 - 1e-12)
    assert iv.hi - iv.lo == pytest.approx(2 * Z * math.sqrt(2) * math.sqrt(3 / (4 * n)),
                                          rel=0.12)


def test_each_side_is_the_widened_quantile_or_the_within_run_floor_whichever_is_wider():
    """The rule every interval of the report ends in, on draws made by hand: 1010 combined
    draws of which 30 at v - 1 and 30 at v + 2 (so the 2.5 / 97.5 % quantiles are exactly
    v - 1 and v + 2), within-run draws +-1 (sd sqrt(1000 / 999)), three replicas (widening
    sqrt(3/2)): the low side is set by the floor z x se, the high side by the quantile."""
    from ligwf.analysis.records.intervals import interval_from_draws

    v = 10.0
    combined = np.concatenate([np.full(30, v - 1), np.full(950, v), np.full(30, v + 2)])
    within = v + np.tile([-1.0, 1.0], 500)
    se = math.sqrt(1000 / 999)
    iv = interval_from_draws(v, combined, within, 3, (-math.inf, math.inf))
    assert Z * se > math.sqrt(1.5) * 1.0 and math.sqrt(1.5) * 2.0 > Z * se
    assert iv.se_within == pytest.approx(se, rel=1e-12)
    assert iv.lo == pytest.approx(v - Z * se, rel=1e-12)
    assert iv.hi == pytest.approx(v + math.sqrt(1.5) * 2.0, rel=1e-12)
    clipped = interval_from_draws(v, combined, within, 3, (9.0, 11.0))
    assert (clipped.lo, clipped.hi) == (9.0, 11.0)


def test_cases_without_the_series_are_left_out_and_none_gives_nan():
    s = stats_of({"r0": {"angle": constant(30.0)}, "r1": {"angle": np.empty(0)}})
    iv = s.frame_metric(["r0", "r1", "not-a-case"], "angle")
    assert iv.value == 30.0 and iv.replicas == 1
    empty = s.frame_metric(["r1"], "angle")
    assert math.isnan(empty.value) and empty.replicas == 0


# -- errors against CG1, pooled over replicas -------------------------------------------------

def test_relative_error_of_the_pooled_means_and_its_joint_interval():
    """Error of CG-n against CG1 = |mean of the CG-n runs - mean of the CG1 runs| / CG1 mean
    (means of the replicas' own means). Constant runs: a draw pairs c in {34, 35, 36} with r
    in {30, 31, 32} (1/4, 1/2, 1/4 each, independent), so the error draws span
    |34 - 32| / 32 .. |36 - 30| / 30 (each extreme with probability 1/16 > 2.5 %); the
    interval is that spread widened by sqrt(2) (two CG-n replicas)."""
    series = runs("angle", {"cg1-a": constant(30), "cg1-b": constant(32),
                            "cg2-a": constant(34), "cg2-b": constant(36)})
    iv = stats_of(series).error_metric(["cg2-a", "cg2-b"], ["cg1-a", "cg1-b"], "angle_error")
    v = abs(35.0 - 31.0) / 31.0
    q_lo, q_hi = 2.0 / 32.0, 6.0 / 30.0
    assert iv.value == pytest.approx(v, rel=1e-14)
    assert iv.lo == pytest.approx(v - math.sqrt(2) * (v - q_lo), rel=1e-12)
    assert iv.hi == pytest.approx(v + math.sqrt(2) * (q_hi - v), rel=1e-12)
    assert iv.se_within == pytest.approx(0.0, abs=1e-12)
    assert iv.replicas == 2


def test_error_against_one_cg1_run_keeps_that_run_fixed():
    """With one CG1 run the reference is not resampled over replicas (there is one): the
    error draws come from the CG-n replicas only: |{34, 35, 36} - 30| / 30."""
    series = runs("angle", {"cg1": constant(30), "cg2-a": constant(34), "cg2-b": constant(36)})
    iv = stats_of(series).error_metric(["cg2-a", "cg2-b"], ["cg1"], "angle_error")
    v = 5.0 / 30.0
    assert iv.value == pytest.approx(v, rel=1e-14)
    assert iv.lo == pytest.approx(v - math.sqrt(2) * (v - 4.0 / 30.0), rel=1e-12)
    assert iv.hi == pytest.approx(v + math.sqrt(2) * (6.0 / 30.0 - v), rel=1e-12)


def test_error_of_one_case_has_a_value_and_no_interval():
    series = runs("angle", {"cg1": constant(40), "cg3": constant(38)})
    iv = stats_of(series).error_metric(["cg3"], ["cg1"], "angle_error")
    assert iv.value == pytest.approx(2.0 / 40.0, rel=1e-14)
    assert math.isnan(iv.lo) and math.isnan(iv.hi)


def test_error_without_a_reference_is_nan():
    series = runs("angle", {"cg2": constant(30)})
    assert math.isnan(stats_of(series).error_metric(["cg2"], [], "angle_error").value)


def test_profile_error_is_the_relative_l2_over_the_bins_both_fill():
    """Velocity profiles (frames x bins): ||v - v_ref|| / ||v_ref|| over the bins filled in
    both means; an empty bin (nan in every frame) is left out of both norms."""
    ref = np.tile([1.0, np.nan, 3.0, 2.0], (30, 1))
    run = np.tile([2.0, 5.0, 3.0, 2.0], (30, 1))
    series = runs("profile", {"cg1": ref, "cg2": run})
    iv = stats_of(series).error_metric(["cg2"], ["cg1"], "profile_error")
    assert iv.value == pytest.approx(1.0 / math.sqrt(1 + 9 + 4), rel=1e-14)


# -- the CG1 noise floor -----------------------------------------------------------------------

def test_floor_measured_over_cg1_replicas_is_the_largest_leave_one_out_error():
    """Each CG1 replica against the mean of the others, the largest: 30 vs mean(33, 27) = 30
    -> 0; 33 vs 28.5 -> 4.5 / 28.5; 27 vs 31.5 -> 4.5 / 31.5."""
    series = runs("angle", {"a": constant(30), "b": constant(33), "c": constant(27)})
    floor = stats_of(series).floor(["a", "b", "c"], "angle_error")
    assert floor.value == pytest.approx(4.5 / 28.5, rel=1e-14)
    assert floor.source == "measured over 3 CG1 replicas"


def test_floor_estimated_from_one_cg1_run_is_the_95th_percentile_of_its_noise():
    """One CG1 run of n independent Gaussian frames (mean mu, sd sigma): two independent
    resamples' means differ by N(0, sqrt(2) sigma / sqrt(n)), so their relative error's
    95th percentile is z sqrt(2) sigma / (sqrt(n) mu)."""
    n, mu, sigma = 400, 30.0, 1.5
    x = mu + sigma * np.random.default_rng(2).standard_normal(n)
    floor = stats_of(runs("angle", {"cg1": x})).floor(["cg1"], "angle_error")
    assert floor.value == pytest.approx(Z * math.sqrt(2) * sigma / (math.sqrt(n) * mu),
                                        rel=0.15)
    assert floor.source.startswith("indicative: estimated from 1 CG1 run")


def test_floor_of_a_noiseless_single_run_is_zero_and_of_none_is_unknown():
    s = stats_of(runs("angle", {"cg1": constant(30)}))
    assert s.floor(["cg1"], "angle_error").value == 0.0
    none = s.floor([], "angle_error")
    assert math.isnan(none.value) and none.source == "none"
    assert mark(0.01, none.value) == "–"


def test_an_error_within_the_measured_floor_is_within():
    """CG1 replicas 30 / 33 / 27 (floor 4.5 / 28.5 = 0.158); a CG2 at 32 (error 2 / 30) is
    within it, a CG2 at 36 (error 6 / 30 = 0.2) beyond."""
    series = runs("angle", {"a": constant(30), "b": constant(33), "c": constant(27),
                            "near": constant(32), "far": constant(36)})
    s = stats_of(series)
    floor = s.floor(["a", "b", "c"], "angle_error")
    near = s.error_metric(["near"], ["a", "b", "c"], "angle_error").value
    far = s.error_metric(["far"], ["a", "b", "c"], "angle_error").value
    assert near == pytest.approx(2.0 / 30.0) and far == pytest.approx(6.0 / 30.0)
    assert near < floor.value < far   # the points; their intervals decide the marks
    assert isinstance(floor, Floor)


# -- CG1 scatter of a frame metric ---------------------------------------------------------------

def test_scatter_is_the_std_over_cg1_replicas_or_one_runs_within_error():
    series = runs("angle", {"a": constant(30), "b": constant(33), "c": constant(27)})
    value, source = stats_of(series).scatter(["a", "b", "c"], "angle")
    assert value == pytest.approx(3.0, rel=1e-14)       # sample std (ddof 1) of 30, 33, 27
    assert source == "std over 3 CG1 replicas"
    n = 400
    x = 30.0 + np.random.default_rng(4).standard_normal(n)
    value, source = stats_of(runs("angle", {"one": x})).scatter(["one"], "angle")
    assert value == pytest.approx(1.0 / math.sqrt(n), rel=0.12)
    assert source == "within-run error of 1 CG1 run"


def test_same_seed_same_interval():
    rng = np.random.default_rng(8)
    series = runs("angle", {"a": 30 + rng.standard_normal(50), "b": 31 + rng.standard_normal(50)})
    one = stats_of(series, seed=9).frame_metric(["a", "b"], "angle")
    two = stats_of(series, seed=9).frame_metric(["a", "b"], "angle")
    assert (one.lo, one.hi, one.se_within) == (two.lo, two.hi, two.se_within)


def test_cost_interval_t_on_the_logarithm():
    """Costs 2 and 8 core-s: geometric mean 4, sd of the logs ln(4) / sqrt(2), half-width
    t(0.975, 1) x ln(4) / 2 on the log scale; the value is the arithmetic mean 5."""
    import pandas as pd

    from ligwf.inference.uncertainty import cost_interval

    iv = cost_interval(pd.Series([2.0, 8.0]))
    half = T1 * math.log(4.0) / 2.0
    assert iv.value == 5.0
    assert iv.lo == pytest.approx(4.0 * math.exp(-half), rel=1e-12)
    assert iv.hi == pytest.approx(4.0 * math.exp(half), rel=1e-12)
    one = cost_interval(pd.Series([3.0, math.nan, -1.0]))   # non-positive / nan ignored
    assert one.value == 3.0 and math.isnan(one.lo)
