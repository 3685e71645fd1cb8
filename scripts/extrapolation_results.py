"""docs/results/extrapolation/: the size relation over every committed study and the
extrapolated CG1 reference checked where CG1 exists (issue 44 items 3 and 5).

Reads only committed case tables (and, given RUNS, the new drums' analysed study folders
in it, through open_study, whose case and extrapolation tables it copies here); writes
size_relation.csv (one row per study, rule and CG level: the angle's excess over CG1
against x = (n - 1) d / D), size_fit.csv (the Weber slope through the origin that
``ligwf/inference/size_relation.py`` carries as constants), validation.csv (per (drum,
rule) pair: the extrapolated 95 % interval, the form's checks, the measured CG1 mean) and
size_relation.png. ``--check`` recomputes the tables from the committed case tables and
compares them byte for byte (the new drums' rows of validation.csv are carried over when
RUNS is not given).

    .venv/bin/python scripts/extrapolation_results.py [RUNS] [--check] [--no-figure]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.api.results import open_study
from ligwf.api.results_folder import ResultsFolder, csv_text, results_command
from ligwf.inference import extrapolation as ex
from ligwf.inference import size_relation as sr
from ligwf.inference.verdict import is_control_group
from ligwf.study import layout

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "docs" / "results"
OUT = RESULTS / "extrapolation"
#: the tables this folder derives
SIZE_RELATION, SIZE_FIT, VALIDATION = "size_relation.csv", "size_fit.csv", "validation.csv"
FIGURE = "size_relation.png"
#: committed studies with CG1 and CG-n runs: (name, results folders whose case tables are
#: pooled (runs seen twice counted once), d / D, a flow (water-like liquid) or binder bed)
STUDIES = (
    ("we_vs_bo drum (ladder, 80-min ladder, we_vs_bo)",
     ("we_vs_bo", "ladder", "ladder/cap_80min"), 0.001 / 0.05, "flow"),
    ("demo", ("demo",), 0.002 / 0.05, "flow"),
    ("granules", ("granules",), 0.0015 / 0.04, "binder"),
    ("gsd_cg", (f"gsd_cg/{layout.REPORT_DIR}",), 0.0015 / 0.04, "binder"),
)
#: (drum, rule) pairs with CG1 and two or more CG-n levels: (name, results folder, d / D)
PAIRS = (
    ("ladder", "ladder", 0.001 / 0.05),
    ("ladder cap_80min", "ladder/cap_80min", 0.001 / 0.05),
    ("we_vs_bo", "we_vs_bo", 0.001 / 0.05),
)
#: the new drums of criterion.md (run folders, analysed as amendments 3-5 say: each case's
#: own strips; the demo drum in its hard-linked copy): (name, study folder, d / D, the
#: prefix its copied report tables (cases, extrapolation) carry here)
NEW_PAIRS = (
    ("demo drum CG1.5-2.5", "extrapolation_demo_drum_perlevel", 0.002 / 0.05, "demo_drum_"),
    ("new drum CG1.5-2.5", "extrapolation_new_drum", 0.0025 / 0.07, "new_drum_"),
)
#: the report tables of each new drum's study copied here
NEW_COPIED = (layout.CASES_REPORT, layout.EXTRAPOLATION_REPORT)
COLUMN = "angle_of_repose"


def committed_cases(folder: str) -> pd.DataFrame:
    """The case table of the committed results folder ``folder`` (under docs/results/)."""
    return pd.read_csv(RESULTS / folder / layout.CASES_REPORT)


def study_cases(folders) -> pd.DataFrame:
    """The case tables pooled, control twins left out, a run seen in two tables once."""
    frames = [committed_cases(f) for f in folders]
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
    for name, folder, ratio in PAIRS:
        cases = committed_cases(folder)
        rows += [pair_row(name, cases, rule, ratio) for rule in ("weber", "bond")]
    for name, folder, ratio, _ in NEW_PAIRS:
        if runs is not None and (runs / folder).is_dir():
            cases = open_study(runs / folder).cases
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


def derived(folder: ResultsFolder) -> dict[str, str]:
    """The size relation, its fit and the validation from the committed case tables; the
    new drums' rows of the committed validation.csv carried over (their run folders are
    not committed)."""
    rows = size_rows()
    val = validation(None)
    kept = folder.optional_table(VALIDATION)
    if kept is not None:
        kept = kept[~kept["pair"].isin([name for name, _, _ in PAIRS])]
        val = pd.concat([val, kept], ignore_index=True)
    return {SIZE_RELATION: csv_text(rows), SIZE_FIT: csv_text(size_fit(rows)),
            VALIDATION: csv_text(val)}


FOLDER = ResultsFolder(OUT, None, "scripts/extrapolation_results.py [RUNS]", derived)


def arguments(ap) -> None:
    ap.add_argument("--no-figure", action="store_true", help="tables only")


def make(args) -> ResultsFolder:
    """With RUNS, the new drums' validation rows from their study folders; the figure."""
    if args.study is not None:
        (OUT / VALIDATION).write_text(csv_text(validation(args.study)))
        for _, folder, _, prefix in NEW_PAIRS:
            if (args.study / folder).is_dir():
                FOLDER.copy_report(args.study / folder, NEW_COPIED, prefix=prefix)
    if not args.no_figure:
        rows = size_rows()
        figure(rows, size_fit(rows), OUT / FIGURE)
    return FOLDER


def main(argv=None) -> int:
    return results_command(__doc__, [FOLDER], make, argv, arguments)


if __name__ == "__main__":
    sys.exit(main())
