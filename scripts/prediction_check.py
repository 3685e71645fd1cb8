#!/usr/bin/env python3
"""Does "what would decide" predict the half-width it promises? (issue 30 item 4, on real runs)

The report's planning (:mod:`ligwf.inference.sampling`) predicts the half-width of a
CG-n - CG1 interval after S more seconds of production on the existing runs (only the
within-run part of each run mean's variance shrinks) or after K more replicas. This checks
both predictions on a finished study's own runs:

* **extension**: each run's steady window is cut to its first half (the state of a study
  that ran half as long); from those halves the planning predicts the half-width after the
  other half is added, and the full windows give the half-width measured. The engine is
  deterministic and a continued case resumes from its own restart, so the full window is
  what the extension would have produced.
* **replicas**: the CG-n arm's first half of its seeds predicts the half-width with the other
  half added; all of its seeds give the one measured.

Both at the single-look level (Welch, alpha 0.05: the (1 - 2 alpha) interval), per CG-n
condition and signed statistic. A prediction holds when the measured half-width is within
+-30 % of it.

    .venv/bin/python scripts/prediction_check.py runs/demo docs/results/demo/prediction_check.csv
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from benchmarks.bench_prediction import halves_within_variance
from ligwf.inference import sampling
from ligwf.api.results import open_study
from ligwf.analysis.records.statistics import MEAN, SHARE_ABOVE
from ligwf.inference.budget import signed_columns

TOLERANCE = 0.30
ALPHA = 0.05


def run_value(x: np.ndarray, spec) -> np.ndarray:
    """The per-frame quantity whose mean is the run's value (a share is a mean of 0/1)."""
    if spec.statistic == SHARE_ABOVE:
        return np.where(np.isfinite(x), (x > spec.threshold).astype(float), np.nan)
    return x


#: the within-run estimates a check can use: the planner's own, or the two-half batch means
#: of benchmarks/bench_prediction.py (a record of the alternative H5 tested, not the planner)
WITHIN = {"planner": sampling.within_variance,
          "halves": lambda s: halves_within_variance(s[np.isfinite(s)])}


def arm(series: list[np.ndarray], seconds: list[float], within=sampling.within_variance
        ) -> sampling.ArmRuns:
    values = [float(np.nanmean(s)) for s in series]
    return sampling.arm(values, [within(s) for s in series], seconds, steady_share=1.0)


def check(study: Path, within=sampling.within_variance) -> pd.DataFrame:
    results = open_study(study)
    flow, cases = results.flow_record, results.cases
    rows = []
    for column in signed_columns():
        spec = flow.metric(column)
        if spec.statistic not in (MEAN, SHARE_ABOVE):
            continue
        per_case = {}
        for cid in cases["case_id"]:
            c = flow.cases.get(cid)
            if c is None or spec.series not in c.series or len(c.times) < 4:
                continue
            x = run_value(np.array([np.nan if v is None else v for v in c.series[spec.series]],
                                   dtype=float), spec)
            t = np.asarray(c.times, float)
            step = float(np.median(np.diff(t)))
            per_case[cid] = (x, step)
        ref = [cid for cid in cases.loc[cases["cg"] == 1.0, "case_id"] if cid in per_case]
        for (cg, rule), sub in cases[cases["cg"] != 1.0].groupby(["cg", "rule"], sort=True):
            ids = [cid for cid in sub["case_id"] if cid in per_case]
            if len(ids) < 4 or len(ref) < 2:
                continue
            cond = f"cg{cg:g}-{rule}"

            def halves(which):
                ser = [per_case[c][0] for c in which]
                half = [s[: len(s) // 2] for s in ser]
                secs_half = [len(h) * per_case[c][1] for h, c in zip(half, which)]
                secs_full = [len(s) * per_case[c][1] for s, c in zip(ser, which)]
                return ser, half, secs_half, secs_full

            xs, xh, xsh, xsf = halves(ids)
            ys, yh, ysh, ysf = halves(ref)
            x_full, y_full = arm(xs, xsf, within), arm(ys, ysf, within)
            x_half, y_half = arm(xh, xsh, within), arm(yh, ysh, within)
            measured = sampling.half_width(x_full, y_full, ALPHA)
            added = (float(np.mean(np.subtract(xsf, xsh))), float(np.mean(np.subtract(ysf, ysh))))
            predicted = sampling.half_width(x_half, y_half, ALPHA, extend=added)
            rows.append(_row(cond, column, "extension", f"+{added[0]:.3g} s CG-n, "
                             f"+{added[1]:.3g} s CG1 on every run",
                             sampling.half_width(x_half, y_half, ALPHA), predicted, measured))
            k = len(ids) // 2
            x_few = arm(xs[:k], xsf[:k], within)
            predicted = sampling.half_width(x_few, y_full, ALPHA, add=(len(ids) - k, 0))
            rows.append(_row(cond, column, "replicas", f"{k} -> {len(ids)} CG-n seeds",
                             sampling.half_width(x_few, y_full, ALPHA), predicted, measured))
    return pd.DataFrame(rows)


def _row(cond, column, kind, what, before, predicted, measured) -> dict:
    ratio = measured / predicted if predicted > 0 else math.nan
    return {"condition": cond, "statistic": column, "kind": kind, "what": what,
            "half_width_before": before, "predicted_half_width": predicted,
            "measured_half_width": measured, "measured_over_predicted": ratio,
            "within_30_percent": bool(abs(ratio - 1.0) <= TOLERANCE) if math.isfinite(ratio)
            else False}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--within", choices=sorted(WITHIN), default="planner",
                    help="within-run estimate of a run mean (default: the planner's own)")
    args = ap.parse_args(argv)
    table = check(args.study, WITHIN[args.within])
    table.to_csv(args.out, index=False)
    print(table.to_string(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
