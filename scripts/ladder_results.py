#!/usr/bin/env python3
"""docs/results/ladder/: the committed tables of the ladder study and the README whose every
number is read from them.

    ligwf study workflows/ladder.yaml --out runs/ladder --no-snapshots --until-decided --max-looks 3 --max-core-hours 2.7
    ligwf study runs/ladder --out runs/ladder --no-snapshots --until-decided --every-level --max-looks 3 --max-core-hours 6.2
    .venv/bin/python scripts/ladder_results.py runs/ladder          # copies tables, writes README
    .venv/bin/python scripts/ladder_results.py --check               # README == text from tables

``--check`` (what tests/report/test_committed_ladder.py runs) rebuilds the README from the
committed tables and fails when the committed README differs: a sentence cannot drift
from its table.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ligwf.report.rounds import look_line  # noqa: E402
from ligwf.study.rounds import read_rounds  # noqa: E402
from scripts.results_readme import copy_files, number as _n, parser, write_or_check  # noqa: E402

OUT = ROOT / "docs" / "results" / "ladder"
TABLES = ("verdict.csv", "cases.csv", "conditions.csv", "summary.md")
#: the sequential study's record (in the study folder, beside report/)
ROUNDS = "rounds.json"
#: the runs' commands: the sequential run of amendment 2 (stopped at look 1, stuck), then
#: its continuation (amendment 3) on the same study folder
COMMANDS = ("ligwf study workflows/ladder.yaml --out runs/ladder --no-snapshots --until-decided "
            "--max-looks 3 --max-core-hours 2.7",
            "ligwf study runs/ladder --out runs/ladder --no-snapshots --until-decided "
            "--every-level --max-looks 3 --max-core-hours 6.2",
            "ligwf report runs/ladder --no-snapshots   # the same looks; prices at this "
            "machine's measured rates")
#: look 1 as amendment 2's run first took it (stuck), before the continuation re-took it
FIRST_LOOK = "rounds_look1_first.json"


def rounds_lines(rounds) -> list[str]:
    """The looks of the sequential study (rounds.json), as the report words them."""
    if not rounds.looks:
        return ["One look at alpha = 0.05 (no rounds record)."]
    lines = [f"At most {rounds.max_looks} looks, each at alpha {rounds.alpha_per_look:.3g} "
             f"(Bonferroni spending of {rounds.alpha:g}), Hsu's degrees of freedom; cap "
             + (f"{rounds.max_core_hours:g} core-h." if rounds.max_core_hours else "none."), ""]
    lines += [f"- {look_line(x)}" for x in rounds.looks]
    if not rounds.looks[-1].stop:
        lines += ["", f"The run was ended after look {rounds.looks[-1].number} by the session's "
                  "clock (SIGTERM), before the round it planned: the cap was not reached and "
                  "the looks were not spent. The same command on the run folder would continue "
                  "it; run folders are not committed."]
    return lines


def readme(verdict: pd.DataFrame, cases: pd.DataFrame, rounds=None) -> str:
    """The README text, every number from ``verdict`` (verdict.csv), ``cases`` and the
    rounds record."""
    lines = ["# The ladder: which CG level and rule keeps the flow of the we_vs_bo drum",
             "",
             "Pre-registration (budget, statistics, looks, cap), committed before the runs: "
             "[criterion.md](criterion.md). Made by:",
             "",
             "```", *COMMANDS, ".venv/bin/python scripts/ladder_results.py runs/ladder", "```",
             "",
             "Tables: `verdict.csv` (one row per CG level, rule and criterion), `cases.csv` "
             "(one row per run), `conditions.csv`, the report's `summary.md`. This README is "
             "written from them by `scripts/ladder_results.py` and checked against them by "
             "`tests/report/test_committed_ladder.py`.",
             "",
             "Timings: the first 14 runs (look 1) shared the machine with the developer's "
             "tests (niced; CG1 r1 took 6,645 core-s against r0's 3,070); the continuation's "
             "runs had the 2 cores to themselves. The CG1 runs used 2 ranks, the CG-n runs 1: "
             "the speedups (production core-seconds per simulated second, CG1 over CG-n) are "
             "indicative, not a benchmark (benchmarks/bench_cg_speedup.py is). The design was "
             "amended to two CG1 seeds before any result was analysed (criterion.md); "
             "amendment 2 registered the sequential run (`--until-decided`) before it started, "
             "amendment 3 its continuation (`--every-level`, look 1 re-taken on the same data "
             f"at the same level; look 1 as first taken: `{FIRST_LOOK}`).",
             "", "## Looks (`rounds.json`)", "", *rounds_lines(rounds if rounds is not None
                                                             else read_rounds(OUT / "none")),
             "", "## Runs", ""]
    runs = cases.groupby(["cg", "rule"], sort=True)
    lines += ["| condition | runs | particles | angle of repose per run [deg] | rigid-block "
              "share per run | core-s per run |", "|---|---|---|---|---|---|"]
    for (cg, rule), sub in runs:
        lines.append(f"| cg{cg:g}-{rule} | {len(sub)} | {int(sub['particles'].iloc[0]):,} | "
                     + ", ".join(f"{a:.2f}" for a in sub["angle_of_repose"]) + " | "
                     + ", ".join(f"{a:.2f}" for a in sub["rigid_frame_share"]) + " | "
                     + ", ".join(f"{a:.0f}" for a in sub["core_seconds"]) + " |")
    lines += ["", "## Verdict (budget: the workflow's `accept:` block)", ""]
    alpha = rounds.alpha_per_look if rounds is not None and rounds.looks else 0.05
    lines += ["| condition | speedup (core-s) | verdict | criterion | state | CG-n - CG1 "
              f"[{100 * (1 - 2 * alpha):.3g} % interval] | shown within | budget |",
              "|---|---|---|---|---|---|---|---|"]
    for _, r in verdict.iterrows():
        unit = f" {r['unit']}" if isinstance(r["unit"], str) and r["unit"] else ""
        lines.append(f"| {r['condition']} | {_n(r['speedup_core'])} | {r['condition_state']} | "
                     f"{r['label']} | {r['state']} | {_n(r['value'])} [{_n(r['lo'])}, "
                     f"{_n(r['hi'])}]{unit} | {_n(r['shown_within'])}{unit} | "
                     f"{_n(r['budget'])}{unit} |")
    lines += ["", "## Reading", ""]
    flow = verdict[verdict["criterion"].isin(["angle_deg", "rigid_share", "flowing_layer",
                                              "profile_error"])]
    decided = flow[flow["state"].isin(["pass", "fail"])]
    lines.append(f"- Flow criteria decided: {len(decided)} of {len(flow)} "
                 "(angle, velocity profile, rigid-block share, flowing layer of every level).")
    meets = verdict[verdict["cheapest"].astype(str) == "True"]
    if len(meets):
        c = meets.iloc[0]
        lines.append(f"- The cheapest level that meets the budget: {c['condition']} "
                     f"(speedup {_n(c['speedup_core'])}).")
    else:
        lines.append("- No level meets the whole budget. Per level, the criteria that "
                     "decidedly fail:")
        for cond, sub in verdict.groupby("condition", sort=True):
            fails = sub[sub["state"] == "fail"]
            what = "; ".join(f"{r['label']} {_n(r['value'])} [{_n(r['lo'])}, {_n(r['hi'])}]"
                             for _, r in fails.iterrows()) or "none (undecided only)"
            lines.append(f"  - {cond}: {what}")
    rigid = verdict[verdict["criterion"] == "rigid_share"].set_index("condition")["state"]
    bond_fail = [c for c in rigid.index if "bond" in c and rigid[c] == "fail"]
    weber_pass = [c for c in rigid.index if "weber" in c and rigid[c] == "pass"]
    lines.append(f"- Against the source study (We keeps the flow, Bo does not), registered on "
                 f"the rigid-block share: Bond fails it in {len(bond_fail)} of "
                 f"{sum('bond' in c for c in rigid.index)} levels, Weber passes it in "
                 f"{len(weber_pass)} of {sum('weber' in c for c in rigid.index)}.")
    open_ = flow[flow["state"] == "undecided"]
    for _, r in open_.iterrows():
        lines.append(f"- Undecided: {r['condition']} {r['label']}: {r['note']}.")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = parser(__doc__, "ladder")
    args = ap.parse_args(argv)
    if not args.check:
        if args.study is None:
            ap.error("give the study folder (or --check)")
        copy_files(args.study / "report", OUT, TABLES)
        copy_files(args.study, OUT, [ROUNDS])
        first = args.study.parent / "ladder_rounds_look1_amendment2.json"
        if first.is_file():
            copy_files(first.parent, OUT, [first.name])
            (OUT / first.name).rename(OUT / FIRST_LOOK)
    return write_or_check(OUT, lambda: readme(pd.read_csv(OUT / "verdict.csv"),
                                              pd.read_csv(OUT / "cases.csv"), read_rounds(OUT)),
                          args.check, "scripts/ladder_results.py runs/ladder")


if __name__ == "__main__":
    sys.exit(main())
