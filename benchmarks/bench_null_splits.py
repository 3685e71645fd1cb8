#!/usr/bin/env python3
"""The verdict's difference intervals on real runs with nothing to find (issue 30, item 1).

The synthetic benchmark (``bench_coverage.py``) assumes AR(1) frames and normal replica
offsets; this one takes real runs of ONE condition (R seeds of the same scene, CG level and
rule), splits them into two disjoint pseudo-conditions of R runs each, and computes the
interval the report computes for CG-n - CG1 (Welch on the run means, as
:func:`ligwf.inference.equivalence.difference_estimate`) for every signed criterion's
statistic. The true difference is 0, so the 95 % interval must hold 0 in about 95 % of the
splits (the issue asks >= 90 %), and the 90 % interval the two one-sided tests use in about
90 %. Every split of the seeds into two groups of R (unordered) is used once.

    .venv/bin/python benchmarks/bench_null_splits.py runs/null8 [runs/other ...]

Each argument is a study folder whose report has run (``report/cases.csv``); conditions with
fewer than 4 runs are skipped. Prints one row per (condition, statistic, R) and the share of
all splits, per R, whose interval holds 0.
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.inference.equivalence import difference_estimate
from ligwf.inference.budget import signed_columns
from ligwf.study import layout

#: the interval levels checked: the report's 95 % statement and the TOST's 90 % interval
LEVELS = {"95 %": 0.025, "90 %": 0.05}


def splits(n: int, r: int):
    """Every unordered split of runs 0..n-1 into two disjoint groups of r (the rest unused)."""
    seen = set()
    for a in itertools.combinations(range(n), r):
        rest = [i for i in range(n) if i not in a]
        for b in itertools.combinations(rest, r):
            key = frozenset((a, b))
            if key not in seen:
                seen.add(key)
                yield list(a), list(b)


def holds_zero(values: np.ndarray, r: int) -> dict[str, tuple[int, int]]:
    """Per level, (splits whose interval holds 0, splits with an interval)."""
    out = {name: [0, 0] for name in LEVELS}
    for a, b in splits(len(values), r):
        for name, alpha in LEVELS.items():
            e = difference_estimate(values[a], values[b], alpha)
            if math.isfinite(e.lo) and math.isfinite(e.hi):
                out[name][1] += 1
                out[name][0] += int(e.lo <= 0.0 <= e.hi)
    return {k: (v[0], v[1]) for k, v in out.items()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("studies", nargs="+", type=Path)
    args = ap.parse_args(argv)
    total: dict[tuple[int, str], list[int]] = {}
    print(f"{'condition':<14} {'statistic':<30} {'runs':>4} {'R':>2} "
          + " ".join(f"{'holds 0 (' + k + ')':>22}" for k in LEVELS))
    for study in args.studies:
        cases = pd.read_csv(study / layout.REPORT_DIR / layout.CASES_REPORT)
        for (cg, rule), sub in cases.groupby(["cg", "rule"], sort=True):
            for col in signed_columns():
                if col not in sub:
                    continue
                values = sub[col].to_numpy(float)
                values = values[np.isfinite(values)]
                for r in range(2, len(values) // 2 + 1):
                    if np.ptp(values) == 0:
                        continue          # a constant statistic (0 rigid frames): no interval
                    res = holds_zero(values, r)
                    cells = []
                    for name, (k, n) in res.items():
                        total.setdefault((r, name), [0, 0])
                        total[(r, name)][0] += k
                        total[(r, name)][1] += n
                        cells.append(f"{k:>6} of {n:<5} ({k / n:.3f})" if n else "-")
                    print(f"cg{cg:g}-{rule:<10} {col:<30} {len(values):>4} {r:>2} "
                          + " ".join(f"{c:>22}" for c in cells))
    print()
    for (r, name), (k, n) in sorted(total.items()):
        print(f"R = {r}, {name} interval: holds 0 in {k} of {n} splits ({k / n:.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
