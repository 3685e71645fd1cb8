#!/usr/bin/env python3
"""How well can any planner predict the half-width an extension leaves? (issue 30, item 4)

``scripts/prediction_check.py`` asks of a real study that the half-width the planner
(:func:`ligwf.inference.sampling.half_width`) predicts for a doubled steady window be
within +-30 % of the one measured after it; on the demo it held in 1 of 6 rows, on the
ladder in 3 of 7, every miss on the conservative side. This benchmark measures, on synthetic
studies shaped like ours, what that criterion can ask of a prediction at all:

* **planner**: the report's prediction from the first half of every run (within-run
  variances from the runs' own frames, the between-run rest kept), for the window doubled;
* **oracle**: the expected half-width with the true variances known (AR(1) variance of a
  mean plus the offset variance; Welch's df from them): the best any plan could say
  before the extension is run;
* measured: the half-width of the full windows.

Per cell (AR(1) phi, frames of the full window, replica offset sd in frame sds, CG-n runs R
against 3 CG1 runs, and ``start-up``: a per-run offset of ``drift`` frame sds that decays
with a time constant of 1/8 of the full window, i.e. a start that had not settled when the
steady window began) it prints the share of trials whose measured / predicted ratio lies
within +-30 % and the ratio's 10 / 50 / 90 % quantiles, for the planner and the oracle.

Registered before the first run (2026-12-05 05:35 UTC):

* H1: with only stationary seed noise (no start-up), the oracle holds +-30 % in fewer than
  80 % of trials in every cell: a per-row +-30 % check cannot be met reliably by any plan at
  these replica counts, so a real study's rows are read against these shares;
* H2: in those cells the planner's median ratio lies in [0.75, 1.05] and its +-30 % share
  is not below the oracle's minus 0.05 (nothing is lost to estimating the variances);
* H3: with a start-up transient the planner's median ratio falls below 0.75 in at least one
  cell (the extension removes start-up scatter the first half shows as between-run: the
  conservative side the real misses are on).

Registered 2026-12-06 02:35 UTC, before the within-run part was bounded by the run-mean
variance (``sampling.components``; docs/results/prediction_check/README.md) and before
these cells were first run: cells with a ``periodic`` component (a sinusoid of random phase
per run, period 16 frames, amplitude 1.5 frame sds, as the real angle of repose oscillates),
no start-up.

* H4: in every periodic cell the planner's median ratio lies in [0.75, 1.25] and its +-30 %
  share is not below the oracle's minus 0.05.

Registered 2026-12-06 06:40 UTC, before these columns were first run: a two-half
batch-means within part ((first-half mean - second-half mean)^2 / 4 a run, so that the
between part is the covariance of the half-window means; :func:`halves_within_variance`)
beside the planner's (s^2 x 2 tau / n, Sokal's window). An exploratory comparison at 8 and 3
runs an arm (150 trials, other seeds, not committed) suggested it: never much worse, better
with a start-up transient.

* H5: in every cell the two-half planner's +-30 % share is not below the planner's minus
  0.05, and in at least half of the start-up cells it is above it by 0.05 or more.

Result (docs/results/prediction_check/bench_prediction_halves.txt): H5 does not hold (better
by 0.05 in 12 of 36 start-up cells; up to 0.15 worse in periodic cells whose half windows are
shorter than a period), so the planner keeps its estimate; the column stays as the record.

    .venv/bin/python benchmarks/bench_prediction.py             # ~3 min
    .venv/bin/python benchmarks/bench_prediction.py --trials 1000
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys

import numpy as np

from benchmarks.bench_coverage import ar1_runs
from ligwf.inference import sampling
from ligwf.inference.equivalence import ALPHA, t_quantile, welch_df

TOLERANCE = 0.30
CG1_RUNS = 3


def ar1_mean_variance(frames: int, phi: float) -> float:
    """Variance of the mean of ``frames`` stationary AR(1) frames of unit sd."""
    k = np.arange(1, frames)
    return float((1.0 + 2.0 * np.sum((1.0 - k / frames) * phi**k)) / frames)


#: the periodic cells: period (frames) and amplitude (frame sds) of the oscillation
PERIOD, AMPLITUDE = 16.0, 1.5


def runs(rng, trials: int, R: int, frames: int, phi: float, offset: float,
         drift: float, amplitude: float = 0.0) -> np.ndarray:
    """(trials, R, frames) AR(1) runs with a seed offset, a decaying start-up offset and an
    oscillation of ``amplitude`` (period :data:`PERIOD`, a random phase per run)."""
    x = ar1_runs(rng, trials, R, frames, phi, offset)
    if drift > 0:
        decay = np.exp(-np.arange(frames) / (frames / 8.0))
        x = x + drift * rng.standard_normal((trials, R))[:, :, None] * decay
    if amplitude > 0:
        phase = rng.uniform(0.0, 2.0 * math.pi, (trials, R))[:, :, None]
        x = x + amplitude * np.sin(2.0 * math.pi * np.arange(frames) / PERIOD + phase)
    return x


def sine_mean_variance(frames: int, amplitude: float) -> float:
    """Variance of the mean of ``frames`` frames of a sinusoid of random phase."""
    if amplitude == 0:
        return 0.0
    w = 2.0 * math.pi / PERIOD
    return amplitude**2 / 2.0 * (math.sin(frames * w / 2.0) / (frames * math.sin(w / 2.0)))**2


def halves_within_variance(series: np.ndarray) -> float:
    """The two-half batch-means estimate of a run mean's within-run variance,
    (first-half mean - second-half mean)^2 / 4: a seed's offset cancels, so over an arm's
    runs the rest of the run-mean variance is the covariance of the half-window means."""
    half = len(series) // 2
    if half < 1:
        return math.nan
    return float((series[:half].mean() - series[len(series) - half:].mean()) ** 2 / 4.0)


def _arm(series: np.ndarray, within=sampling.within_variance) -> sampling.ArmRuns:
    return sampling.arm(series.mean(axis=1), [within(s) for s in series],
                        [float(series.shape[1])] * len(series), steady_share=1.0)


def oracle(R: int, frames: int, phi: float, offset: float, amplitude: float = 0.0) -> float:
    """Expected-variance half-width of the full windows' Welch interval (no start-up)."""
    v = offset**2 + ar1_mean_variance(frames, phi) + sine_mean_variance(frames, amplitude)
    return t_quantile(welch_df(v, R, v, CG1_RUNS), ALPHA) * math.sqrt(v / R + v / CG1_RUNS)


def cell(rng, trials: int, R: int, frames: int, phi: float, offset: float,
         drift: float, amplitude: float = 0.0) -> dict:
    x = runs(rng, trials, R, frames, phi, offset, drift, amplitude)
    y = runs(rng, trials, CG1_RUNS, frames, phi, offset, drift, amplitude)
    half = frames // 2
    ratios = {"planner": [], "halves": [], "oracle": []}
    best_hw = oracle(R, frames, phi, offset, amplitude) if drift == 0 else math.nan
    for t in range(trials):
        measured = sampling.half_width(_arm(x[t]), _arm(y[t]), ALPHA)
        for name, within in (("planner", sampling.within_variance),
                             ("halves", halves_within_variance)):
            predicted = sampling.half_width(
                _arm(x[t, :, :half], within), _arm(y[t, :, :half], within), ALPHA,
                extend=(frames - half, frames - half))
            ratios[name].append(measured / predicted)
        ratios["oracle"].append(measured / best_hw)
    return {k: np.asarray(v) for k, v in ratios.items()}


def summary(r: np.ndarray) -> str:
    r = r[np.isfinite(r)]
    if not len(r):
        return f"{'-':>6} {'-':>17}"
    within = float(np.mean(np.abs(r - 1.0) <= TOLERANCE))
    q = np.quantile(r, [0.1, 0.5, 0.9])
    return f"{within:6.2f} {q[0]:5.2f} {q[1]:5.2f} {q[2]:5.2f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=300)
    ap.add_argument("--seed", type=int, default=20261205)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    print(f"extension predictions: {args.trials} trials a cell; CG-n R runs vs {CG1_RUNS} "
          f"CG1 runs; window doubled; within +-{TOLERANCE:.0%} share, ratio q10 q50 q90")
    print(f"{'phi':>4} {'frames':>6} {'offset':>6} {'R':>2} {'start-up':>8} | "
          f"{'planner':>6} {'q10':>5} {'q50':>5} {'q90':>5} | "
          f"{'oracle':>6} {'q10':>5} {'q50':>5} {'q90':>5} | "
          f"{'halves':>6} {'q10':>5} {'q50':>5} {'q90':>5}")
    h1 = h2 = h5 = True
    startup_better = startup_cells = 0
    h3 = False
    for phi, frames, offset, R, drift in itertools.product(
            (0.3, 0.6, 0.9), (24, 60, 200), (0.0, 1.0), (3, 6), (0.0, 2.0)):
        c = cell(rng, args.trials, R, frames, phi, offset, drift)
        print(f"{phi:4.1f} {frames:6d} {offset:6.1f} {R:2d} {drift:8.1f} | "
              f"{summary(c['planner'])} | {summary(c['oracle'])} | {summary(c['halves'])}",
              flush=True)
        p, o = c["planner"], c["oracle"]
        share = float(np.mean(np.abs(p - 1.0) <= TOLERANCE))
        halves = float(np.mean(np.abs(c["halves"] - 1.0) <= TOLERANCE))
        h5 = h5 and halves >= share - 0.05
        if drift > 0:
            startup_cells += 1
            startup_better += halves >= share + 0.05
        median = float(np.median(p))
        if drift == 0:
            best = float(np.mean(np.abs(o - 1.0) <= TOLERANCE))
            h1 = h1 and best < 0.80
            h2 = h2 and 0.75 <= median <= 1.05 and share >= best - 0.05
        else:
            h3 = h3 or median < 0.75
    print(f"H1 (oracle within +-30 % in < 80 % of trials, every stationary cell): "
          f"{'holds' if h1 else 'does not hold'}")
    print(f"H2 (planner median in [0.75, 1.05], share >= oracle's - 0.05, stationary cells): "
          f"{'holds' if h2 else 'does not hold'}")
    print(f"H3 (a start-up transient takes the planner's median below 0.75 somewhere): "
          f"{'holds' if h3 else 'does not hold'}")
    print(f"periodic cells: period {PERIOD:g} frames, amplitude {AMPLITUDE:g} frame sds, "
          f"no start-up")
    h4 = True
    for phi, frames, offset, R in itertools.product((0.3, 0.6, 0.9), (24, 60, 200),
                                                    (0.0, 1.0), (3, 6)):
        c = cell(rng, args.trials, R, frames, phi, offset, 0.0, AMPLITUDE)
        print(f"{phi:4.1f} {frames:6d} {offset:6.1f} {R:2d} {'sine':>8} | "
              f"{summary(c['planner'])} | {summary(c['oracle'])} | {summary(c['halves'])}",
              flush=True)
        p, o = c["planner"], c["oracle"]
        median = float(np.median(p))
        h5 = h5 and (float(np.mean(np.abs(c["halves"] - 1.0) <= TOLERANCE))
                     >= float(np.mean(np.abs(p - 1.0) <= TOLERANCE)) - 0.05)
        h4 = h4 and 0.75 <= median <= 1.25 and (
            float(np.mean(np.abs(p - 1.0) <= TOLERANCE))
            >= float(np.mean(np.abs(o - 1.0) <= TOLERANCE)) - 0.05)
    print(f"H4 (periodic cells: planner median in [0.75, 1.25], share >= oracle's - 0.05): "
          f"{'holds' if h4 else 'does not hold'}")
    h5 = h5 and 2 * startup_better >= startup_cells
    print(f"H5 (two-half planner: share >= the planner's - 0.05 in every cell, >= its + 0.05 "
          f"in {startup_better} of {startup_cells} start-up cells): "
          f"{'holds' if h5 else 'does not hold'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
