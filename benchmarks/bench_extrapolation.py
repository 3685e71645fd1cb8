"""Coverage of the extrapolated CG1 reference (ligwf.inference.extrapolation) on synthetic
ladders like ours.

A ladder: CG-n levels of one rule, each with R runs; a run's value is the mean of 50 AR(1)
frames (phi 0.9, the frames' sd growing as sqrt(n): fewer grains, noisier angle) plus a
per-run seed offset. The truth is theta(n) = 38 + b (n - 1) + c (n - 1)^2 with the size
relation's slope b = SLOPE_DEG x d / D a level (the scale the estimator's prior assumes) and a curvature c that is either drawn for each
trial from the estimator's own prior (normal, sd CURVATURE_PRIOR x (d / D) x b: a
population of drums) or held fixed (0, or 2 prior sds: one drum curving more than most).

Printed per cell: the share of trials whose 95 % interval holds the true CG1 value
(registered: every prior-drawn cell in [0.92, 0.99]), the share whose 90 % interval of
CG-n - CG1 at the coarsest level holds the true difference (what the verdict's two
one-sided tests use), the lack-of-fit check's rejection rate (three levels: at c = 0 it
should be near its 0.05), and the median half-width.

    .venv/bin/python benchmarks/bench_extrapolation.py [--trials N] [--seed S] [--out F]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_coverage import ar1_runs  # noqa: E402

from ligwf.inference import extrapolation as ex  # noqa: E402
from ligwf.inference.size_relation import SLOPE_DEG as SLOPE_SCALE  # noqa: E402

#: (name, CG levels, d / D): the ladder's drum, a 3-level small drum, the source's drum
DESIGNS = (("ladder CG2-3", (2.0, 3.0), 1 / 50), ("small drum CG2-4", (2.0, 3.0, 4.0), 1 / 25),
           ("source drum CG3/4/6", (3.0, 4.0, 6.0), 1 / 200),
           ("source drum CG4/6/8", (4.0, 6.0, 8.0), 1 / 200))
SEEDS = (2, 3, 6)
CURVATURES = ("prior", "none", "+2 sd")
FRAMES, PHI, FRAME_SD, OFFSET_SD, THETA1 = 50, 0.9, 0.8, 0.2, 38.0


def cell(rng: np.random.Generator, trials: int, levels: tuple[float, ...], d_over_D: float,
         R: int, curvature: str) -> dict[str, float]:
    """One design x replicas x curvature cell."""
    b = SLOPE_SCALE * d_over_D
    sd_c = ex.CURVATURE_PRIOR * d_over_D * b
    c = {"prior": rng.normal(0.0, sd_c, trials), "none": np.zeros(trials),
         "+2 sd": np.full(trials, 2.0 * sd_c)}[curvature]
    runs = {}
    for n in levels:
        frames = ar1_runs(rng, trials, R, FRAMES, PHI, OFFSET_SD / FRAME_SD)
        noise = FRAME_SD * math.sqrt(n / levels[0]) * frames.mean(axis=2)   # (trials, R)
        runs[n] = THETA1 + b * (n - 1.0) + c[:, None] * (n - 1.0) ** 2 + noise
    coarse = levels[-1]
    cover = diff_cover = rejected = 0
    halves = []
    for i in range(trials):
        values = {n: runs[n][i] for n in levels}
        e = ex.extrapolate(values, d_over_D, alpha=0.025, slope_scale=SLOPE_SCALE * d_over_D)
        cover += e.lo <= THETA1 <= e.hi
        halves.append(e.half_width)
        rejected += e.form == ex.REJECTED
        d = ex.level_difference(values, coarse, d_over_D, alpha=0.05,
                                slope_scale=SLOPE_SCALE * d_over_D)
        true_d = b * (coarse - 1.0) + c[i] * (coarse - 1.0) ** 2
        diff_cover += d.lo <= true_d <= d.hi
    return dict(coverage=cover / trials, diff_coverage=diff_cover / trials,
                lof_rejected=rejected / trials, half_width=float(np.median(halves)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=44)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    lines = [f"# bench_extrapolation.py --trials {args.trials} --seed {args.seed}",
             f"# curvature prior sd {ex.CURVATURE_PRIOR} per unit (n - 1) d / D; "
             f"frames {FRAMES} AR(1) phi {PHI}, frame sd {FRAME_SD} x sqrt(n / n_min) deg, "
             f"seed offset sd {OFFSET_SD} x that",
             "design\tseeds\tcurvature\tcoverage95\tdiff_coverage90\tlof_rejected\t"
             "median_half_width_deg"]
    for name, levels, ratio in DESIGNS:
        for R in SEEDS:
            for curv in CURVATURES:
                r = cell(rng, args.trials, levels, ratio, R, curv)
                lof = f"{r['lof_rejected']:.3f}" if len(levels) > 2 else "-"
                lines.append(f"{name}\t{R}\t{curv}\t{r['coverage']:.3f}\t"
                             f"{r['diff_coverage']:.3f}\t{lof}\t{r['half_width']:.3f}")
                print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    if args.out:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
