"""docs/results/liquid_spreading/: how fast placed liquid spreads at CG1, We-CG2 and We-CG3
(issue 47 item 2), judged by the registration committed before the runs (criterion.md).

Reads the analysed study (its flow record holds each case's spreading series,
ligwf.analysis.flow.spreading), writes series.csv (per case and frame), cases.csv (per case
the spreading time), levels.csv (per level the rate ratio against CG1 with its interval,
ligwf.inference.spreading), hypotheses.csv (each registered hypothesis, met or not, per
level), a figure, and README.md from those tables; ``--check`` rebuilds the README from the
committed tables and fails when it differs.

    ligwf run workflows/liquid_spreading.yaml --out runs/liquid_spreading
    ligwf analyse runs/liquid_spreading
    .venv/bin/python scripts/liquid_spreading_results.py runs/liquid_spreading
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_readme import ROOT, csv_text, number, parser, write_or_check  # noqa: E402

from ligwf.analysis.flow.spreading import DRY_FRACTION, SPREAD_LEVEL  # noqa: E402
from ligwf.analysis.records.flow import FlowRecord  # noqa: E402
from ligwf.inference.spreading import case_times, level_rates  # noqa: E402
from ligwf.study import layout  # noqa: E402

OUT = ROOT / "docs" / "results" / "liquid_spreading"
COMMAND = "ligwf run workflows/liquid_spreading.yaml --out runs/liquid_spreading"
#: the registered null: the largest CG1 seed-to-seed ratio of spreading times stays below it
NULL_SPREAD = 2.0


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
                                 f", {number(r.rate_ratio_high)}]{bound}, lower end above 1"})
        rows.append({"hypothesis": "H2 n^2", "cg": r.cg, "met": bool(r.contains_expected),
                     "evidence": f"interval [{number(r.rate_ratio_low)}, "
                                 f"{number(r.rate_ratio_high)}] against n^2 = "
                                 f"{r.expected_ratio:g}{bound}"})
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


def readme(cases: pd.DataFrame, levels: pd.DataFrame, hyp: pd.DataFrame,
           timing: pd.DataFrame) -> str:
    lines = ["# Liquid spreading across CG levels (issue 47 item 2)", "",
             "Registered before the runs: [criterion.md](criterion.md) (amendment 1 replaced a "
             "null that could not fail, before any result). Made by:", "", "```", COMMAND,
             "ligwf analyse runs/liquid_spreading",
             ".venv/bin/python scripts/liquid_spreading_results.py runs/liquid_spreading",
             "```", "",
             "Tables: `series.csv` (per case and production frame), `cases.csv` (per case the "
             "spreading time), `levels.csv` (per level the rate against CG1), `hypotheses.csv` "
             "(each registered hypothesis), `timing.csv` (the runs' wall, on a machine shared "
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
    lines += ["", "## Per level (against the 3 CG1 seeds)", "",
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


def main() -> int:
    args = parser(__doc__, "liquid-spreading").parse_args()
    if args.check:
        read = {n: pd.read_csv(OUT / f"{n}.csv") for n in ("cases", "levels", "hypotheses",
                                                            "timing")}
        return write_or_check(OUT, lambda: readme(read["cases"], read["levels"],
                                                  read["hypotheses"], read["timing"]),
                              True, "scripts/liquid_spreading_results.py")
    record = FlowRecord.read(args.study / layout.ANALYSIS_DIR / layout.FLOW_PROFILES)
    series = series_table(record)
    cases = case_times(record.cases.values()).sort_values(["cg", "replica"])
    levels = level_rates(cases)
    hyp = hypotheses(levels)
    timing = timing_table(args.study)
    OUT.mkdir(parents=True, exist_ok=True)
    for name, table in (("series", series), ("cases", cases), ("levels", levels),
                        ("hypotheses", hyp), ("timing", timing)):
        (OUT / f"{name}.csv").write_text(csv_text(table))
    figure(series, OUT / "spreading.png")
    # the README from the tables as committed (rounded), so --check reproduces it
    read = {n: pd.read_csv(OUT / f"{n}.csv") for n in ("cases", "levels", "hypotheses",
                                                        "timing")}
    return write_or_check(OUT, lambda: readme(read["cases"], read["levels"],
                                              read["hypotheses"], read["timing"]),
                          False, "scripts/liquid_spreading_results.py")


if __name__ == "__main__":
    sys.exit(main())
