"""docs/results/extrapolation/: the size relation over every committed study and the
extrapolated CG1 reference checked where CG1 exists (issue 44 items 3 and 5).

Reads only committed case tables (and, with --runs, the new drums' analysed study folders);
writes size_relation.csv (one row per study, rule and CG level: the angle's excess over
CG1 against x = (n - 1) d / D), size_fit.csv (the Weber slope through the origin that
``ligwf/inference/size_relation.py`` carries as constants), validation.csv (per (drum,
rule) pair: the extrapolated 95 % interval, the form's checks, the measured CG1 mean) and
size_relation.png. ``--check`` recomputes and compares instead of writing.

    .venv/bin/python scripts/extrapolation_results.py [--runs runs] [--check]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.inference import extrapolation as ex
from ligwf.inference import size_relation as sr
from ligwf.inference.verdict import is_control_group

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from scripts.results_readme import csv_text  # noqa: E402

OUT = ROOT / "docs/results/extrapolation"
#: committed studies with CG1 and CG-n runs: (name, case tables pooled (runs seen twice
#: counted once), d / D, a flow (water-like liquid) or binder bed)
STUDIES = (
    ("we_vs_bo drum (ladder, 80-min ladder, we_vs_bo)",
     ("docs/results/we_vs_bo/cases.csv", "docs/results/ladder/cases.csv",
      "docs/results/ladder/cap_80min/cases.csv"), 0.001 / 0.05, "flow"),
    ("demo", ("docs/results/demo/cases.csv",), 0.002 / 0.05, "flow"),
    ("granules", ("docs/results/granules/cases.csv",), 0.0015 / 0.04, "binder"),
    ("gsd_cg", ("docs/results/gsd_cg/report/cases.csv",), 0.0015 / 0.04, "binder"),
)
#: (drum, rule) pairs with CG1 and two or more CG-n levels: (name, case table, d / D)
PAIRS = (
    ("ladder", "docs/results/ladder/cases.csv", 0.001 / 0.05),
    ("ladder cap_80min", "docs/results/ladder/cap_80min/cases.csv", 0.001 / 0.05),
    ("we_vs_bo", "docs/results/we_vs_bo/cases.csv", 0.001 / 0.05),
)
#: the new drums of criterion.md (run folders, analysed as amendments 3 and 4 say: each
#: case's own strips, in the hard-linked copy): (name, study folder, d / D)
NEW_PAIRS = (
    ("demo drum CG1.5-2.5", "extrapolation_demo_drum_perlevel", 0.002 / 0.05),
)
COLUMN = "angle_of_repose"


def study_cases(paths) -> pd.DataFrame:
    """The case tables pooled, control twins left out, a run seen in two tables once."""
    frames = [pd.read_csv(ROOT / p) for p in paths]
    t = pd.concat(frames, ignore_index=True)
    t = t[~t["group"].astype(str).map(is_control_group)]
    t = t.assign(_key=t[COLUMN].round(9)).drop_duplicates(["cg", "rule", "_key"])
    return t.drop(columns="_key")


def size_rows() -> pd.DataFrame:
    rows = []
    for name, paths, ratio, bed in STUDIES:
        for r in sr.excess_rows(study_cases(paths), name, ratio, COLUMN):
            rows.append(r | {"bed": bed})
    return pd.DataFrame(rows, columns=[*sr.COLUMNS, "bed"])


def size_fit(rows: pd.DataFrame) -> pd.DataFrame:
    out = []
    for label, sub in (("weber, every study", rows[rows["rule"] == "weber"]),
                       ("weber, flow beds", rows[(rows["rule"] == "weber")
                                                 & (rows["bed"] == "flow")])):
        f = sr.fit_slope(sub)
        d_over_nd = 1.0 / (sub["cg"] * sub["d_over_D"])
        out.append(dict(fit=label, slope_deg=f.slope, se=f.se, lo=f.lo, hi=f.hi,
                        birge=f.birge, rows=f.rows, d_over_nd_min=float(d_over_nd.min()),
                        d_over_nd_max=float(d_over_nd.max())))
    return pd.DataFrame(out)


def pair_row(name: str, cases: pd.DataFrame, rule: str, ratio: float) -> dict:
    t = cases[~cases["group"].astype(str).map(is_control_group)]
    ref = pd.to_numeric(t.loc[t["cg"] == 1.0, COLUMN], errors="coerce").dropna()
    arm = t[(t["rule"].astype(str) == rule) & (t["cg"] > 1.0)]
    values = {float(n): pd.to_numeric(g[COLUMN], errors="coerce").to_numpy()
              for n, g in arm.groupby("cg")}
    e = ex.extrapolate(values, ratio, alpha=0.025, slope_scale=sr.SLOPE_DEG * ratio)
    cg1 = float(ref.mean())
    return dict(pair=name, rule=rule, levels=" ".join(f"{n:g}" for n in e.levels),
                replicas=" ".join(str(r) for r in e.replicas), d_over_D=ratio,
                extrapolated=e.value, lo=e.lo, hi=e.hi, half_width=e.half_width,
                noise_se=e.se, model_term=e.model_term, df=e.df, form=e.form,
                lack_of_fit_p=e.lack_of_fit_p, observed_order=e.observed_order,
                cg1_mean=cg1, cg1_se=float(ref.std(ddof=1) / np.sqrt(len(ref))),
                cg1_replicas=len(ref), inside=bool(e.lo <= cg1 <= e.hi))


def validation(runs: Path | None) -> pd.DataFrame:
    rows = []
    for name, path, ratio in PAIRS:
        cases = pd.read_csv(ROOT / path)
        rows += [pair_row(name, cases, rule, ratio) for rule in ("weber", "bond")]
    for name, folder, ratio in NEW_PAIRS:
        table = (runs / folder / "report" / "cases.csv") if runs else None
        if table is not None and table.is_file():
            cases = pd.read_csv(table)
            rows += [pair_row(name, cases, rule, ratio) for rule in ("weber", "bond")]
    return pd.DataFrame(rows)


def figure(rows: pd.DataFrame, fit: pd.DataFrame, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for (rule, bed), sub in rows.groupby(["rule", "bed"]):
        ax.errorbar(sub["x"], sub["excess_deg"], yerr=1.96 * sub["excess_se"], fmt="o" if
                    rule == "weber" else "s", label=f"{rule}, {bed} bed", capsize=3,
                    mfc="none" if rule == "bond" else None)
    f = fit.iloc[0]
    x = np.linspace(0, rows["x"].max() * 1.05, 50)
    ax.plot(x, f["slope_deg"] * x, "k-", label=f"weber fit: {f['slope_deg']:.0f} deg x "
            f"(n - 1) d / D [{f['lo']:.0f}, {f['hi']:.0f}]")
    ax.fill_between(x, f["lo"] * x, f["hi"] * x, color="k", alpha=0.12)
    ax.axhline(0, color="grey", lw=0.5)
    ax.set_xlabel("(n - 1) d / D")
    ax.set_ylabel("angle of repose, CG-n - CG1 (deg)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)



def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=Path, default=None,
                    help="folder holding the new drums' analysed study folders")
    ap.add_argument("--check", action="store_true", help="compare, do not write")
    ap.add_argument("--no-figure", action="store_true", help="tables only")
    args = ap.parse_args(argv)
    rows = size_rows()
    fit = size_fit(rows)
    val = validation(args.runs)
    tables = {"size_relation.csv": csv_text(rows), "size_fit.csv": csv_text(fit)}
    committed = OUT / "validation.csv"
    if args.runs is None and committed.is_file():
        # without the run folders the new drums' rows are kept as committed: the committed
        # pairs' rows are recomputed, the others carried over
        kept = pd.read_csv(committed)
        kept = kept[~kept["pair"].isin([name for name, _, _ in PAIRS])]
        val = pd.concat([val, kept], ignore_index=True)
    tables["validation.csv"] = csv_text(val)
    if args.check:
        bad = [n for n, text in tables.items()
               if not (OUT / n).is_file() or (OUT / n).read_text() != text]
        print("differ: " + ", ".join(bad) if bad else "tables reproduce")
        return 1 if bad else 0
    OUT.mkdir(parents=True, exist_ok=True)
    for n, text in tables.items():
        (OUT / n).write_text(text)
    if not args.no_figure:
        figure(rows, fit, OUT / "size_relation.png")
    print(fit.to_string(index=False))
    print(val.to_string(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
