"""Confidence intervals that respect the data: correlated frames, few replicas, bounds.

Frames of one run are not independent (the measured autocorrelation time of the flow
angle is 2-5 frames), and a study has one to a few replicas per condition. A Student-t
interval over two replica means (t = 12.7) gives negative shares or, when the two means
happen to coincide, a band far narrower than the scatter inside each run. So:

* **block bootstrap over frames**: each run's frame series is resampled in moving blocks
  of ``block_length`` frames (twice the integrated autocorrelation time, at least 1),
  which keeps the correlation inside blocks;
* **combined with replicas**: each draw picks R replicas with replacement and one block
  resample of each, and averages their statistic; the spread of the draws around the
  condition value is widened by sqrt(R / (R - 1)) (a bootstrap over R items underestimates
  their variance by (R - 1) / R);
* **never narrower than the within-run noise**: the within-run standard error of the
  condition value (the spread of draws that keep the replicas fixed and resample frames
  only) sets a floor: each side of the interval reaches at least z x that error;
* **bounded**: shares stay in [0, 1], costs and errors >= 0 (the interval is clipped to
  the range the quantity can take; a percentile bootstrap of a bounded statistic already
  stays inside);
* **one replica**: no replica interval at all (the report says so); the within-run error
  is still given.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import stats

LEVEL = 0.95


def autocorrelation_time(x: np.ndarray, window: float = 5.0) -> float:
    """Integrated autocorrelation time in frames (0.5 for independent frames), with
    Sokal's self-consistent window (sum up to lag M with M >= window x tau)."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    n = len(x)
    if n < 4 or np.var(x) == 0:
        return 0.5
    y = x - x.mean()
    f = np.fft.rfft(y, 2 * n)
    acf = np.fft.irfft(f * np.conj(f))[:n]
    acf /= acf[0]
    tau = 0.5
    for m in range(1, n):
        tau += acf[m]
        if m >= window * tau:
            break
    return float(max(tau, 0.5))


def block_length(x: np.ndarray) -> int:
    """Frames per bootstrap block: 2 x autocorrelation time, rounded up, at least 1."""
    return max(1, math.ceil(2.0 * autocorrelation_time(x) - 1e-9))


def within_run_se(x: np.ndarray) -> float:
    """Standard error of the mean of one run's frame series: std / sqrt(n_eff) with
    n_eff = n / (2 tau) (nan with fewer than two finite frames)."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    if len(x) < 2:
        return math.nan
    return float(np.std(x, ddof=1) * math.sqrt(2.0 * autocorrelation_time(x) / len(x)))


def block_indices(n: int, block: int, draws: int, rng: np.random.Generator) -> np.ndarray:
    """(draws, n) frame indices of moving-block resamples of a series of n frames."""
    block = min(max(block, 1), n)
    starts = rng.integers(0, n - block + 1, size=(draws, math.ceil(n / block)))
    idx = (starts[:, :, None] + np.arange(block)[None, None, :]).reshape(draws, -1)
    return idx[:, :n]


Statistic = Callable[[np.ndarray], np.ndarray]   # (draws, frames, ...) -> (draws, ...)


def nanmean(a, axis=None):
    """np.nanmean without the warning for all-nan slices (empty profile bins stay nan)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmean(a, axis=axis)


def _mean(a: np.ndarray) -> np.ndarray:
    return nanmean(a, axis=1)


def run_draws(series: np.ndarray, draws: int, rng: np.random.Generator,
              stat: Statistic = _mean, block_signal: np.ndarray | None = None) -> np.ndarray:
    """Block-bootstrap draws of ``stat`` over one run's frames (axis 0 of ``series``;
    a profile series has the bins on axis 1). The block length comes from
    ``block_signal`` (default: the series itself, or its row means)."""
    series = np.asarray(series, float)
    sig = block_signal if block_signal is not None else (
        series if series.ndim == 1 else nanmean(series, axis=1))
    idx = block_indices(len(series), block_length(sig), draws, rng)
    return stat(series[idx])


@dataclass(frozen=True)
class Interval:
    """A condition value with its interval and its within-run standard error."""

    value: float
    lo: float          # nan: no replica interval
    hi: float
    se_within: float   # within-run standard error of value (frames resampled, replicas fixed)
    replicas: int


def interval_from_draws(value: float, combined: np.ndarray, within: np.ndarray, replicas: int,
                        bounds: tuple[float, float], level: float = LEVEL) -> Interval:
    """Interval from combined (replica + frame) draws, widened for few replicas, floored
    at z x the within-run error, clipped to ``bounds``; none for one replica."""
    within = within[np.isfinite(within)]
    se = float(np.std(within, ddof=1)) if len(within) > 1 else math.nan
    if replicas < 2 or not math.isfinite(value):
        return Interval(value, math.nan, math.nan, se, replicas)
    combined = combined[np.isfinite(combined)]
    z = float(stats.norm.ppf(0.5 + level / 2))
    widen = math.sqrt(replicas / (replicas - 1))
    q_lo, q_hi = (np.quantile(combined, [0.5 - level / 2, 0.5 + level / 2])
                  if len(combined) else (value, value))
    floor = z * se if math.isfinite(se) else 0.0
    lo = value - max(widen * (value - q_lo), floor)
    hi = value + max(widen * (q_hi - value), floor)
    return Interval(value, max(lo, bounds[0]), min(hi, bounds[1]), se, replicas)


def condition_draws(runs: list[np.ndarray], draws: int, rng: np.random.Generator,
                    stat: Statistic = _mean) -> tuple[np.ndarray, np.ndarray]:
    """(combined, within) draws of the mean over replicas of a per-run statistic.

    combined: replicas drawn with replacement, frames block-resampled; within: every
    replica once, frames block-resampled (the within-run noise of the condition value).
    """
    per_run = np.stack([run_draws(r, draws, rng, stat) for r in runs])   # (R, draws, ...)
    within = nanmean(per_run, axis=0)
    pick = rng.integers(0, len(runs), size=(draws, len(runs)))
    combined = nanmean(per_run[pick, np.arange(draws)[:, None]], axis=1)
    return combined, within


def frame_metric_interval(runs: list[np.ndarray], bounds: tuple[float, float], draws: int,
                          seed: int, stat: Statistic = _mean) -> Interval:
    """Condition value (mean over replicas of ``stat`` of each run) with its interval."""
    runs = [np.asarray(r, float) for r in runs if len(r)]
    if not runs:
        return Interval(math.nan, math.nan, math.nan, math.nan, 0)
    rng = np.random.default_rng(seed)
    value = float(nanmean([stat(r[None, :])[0] for r in runs]))
    combined, within = condition_draws(runs, draws, rng, stat)
    return interval_from_draws(value, combined, within, len(runs), bounds)


def positive_replica_interval(values: np.ndarray, level: float = LEVEL) -> Interval:
    """Interval of a positive quantity measured once per replica (run cost): Student t on
    the logarithm, so the bounds stay positive; none for one replica."""
    x = np.asarray(values, float)
    x = x[np.isfinite(x) & (x > 0)]
    if len(x) == 0:
        return Interval(math.nan, math.nan, math.nan, math.nan, 0)
    m = float(np.mean(x))
    if len(x) < 2:
        return Interval(m, math.nan, math.nan, math.nan, 1)
    lx = np.log(x)
    half = float(stats.t.ppf(0.5 + level / 2, len(x) - 1) * lx.std(ddof=1) / math.sqrt(len(x)))
    g = float(np.exp(lx.mean()))
    return Interval(m, min(g * math.exp(-half), m), max(g * math.exp(half), m), math.nan, len(x))
