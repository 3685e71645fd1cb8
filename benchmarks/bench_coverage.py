#!/usr/bin/env python3
"""Coverage of the verdict's intervals on synthetic studies like ours (issue 30).

Each run is an AR(1) frame series (coefficient phi, unit innovation sd scaled to a frame sd
of 1) plus a replica offset (sd ``offset`` x the frame sd); an arm has R runs; a statistic's
run value is its steady-window mean, exactly as the report takes it. For every cell
(phi 0.3 / 0.6 / 0.9, 10 / 50 / 200 frames, offsets 0 / 1 / 3, R = 2 / 3 / 4 / 6) and
``--trials`` studies it prints the share of studies whose interval holds the truth:

* ``value``: the 95 % interval of a condition value (t on run means, R - 1 df);
* ``diff``: the 95 % interval of CG-n - CG1 (Welch, Satterthwaite df), both arms R runs;
* ``tost``: the (1 - 2 alpha) = 90 % interval's lower bound holds the truth, i.e. the
  one-sided coverage each of the two one-sided tests relies on (nominal 0.95);
* ``wrong pass``: the share of studies whose true difference sits exactly on the budget
  (delta = budget = 1 frame sd) that the two one-sided tests still pass (nominal <= 0.05);
* ``norm``: the upper bound of the relative L2 profile distance (8 bins, a profile of
  mean 1 per bin, the CG-n arm shifted by 0.3 in the first bin) holds the true distance
  (nominal >= 0.95; the Bonferroni box makes it conservative);
* ``norm bias``: mean noise-corrected and raw distance of two arms with no difference.

Every coverage cell must lie in [0.92, 0.99]; the summary line says how many do.
The previous interval (frame bootstrap over replicas, ``intervals.frame_metric_interval``)
is measured on the R = 2 / 3 cells with ``--old`` (slow).

    .venv/bin/python benchmarks/bench_coverage.py                 # ~1-2 min
    .venv/bin/python benchmarks/bench_coverage.py --trials 1000
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys

import numpy as np

from ligwf.analysis.records.equivalence import (ALPHA, PASS, difference_estimate, equivalence,
                                                mean_estimate, norm_estimate)

LOW, HIGH = 0.92, 0.99


def ar1_runs(rng: np.random.Generator, trials: int, runs: int, frames: int, phi: float,
             offset: float, shape: tuple[int, ...] = ()) -> np.ndarray:
    """(trials, runs, frames, *shape) AR(1) frames of unit stationary sd plus a per-run
    offset of sd ``offset``, started in the stationary distribution."""
    size = (trials, runs, *shape)
    innov = math.sqrt(1.0 - phi * phi)
    x = np.empty((trials, runs, frames, *shape))
    x[:, :, 0] = rng.standard_normal(size)
    for t in range(1, frames):
        x[:, :, t] = phi * x[:, :, t - 1] + innov * rng.standard_normal(size)
    return x + offset * rng.standard_normal(size)[:, :, None]


def cell(rng, trials: int, R: int, frames: int, phi: float, offset: float) -> dict[str, float]:
    """Coverage shares of one cell."""
    a = ar1_runs(rng, trials, R, frames, phi, offset).mean(axis=2)   # (trials, R) run means
    b = ar1_runs(rng, trials, R, frames, phi, offset).mean(axis=2)
    value = diff = tost = wrong = 0
    for i in range(trials):
        e = mean_estimate(a[i], alpha=0.025)
        value += e.lo <= 0.0 <= e.hi
        d = difference_estimate(a[i], b[i], alpha=0.025)
        diff += d.lo <= 0.0 <= d.hi
        d90 = difference_estimate(a[i], b[i], alpha=ALPHA)
        tost += d90.lo <= 0.0
        # the truth on the budget: CG-n = CG1 + 1 (one frame sd), budget 1
        wrong += equivalence(difference_estimate(a[i] + 1.0, b[i], ALPHA), 1.0).state == PASS
    return {"value": value / trials, "diff": diff / trials, "tost": tost / trials,
            "wrong pass": wrong / trials}


def norm_cell(rng, trials: int, R: int, frames: int, phi: float, offset: float,
              bins: int = 8) -> dict[str, float]:
    """Coverage of the profile distance's upper bound, and its bias at no difference."""
    shift = np.zeros(bins)
    shift[0] = 0.3
    a = ar1_runs(rng, trials, R, frames, phi, offset, (bins,)).mean(axis=2) + 1.0 + shift
    b = ar1_runs(rng, trials, R, frames, phi, offset, (bins,)).mean(axis=2) + 1.0
    c = ar1_runs(rng, trials, R, frames, phi, offset, (bins,)).mean(axis=2) + 1.0
    truth = float(np.sqrt(np.sum(shift**2)) / math.sqrt(bins))
    cover = 0
    corrected, raw = [], []
    for i in range(trials):
        cover += norm_estimate(a[i], b[i]).hi >= truth
        null = norm_estimate(c[i], b[i])
        corrected.append(null.value)
        raw.append(null.raw)
    return {"norm": cover / trials, "norm bias": float(np.mean(corrected)),
            "norm raw": float(np.mean(raw))}


def old_cell(rng, trials: int, R: int, frames: int, phi: float, offset: float) -> float:
    from ligwf.analysis.records.intervals import frame_metric_interval
    x = ar1_runs(rng, trials, R, frames, phi, offset)
    hits = 0
    for i in range(trials):
        iv = frame_metric_interval(list(x[i]), (-math.inf, math.inf), 400, seed=i)
        hits += iv.lo <= 0.0 <= iv.hi
    return hits / trials


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=400)
    ap.add_argument("--seed", type=int, default=20261202)
    ap.add_argument("--old", action="store_true", help="also the previous bootstrap interval")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    rows, inside, total = [], 0, 0
    print(f"trials per cell: {args.trials}; coverage cells must lie in [{LOW}, {HIGH}]")
    head = (f"{'R':>2} {'frames':>6} {'phi':>4} {'offset':>6} | {'value':>6} {'diff':>6} "
            f"{'tost':>6} {'norm':>6} | {'wrong pass':>10} {'norm bias':>9} {'norm raw':>8}")
    print(head)
    for R, frames, phi, offset in itertools.product((2, 3, 4, 6), (10, 50, 200),
                                                    (0.3, 0.6, 0.9), (0.0, 1.0, 3.0)):
        c = cell(rng, args.trials, R, frames, phi, offset)
        c.update(norm_cell(rng, args.trials, R, frames, phi, offset))
        for k in ("value", "diff", "tost", "norm"):
            total += 1
            inside += LOW <= c[k] <= HIGH
        rows.append((R, frames, phi, offset, c))
        print(f"{R:>2} {frames:>6} {phi:>4} {offset:>6} | {c['value']:6.3f} {c['diff']:6.3f} "
              f"{c['tost']:6.3f} {c['norm']:6.3f} | {c['wrong pass']:10.3f} "
              f"{c['norm bias']:9.3f} {c['norm raw']:8.3f}", flush=True)
    worst_wrong = max(c["wrong pass"] for *_, c in rows)
    for k in ("value", "diff", "tost", "norm"):
        vals = [c[k] for *_, c in rows]
        n_in = sum(LOW <= v <= HIGH for v in vals)
        print(f"{k}: coverage {min(vals):.3f}-{max(vals):.3f}, {n_in} of {len(vals)} cells "
              f"in [{LOW}, {HIGH}]")
    print(f"wrong pass at delta = budget: at most {worst_wrong:.3f} (nominal 0.05)")
    print(f"summary: {inside} of {total} coverage cells in [{LOW}, {HIGH}]")
    if args.old:
        for R, frames, phi, offset in itertools.product((2, 3), (50,), (0.6,), (0.0, 2.0)):
            print(f"old bootstrap interval R={R} frames={frames} phi={phi} offset={offset}: "
                  f"coverage {old_cell(rng, min(args.trials, 150), R, frames, phi, offset):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
