"""The ``auto`` steady window on signals with a known spin-up (ligwf.analysis.flow.steady)."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.bench_coverage import ar1_runs
from ligwf.analysis.flow.steady import (FALLBACK_FRACTION, MSER_BATCH, auto_fraction,
                                        mser_index, settled_index)


def spin_up(n: int, settle: int, seed: int) -> np.ndarray:
    """A level of 40 reached with an exponential of time constant settle/4 frames, noise 1."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    return 40.0 * (1 - np.exp(-4.0 * k / settle)) + rng.normal(0, 1.0, n)


@pytest.mark.parametrize("settle", [5, 10, 20])
def test_window_starts_after_the_spin_up(settle):
    times = 1.0 + 0.01 * np.arange(60)
    x = spin_up(60, settle, settle)
    frac = auto_fraction(times, [x, 0.5 * x], 1.0, 0.6)
    k = int(round(frac * 60))
    assert settle * 0.5 <= k <= settle + 6
    assert np.all(np.abs(x[k:] - 40.0) < 6.0)


def test_steady_signal_keeps_almost_everything_and_short_runs_fall_back():
    x = np.random.default_rng(1).normal(40, 1, 60)
    assert settled_index(x) <= 3
    assert auto_fraction(np.arange(4.0), [np.ones(4)], 0.0, 4.0) == FALLBACK_FRACTION


@pytest.mark.parametrize("settle", [10, 20, 40])
def test_a_long_run_starts_after_the_spin_up_by_mser5(settle):
    """From 80 frames on the window comes from MSER-5: after the spin-up, in whole batches,
    and nothing of the spin-up left in it."""
    n = 200
    times = 1.0 + 0.01 * np.arange(n)
    x = spin_up(n, settle, settle)
    frac = auto_fraction(times, [x, 0.5 * x], 1.0, 0.01 * n)
    k = int(round(frac * n))
    assert k % MSER_BATCH == 0 and settle * 0.5 <= k <= settle + 3 * MSER_BATCH
    assert abs(x[k:].mean() - 40.0) < 0.5


def test_a_long_steady_correlated_run_keeps_its_window_where_the_band_throws_half_away():
    """AR(1) frames (phi 0.8) of 160 frames and no spin-up: the running-mean band, crossed
    by chance somewhere, puts the start at the 50 % cap in most such runs (bench_steady:
    0.89); MSER-5, the rule from 80 frames on, in few."""
    rng = np.random.default_rng(7)
    band = mser = 0
    for sig in ar1_runs(rng, 100, 2, 160, 0.8, 0.0):
        band += max(settled_index(s) for s in sig) >= 72
        mser += auto_fraction(np.arange(160.0), sig, 0.0, 160.0) >= 0.45
        assert max(mser_index(s) for s in sig) <= 80
    assert band >= 60 and mser <= 15, (band, mser)


def test_mser_index_is_a_whole_number_of_batches_and_ignores_missing_frames():
    x = np.r_[np.full(20, 10.0), np.zeros(80)] + np.random.default_rng(2).normal(0, 0.1, 100)
    assert mser_index(x) == 20
    x[50] = np.nan
    assert mser_index(x) == 20
    assert mser_index(np.full(8, np.nan)) == 0
