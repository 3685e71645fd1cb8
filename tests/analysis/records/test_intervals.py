"""Intervals on synthetic series with known statistics (ligwf.analysis.records.intervals)."""

from __future__ import annotations

import numpy as np
import pytest

from ligwf.analysis.records.intervals import (autocorrelation_time, frame_metric_interval,
                                      positive_replica_interval, within_run_se)


def ar1(n: int, phi: float, seed: int, mean: float = 0.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = np.empty(n)
    x[0] = rng.normal()
    for k in range(1, n):
        x[k] = phi * x[k - 1] + rng.normal() * np.sqrt(1 - phi**2)
    return mean + x


def test_autocorrelation_time_of_an_ar1_series():
    taus = [autocorrelation_time(ar1(4000, 0.6, s)) for s in range(4)]
    assert np.mean(taus) == pytest.approx((1 + 0.6) / (2 * (1 - 0.6)), rel=0.25)
    assert autocorrelation_time(np.random.default_rng(0).normal(size=4000)) < 0.8


def test_within_run_error_matches_the_spread_of_run_means():
    means = [ar1(300, 0.7, s).mean() for s in range(200)]
    se = np.mean([within_run_se(ar1(300, 0.7, 1000 + s)) for s in range(20)])
    assert se == pytest.approx(np.std(means), rel=0.3)


def test_two_coinciding_replicas_still_get_the_within_run_width():
    a = ar1(200, 0.7, 1, mean=40.0)
    b = a - a.mean() + a.mean()          # identical means, as Bo-CG2's two seeds
    iv = frame_metric_interval([a, b[::-1]], (-90, 90), 500, 0)
    assert iv.hi - iv.lo >= 2 * 1.9 * iv.se_within
    assert iv.se_within >= 0.5 * within_run_se(a) / np.sqrt(2)


def test_bounded_share_and_one_replica():
    rng = np.random.default_rng(2)
    rare = [(rng.uniform(size=100) > 0.97).astype(float) for _ in range(2)]
    iv = frame_metric_interval(rare, (0.0, 1.0), 500, 0)
    assert 0.0 <= iv.lo <= iv.value <= iv.hi <= 1.0
    one = frame_metric_interval(rare[:1], (0.0, 1.0), 500, 0)
    assert np.isnan(one.lo) and np.isnan(one.hi) and np.isfinite(one.se_within)


def test_cost_interval_is_positive():
    iv = positive_replica_interval(np.array([23.9, 2.0]))
    assert 0 < iv.lo <= iv.value <= iv.hi
    assert np.isnan(positive_replica_interval(np.array([5.0])).lo)
