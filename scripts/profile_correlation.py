"""docs/results/profile_correlation/: how strongly a seed's velocity-profile error is shared
between depth bins, measured on real profiles (issue 45 item 2: the profile bounds' degrees
of freedom assume independent bins; a seed that moves the flowing layer moves many bins).

For each analysed study: within every condition (group, rule, CG level) with >= 2 seeds,
each seed's steady-window mean profile minus the condition's mean; the pooled covariance of
those residuals over conditions (each condition gives seeds - 1 degrees of freedom); its
correlation matrix over the bins every seed measured. Reported per study: the mean
correlation of bins k apart (k = 1, 2, 4, 8), the mean over all pairs, and the effective
number of independent bins B_eff = (sum of eigenvalues)^2 / sum of squared eigenvalues of
the correlation matrix (B for independent bins, 1 for one shared shift). ``--check``
rebuilds the README from the committed table.

    .venv/bin/python scripts/profile_correlation.py runs/paper_scale_cg runs/paper_scale_cg_bond
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.api.results_folder import ResultsFolder, check_all, csv_text, number
from ligwf.study import layout

OUT = Path(__file__).resolve().parents[1] / "docs" / "results" / "profile_correlation"
#: the table this script measures (named here, once)
CORRELATION = "correlation.csv"
LAGS = (1, 2, 4, 8)


def residuals(record: dict) -> tuple[np.ndarray, int, int, int]:
    """(residual rows over the bins every seed measured, degrees of freedom, conditions,
    seeds) of one study's flow record."""
    by_cond: dict[tuple, list[np.ndarray]] = {}
    for c in record["cases"].values():
        prof = c.get("profile_v_mean") or []
        if not prof:
            continue
        v = np.array([np.nan if x is None else float(x) for x in prof])
        if not np.isfinite(v).any():
            continue
        key = (json.dumps(c["group"], sort_keys=True), c["rule"], float(c["cg"]))
        by_cond.setdefault(key, []).append(v)
    conds = {k: np.vstack(v) for k, v in by_cond.items() if len(v) >= 2}
    if not conds:
        return np.empty((0, 0)), 0, 0, 0
    width = min(a.shape[1] for a in conds.values())
    stack = np.vstack([a[:, :width] for a in conds.values()])
    keep = np.all(np.isfinite(stack), axis=0)
    rows, dof, seeds = [], 0, 0
    for a in conds.values():
        a = a[:, :width][:, keep]
        rows.append(a - a.mean(axis=0))
        dof += len(a) - 1
        seeds += len(a)
    return np.vstack(rows), dof, len(conds), seeds


def effective_bins(res: np.ndarray, dof: int) -> tuple[np.ndarray, float]:
    """(correlation matrix, effective number of independent bins) of residual rows."""
    cov = res.T @ res / dof
    sd = np.sqrt(np.diag(cov))
    ok = sd > 0
    corr = cov[np.ix_(ok, ok)] / np.outer(sd[ok], sd[ok])
    eig = np.linalg.eigvalsh(corr)
    return corr, float(eig.sum() ** 2 / (eig ** 2).sum())


def null_effective_bins(sizes: list[int], bins: int, trials: int = 2000,
                        seed: int = 20261207) -> tuple[float, float, float]:
    """The null: independent, equal-variance bins in the same design (conditions of the
    same seed counts, residuals about each condition's mean); (median effective bins, its
    97.5 % quantile, median lag-1 correlation). Few degrees of freedom bound the estimate
    (rank <= dof), so the measured value is judged against this, not against ``bins``."""
    rng = np.random.default_rng(seed)
    eff, lag1 = [], []
    for _ in range(trials):
        rows = []
        for n in sizes:
            a = rng.standard_normal((n, bins))
            rows.append(a - a.mean(axis=0))
        corr, e = effective_bins(np.vstack(rows), sum(n - 1 for n in sizes))
        eff.append(e)
        lag1.append(np.mean(np.diag(corr, 1)))
    return (float(np.median(eff)), float(np.quantile(eff, 0.025)),
            float(np.median(lag1)))


def _sizes(record: dict) -> list[int]:
    """Seeds per condition with >= 2 seeds' profiles (the design of :func:`residuals`)."""
    counts: dict[tuple, int] = {}
    for c in record["cases"].values():
        v = [x for x in (c.get("profile_v_mean") or []) if x is not None]
        if v:
            key = (json.dumps(c["group"], sort_keys=True), c["rule"], float(c["cg"]))
            counts[key] = counts.get(key, 0) + 1
    return [n for n in counts.values() if n >= 2]


def correlation_row(name: str, record: dict) -> dict:
    res, dof, conds, seeds = residuals(record)
    bins = res.shape[1]
    cov = res.T @ res / dof
    sd = np.sqrt(np.diag(cov))
    ok = sd > 0
    corr = cov[np.ix_(ok, ok)] / np.outer(sd[ok], sd[ok])
    b = corr.shape[0]
    eig = np.linalg.eigvalsh(corr)
    null_eff, null_low, null_lag1 = null_effective_bins(_sizes(record), b)
    row = {"study": name, "conditions": conds, "seeds": seeds, "dof": dof, "bins": b,
           "null_effective_bins": null_eff, "null_effective_bins_low": null_low,
           "null_mean_corr_lag1": null_lag1,
           "mean_corr_all": float(corr[~np.eye(b, dtype=bool)].mean()),
           "effective_bins": float(eig.sum() ** 2 / (eig ** 2).sum()),
           "largest_eigen_share": float(eig.max() / eig.sum())}
    for k in LAGS:
        row[f"mean_corr_lag{k}"] = (float(np.mean(np.diag(corr, k))) if k < b else np.nan)
    return row


def readme(table: pd.DataFrame) -> str:
    lines = ["# Velocity-profile errors are shared between depth bins (issue 45 item 2)", "",
             "Measured on real profiles: within every condition with >= 2 seeds, each seed's "
             "steady-window mean downhill-velocity profile minus the condition's mean; the "
             "correlation of those residuals between depth bins, pooled over conditions. Made "
             "by:", "", "```",
             ".venv/bin/python scripts/profile_correlation.py runs/paper_scale_cg "
             "runs/paper_scale_cg_bond", "```", "",
             "The source drum's studies (docs/results/paper_scale): We-CG4/6/8 and Bo-CG4/6, "
             "3 seeds each, 16 depth bins.", "",
             f"Table: `{CORRELATION}` (one row per study). This README is written from it by "
             "`scripts/profile_correlation.py` and checked by "
             "`tests/report/test_committed_profile_correlation.py`.", "",
             "The null beside each row: the same design (conditions, seeds, bins) with "
             "independent bins of equal variance, 2,000 draws: few degrees of freedom bound the "
             "estimate (the matrix has rank <= dof), so the measured count is judged against "
             "the null's, not against the number of bins.", "",
             "| study | conditions | seeds (dof) | bins | mean correlation, bins 1 / 2 / 4 / 8 "
             "apart | all pairs | effective independent bins | null: effective bins, median "
             "[2.5 %] | null: lag-1 correlation | largest eigenvalue's share |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for _, r in table.iterrows():
        lags = " / ".join(number(r[f"mean_corr_lag{k}"], 2) for k in LAGS)
        lines.append(f"| {r.study} | {int(r.conditions)} | {int(r.seeds)} ({int(r.dof)}) | "
                     f"{int(r.bins)} | {lags} | {number(r.mean_corr_all, 2)} | "
                     f"{number(r.effective_bins, 2)} | {number(r.null_effective_bins, 2)} "
                     f"[{number(r.null_effective_bins_low, 2)}] | "
                     f"{number(r.null_mean_corr_lag1, 2)} | "
                     f"{number(r.largest_eigen_share, 2)} |")
    below = table[table.effective_bins < table.null_effective_bins_low]
    lines += ["", f"In {len(below)} of {len(table)} studies the measured effective count lies "
              "below the 2.5 % quantile of its independent-bin null: "
              + ("a seed's error moves whole stretches of the profile together (neighbouring "
                 "bins correlate at " + ", ".join(number(v, 2) for v in table.mean_corr_lag1)
                 + "), so bounds whose degrees of freedom count bins as independent are too "
                 "narrow." if len(below) else "independence between bins is not rejected "
                 "on these data.")
              + " `benchmarks/bench_coverage.py --profiles` sizes its correlated-bin noise "
              "from this table (`benchmarks/profile_designs.py`; its result: "
              "[verdict_rates](../verdict_rates/README.md), `profiles.txt`).", ""]
    return "\n".join(lines)


FOLDER = ResultsFolder(OUT, lambda folder: readme(folder.table(CORRELATION)),
                       "scripts/profile_correlation.py STUDY...")


def main(argv=None) -> int:
    """``STUDY...`` measures the studies' table and writes the README; ``--check`` renders
    the README from the committed table and fails (1) when it differs."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("studies", nargs="*", type=Path, help="the analysed studies")
    ap.add_argument("--check", action="store_true",
                    help="only check that the committed README is what its table gives")
    args = ap.parse_args(argv)
    if args.check:
        problems = check_all([FOLDER])
        for problem in problems:
            print(problem, file=sys.stderr)
        return 1 if problems else 0
    rows = []
    for study in args.studies:
        record = json.loads((study / layout.ANALYSIS_DIR / layout.FLOW_PROFILES).read_text())
        if residuals(record)[1] == 0:
            print(f"{study}: no condition with two seeds' profiles, left out", file=sys.stderr)
            continue
        rows.append(correlation_row(study.name, record))
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / CORRELATION).write_text(csv_text(pd.DataFrame(rows)))
    print(FOLDER.write())
    return 0


if __name__ == "__main__":
    sys.exit(main())
