"""docs/results/liquid_spreading/: how fast placed liquid spreads at CG1, We-CG2 and We-CG3
(issue 47 item 2), judged by the registration committed before the runs (criterion.md).

Reads the analysed study (its flow record holds each case's spreading series,
ligwf.analysis.flow.spreading), writes series.csv (per case and frame), cases.csv (per case
the spreading time), levels.csv (per level the rate ratio against CG1 with its interval,
ligwf.inference.spreading), hypotheses.csv (each registered hypothesis, met or not, per
level), a figure, and README.md. levels.csv and hypotheses.csv are derived from the
committed cases.csv (a ResultsFolder's derived tables), so ``--check`` recomputes them and the
README from the committed tables and fails when one differs.

    ligwf run workflows/liquid_spreading.yaml --out runs/liquid_spreading
    ligwf analyse runs/liquid_spreading
    .venv/bin/python scripts/liquid_spreading_results.py runs/liquid_spreading
"""

from __future__ import annotations

import io
import sys
from pathlib import Path

import pandas as pd

from ligwf.analysis.flow.spreading import DRY_FRACTION, SPREAD_LEVEL
from ligwf.analysis.records.flow import FlowRecord
from ligwf.api.results_folder import ResultsFolder, csv_text, number, results_command
from ligwf.inference.spreading import case_times, level_rates
from ligwf.study import layout

ROOT = Path(__file__).resolve().parents[1]

OUT = ROOT / "docs" / "results" / "liquid_spreading"
COMMAND = "ligwf run workflows/liquid_spreading.yaml --out runs/liquid_spreading"
#: the registered null: the largest CG1 seed-to-seed ratio of spreading times stays below it
NULL_SPREAD = 2.0
#: the tables this script measures, then the two derived from them (named here, once)
SERIES, CASES, TIMING = "series.csv", "cases.csv", "timing.csv"
LEVELS, HYPOTHESES = "levels.csv", "hypotheses.csv"


def series_table(record: FlowRecord) -> pd.DataFrame:
    rows = []
    for c in record.cases.values():
        s = c.spreading or {}
        for r, share, wet in zip(s.get("revolutions", ()), s.get("dry_content_share", ()),
                                 s.get("dry_wet_share", ())):
            rows.append({"case_id": c.case_id, "cg": float(c.cg), "rule": c.rule,
                         "replica": int(c.replica), "revolutions": r,
                         "dry_content_share": share, "dry_wet_share": wet})
    return pd.DataFrame(rows).sort_values(["cg", "replica", "revolutions"])


def hypotheses(levels: pd.DataFrame) -> pd.DataFrame:
    """Each registered hypothesis per level: H1 faster, H2 n^2, and the CG1 null."""
    rows = []
    for _, r in levels.iterrows():
        bound = " (a bound)" if r.is_bound else ""
        rows.append({"hypothesis": "H1 faster", "cg": r.cg, "met": bool(r.above_one),
                     "evidence": f"rate ratio {number(r.rate_ratio)} [{number(r.rate_ratio_low)}"
                                 f", {number(r.rate_ratio_high)}]{bound}: lower end "
                                 f"{'above' if r.above_one else 'not above'} 1"})
        rows.append({"hypothesis": "H2 n^2", "cg": r.cg, "met": bool(r.contains_expected),
                     "evidence": f"interval [{number(r.rate_ratio_low)}, "
                                 f"{number(r.rate_ratio_high)}] against n^2 = "
                                 f"{r.expected_ratio:g}: "
                                 f"{'inside' if r.contains_expected else 'outside'}{bound}"})
    if len(levels):
        spread = float(levels.cg1_spread.iloc[0])
        rows.append({"hypothesis": "null CG1 vs CG1", "cg": 1.0, "met": bool(spread < NULL_SPREAD),
                     "evidence": f"largest CG1 seed-to-seed ratio of spreading times "
                                 f"{number(spread)} against {NULL_SPREAD:g}"})
    return pd.DataFrame(rows)


def figure(series: pd.DataFrame, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharex=True)
    colours = {1.0: "k", 2.0: "tab:blue", 3.0: "tab:red"}
    for (cg, rep), g in series.groupby(["cg", "replica"]):
        kw = dict(color=colours.get(cg, "grey"), lw=1,
                  label=f"CG{cg:g}" if rep == series[series.cg == cg].replica.min() else None)
        axes[0].plot(g.revolutions, g.dry_content_share, **kw)
        axes[1].plot(g.revolutions, g.dry_wet_share, **kw)
    axes[0].axhline(SPREAD_LEVEL, color="grey", ls=":", lw=1)
    axes[0].set_ylabel("initially dry particles' share of the liquid\n(1 = uniform)")
    axes[1].set_ylabel("initially dry particles carrying liquid")
    for ax in axes:
        ax.set_xlabel("revolutions of production")
        ax.legend(frameon=False)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def findings(levels: pd.DataFrame, hyp: pd.DataFrame) -> str:
    """The measured answer in words, every number read from the tables."""
    if levels.empty:
        return "No CG-n level was run against CG1."
    faster = [f"CG{r.cg:g} {number(r.rate_ratio)} x [{number(r.rate_ratio_low)}, "
              f"{number(r.rate_ratio_high)}]" for _, r in levels.iterrows()]
    separated = [f"CG{r.cg:g}" for _, r in levels.iterrows() if r.above_one]
    rejected = [f"CG{r.cg:g} ({r.expected_ratio:g})" for _, r in levels.iterrows()
                if not r.contains_expected]
    k = ", ".join(number(v, 2) for v in levels.exponent)
    null = hyp[hyp.hypothesis == "null CG1 vs CG1"]
    null_text = ("the CG1 seeds agree with one another (null met)" if len(null)
                 and bool(null.met.iloc[0]) else "the CG1 seeds do not agree with one "
                 "another (null not met: the ratios are not separated from seed spread)")
    return (f"Placed liquid spread faster per revolution at CG-n than at CG1 in the point "
            f"estimates ({'; '.join(faster)}, rate ratio [95 %]), and {null_text}. "
            + (f"The interval lies above 1 at {', '.join(separated)} only. " if separated
               else "No level's interval lies above 1 with 3 seeds a level: faster is not "
                    "shown. ")
            + (f"The n^2 walk estimate lies outside the interval at {', '.join(rejected)}; "
               if rejected else "The n^2 walk estimate lies inside every interval; ")
            + f"the measured exponents of n are {k} (point estimates; the walk estimate "
            "is 2). The walk estimate assumed the same bridge-rupture rate per particle at "
            "every level (washino moves liquid only at a rupture); why these runs do not "
            "follow it is not measured here.")


def readme(folder: ResultsFolder) -> str:
    """README.md from the committed tables."""
    cases, levels = folder.table(CASES), folder.table(LEVELS)
    hyp, timing = folder.table(HYPOTHESES), folder.table(TIMING)
    lines = ["# Liquid spreading across CG levels (issue 47 item 2)", "",
             "Registered before the runs: [criterion.md](criterion.md) (amendment 1 replaced a "
             "null that could not fail, before any result). Made by:", "", "```", COMMAND,
             "ligwf analyse runs/liquid_spreading",
             ".venv/bin/python scripts/liquid_spreading_results.py runs/liquid_spreading",
             "```", "",
             f"Tables: `{SERIES}` (per case and production frame), `{CASES}` (per case the "
             f"spreading time), `{LEVELS}` (per level the rate against CG1), `{HYPOTHESES}` "
             f"(each registered hypothesis), `{TIMING}` (the runs' wall, on a machine shared "
             "with other work: not a benchmark). This README is written from them by "
             "`scripts/liquid_spreading_results.py` and checked against them by "
             "`tests/report/test_committed_liquid_spreading.py`.", "",
             f"Spreading time: revolutions of production until the particles dry at the first "
             f"frame (below {DRY_FRACTION:g} of the placed content) hold {SPREAD_LEVEL:g} of "
             f"their uniform share of the liquid.", "", "## Registered hypotheses", "",
             "| hypothesis | CG | met | evidence |", "|---|---|---|---|"]
    for _, r in hyp.iterrows():
        lines.append(f"| {r.hypothesis} | {r.cg:g} | {'yes' if r.met else '**no**'} | "
                     f"{r.evidence} |")
    lines += ["", "## What it says", "", findings(levels, hyp), "",
              "## Per level (against the 3 CG1 seeds)", "",
              "| CG | runs | spreading time [rev] (geometric mean) | CG1 [rev] | rate ratio "
              "[95 %] | exponent k [95 %] | n^2 |", "|---|---|---|---|---|---|---|"]
    for _, r in levels.iterrows():
        lines.append(f"| {r.cg:g} | {int(r.runs)} | {number(r.t_spread_rev_geomean)} | "
                     f"{number(r.t_spread_rev_cg1)} | {number(r.rate_ratio)} "
                     f"[{number(r.rate_ratio_low)}, {number(r.rate_ratio_high)}] | "
                     f"{number(r.exponent, 2)} [{number(r.exponent_low, 2)}, "
                     f"{number(r.exponent_high, 2)}] | {r.expected_ratio:g} |")
    lines += ["", "The interval is Welch's t on the log times of the two arms (3 and 3 runs); "
              "its coverage there is checked on synthetic log-normal times in "
              "`tests/inference/test_spreading_rates.py` (0.93-0.97), not on data like these.",
              "", "## Per run", "",
              "| case | CG | dry at start | spreading time [rev] | dry share of liquid at the "
              "end | dry particles wet at the end |", "|---|---|---|---|---|---|"]
    for _, r in cases.iterrows():
        t = number(r.t_spread_rev) + (" (not reached)" if r.censored else "")
        lines.append(f"| {r.case_id} | {r.cg:g} | {int(r.dry_particles)} of "
                     f"{int(r.particles)} | {t} | {number(r.dry_content_share_end)} | "
                     f"{number(r.dry_wet_share_end)} |")
    if len(timing):
        total = float(timing.wall_s.sum())
        lines += ["", f"Wall of the nine runs: {total / 60:.0f} min of run time summed over "
                  "runs (two at a time on 2 cores shared with other work).", ""]
    lines += ["![spreading against revolutions](spreading.png)", ""]
    return "\n".join(lines)


def timing_table(study: Path) -> pd.DataFrame:
    import json
    rows = []
    for m in sorted(study.glob("*/" + layout.MANIFEST_FILE)):
        d = json.loads(m.read_text())
        rows.append({"case_id": m.parent.name, "status": d.get("status"),
                     "wall_s": float(d.get("wall_seconds") or "nan"),
                     "core_s": float(d.get("core_seconds") or "nan")})
    return pd.DataFrame(rows)


def derived(folder: ResultsFolder) -> dict[str, str]:
    """levels.csv and hypotheses.csv, recomputed from the committed cases.csv."""
    cases = folder.table(CASES)
    levels = level_rates(cases)
    return {LEVELS: csv_text(levels),
            HYPOTHESES: csv_text(hypotheses(pd.read_csv(io.StringIO(csv_text(levels)))))}


FOLDER = ResultsFolder(OUT, readme, "scripts/liquid_spreading_results.py "
                                    "runs/liquid_spreading", derived)


def make(args) -> ResultsFolder:
    """Measure the study's series, case times and wall, then let the folder derive the rest."""
    if args.study is None:
        args.error("the study folder is required (or --check)")
    record = FlowRecord.read(args.study / layout.ANALYSIS_DIR / layout.FLOW_PROFILES)
    series = series_table(record)
    cases = case_times(record.cases.values()).sort_values(["cg", "replica"])
    OUT.mkdir(parents=True, exist_ok=True)
    for name, table in ((SERIES, series), (CASES, cases), (TIMING, timing_table(args.study))):
        (OUT / name).write_text(csv_text(table))
    figure(series, OUT / "spreading.png")
    return FOLDER


def main(argv=None) -> int:
    return results_command(__doc__, [FOLDER], make, argv)


if __name__ == "__main__":
    sys.exit(main())
