"""The ``auto`` steady window on signals with a known spin-up (ligwf.analysis.flow.steady)."""

from __future__ import annotations

import numpy as np
import pytest

from ligwf.analysis.flow.steady import FALLBACK_FRACTION, auto_fraction, settled_index


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
