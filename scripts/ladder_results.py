#!/usr/bin/env python3
"""docs/results/ladder/: the committed tables of the ladder studies and the READMEs whose
every number is read from them. Two studies: the continuation (amendments 2 and 3 of
criterion.md, in docs/results/ladder/) and the run under the 80-min cap on a quiet machine
(amendment 4, in docs/results/ladder/cap_80min/).

    ligwf study workflows/ladder.yaml --out runs/ladder --no-snapshots --until-decided --max-looks 3 --max-core-hours 2.7
    ligwf study runs/ladder --out runs/ladder --no-snapshots --until-decided --every-level --max-looks 3 --max-core-hours 6.2
    .venv/bin/python scripts/ladder_results.py runs/ladder          # copies tables, writes README
    /usr/bin/time -v -o runs/ladder80.time ligwf study workflows/ladder.yaml --out runs/ladder80 --no-snapshots --until-decided --max-looks 3 --max-core-hours 2.7
    .venv/bin/python scripts/ladder_results.py runs/ladder80 --ladder cap_80min
    ligwf report runs/ladder80 --out runs/ladder80_replanned --no-snapshots   # after 5c72b39
    .venv/bin/python scripts/ladder_results.py runs/ladder80 --ladder cap_80min --replanned runs/ladder80_replanned
    cp -a runs/ladder80 runs/ladder80_mser && ligwf analyse runs/ladder80_mser --no-vtu && ligwf report runs/ladder80_mser --no-snapshots   # after a1377ba
    .venv/bin/python scripts/ladder_results.py runs/ladder80 --ladder cap_80min --replanned runs/ladder80_replanned --reanalysed runs/ladder80_mser/report
    .venv/bin/python scripts/ladder_results.py --check               # READMEs == text from tables

``--check`` (what tests/report/test_committed_ladder.py runs) rebuilds the README from the
committed tables and fails when the committed README differs: a sentence cannot drift
from its table.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ligwf.analysis.records.steady_window import at_cap  # noqa: E402
from ligwf.api.report_compare import (beside, changed, decided, repeated_runs,  # noqa: E402
                                      wall_minutes)
from ligwf.api.results_folder import (ResultsFolder, number as _n, results_command,  # noqa: E402
                                      runs_rows, verdict_rows)
from ligwf.report.rounds import look_line  # noqa: E402
from ligwf.study import layout  # noqa: E402
from ligwf.study.rounds import read_rounds  # noqa: E402
from ligwf.yamlio import read_yaml_mapping  # noqa: E402

OUT = ROOT / "docs" / "results" / "ladder"
REPORT_FILES = (layout.VERDICT_TABLE, layout.CASES_REPORT, layout.CONDITIONS_REPORT,
                layout.SUMMARY_REPORT)
#: the registered criteria: the keys of the workflow's ``accept:`` block, committed before
#: the runs (criterion.md); the verdict also has criteria added since (the fields)
REGISTERED = tuple(read_yaml_mapping(ROOT / "workflows" / "ladder.yaml", "ladder workflow")
                   ["accept"])
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
#: the wall time of the 80-min run, the line of /usr/bin/time -v that gives it
WALL = "wall.txt"
#: the verdict of the same stored analysis re-reported with the plans' within-run part
#: bounded by the run-mean variance (5c72b39): the states are the run's, the plans today's
REPLANNED = "verdict_bounded_plans.csv"
#: the same runs re-analysed with the steady window of a1377ba (MSER-5 from 80 frames on):
#: their report's verdict and cases tables
REANALYSED = ("verdict_mser_windows.csv", "cases_mser_windows.csv")

TIMING_CONTINUATION = (
    "Timings: the first 14 runs (look 1) shared the machine with the developer's "
    "tests (niced; CG1 r1 took 6,645 core-s against r0's 3,070); the continuation's "
    "runs had the 2 cores to themselves. The CG1 runs used 2 ranks, the CG-n runs 1: "
    "the speedups (production core-seconds per simulated second, CG1 over CG-n) are "
    "indicative, not a benchmark (benchmarks/bench_cg_speedup.py is). The design was "
    "amended to two CG1 seeds before any result was analysed (criterion.md); "
    "amendment 2 registered the sequential run (`--until-decided`) before it started, "
    "amendment 3 its continuation (`--every-level`, look 1 re-taken on the same data "
    f"at the same level; look 1 as first taken: `{FIRST_LOOK}`). The same study under "
    "the registered 80-min cap on a quiet machine: [cap_80min/](cap_80min/README.md).")
TIMING_80MIN = (
    "Amendment 4 of [criterion.md](../criterion.md): amendment 2's command again, from "
    "scratch, on a quiet machine (no tests, helpers or benchmarks ran beside it; the "
    "developer only edited files), cap 2.7 core-h = 80 min of the 2 cores, default choice of "
    "what to extend (the cheapest level that can still pass). The CG1 runs used the "
    "planner's ranks; speedups are indicative (benchmarks/bench_cg_speedup.py is the "
    "benchmark). The continuation with a larger cap: [../README.md](../README.md).")


@dataclass(frozen=True)
class Ladder:
    """One committed ladder study: where its tables go and how it was made."""

    name: str                       # its --ladder name
    out: Path
    study: str                      # its run folder, as the commands name it
    commands: tuple[str, ...]
    timing: str                     # the paragraph on timings and amendments
    title: str = "The ladder: which CG level and rule keeps the flow of the we_vs_bo drum"

    @property
    def folder(self) -> ResultsFolder:
        return ResultsFolder(self.out, partial(render, self),
                             f"scripts/ladder_results.py {self.study} --ladder {self.name}")


LADDERS = {
    "continuation": Ladder("continuation", OUT, "runs/ladder", COMMANDS, TIMING_CONTINUATION),
    "cap_80min": Ladder(
        "cap_80min", OUT / "cap_80min", "runs/ladder80",
        ("/usr/bin/time -v -o runs/ladder80.time ligwf study workflows/ladder.yaml --out "
         "runs/ladder80 --no-snapshots --until-decided --max-looks 3 --max-core-hours 2.7",),
        TIMING_80MIN,
        "The ladder under its 80-min cap, on a quiet machine (criterion.md, amendment 4)"),
}


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


def readme(verdict: pd.DataFrame, cases: pd.DataFrame, rounds=None,
           ladder: Ladder = LADDERS["continuation"], wall: str | None = None,
           repeated: pd.DataFrame | None = None, replanned: pd.DataFrame | None = None,
           reanalysed: tuple[pd.DataFrame, pd.DataFrame] | None = None) -> str:
    """The README text, every number from ``verdict`` (verdict.csv), ``cases``, the
    rounds record, (``wall``) the run's ``/usr/bin/time -v`` report, (``repeated``) the
    cases.csv of the continuation whose seeds this study ran again, (``replanned``) the
    verdict of the same analysis under today's plans and (``reanalysed``) the verdict and
    cases of the same runs re-analysed with today's steady window."""
    remake = f".venv/bin/python scripts/ladder_results.py {ladder.study}" + (
        f" --ladder {ladder.name}" if ladder.name != "continuation" else "")
    criterion = "criterion.md" if ladder.out == OUT else "../criterion.md"
    lines = [f"# {ladder.title}",
             "",
             "Pre-registration (budget, statistics, looks, cap), committed before the runs: "
             f"[criterion.md]({criterion}). Made by:",
             "",
             "```", *ladder.commands, remake, "```",
             "",
             f"Tables: `{layout.VERDICT_TABLE}` (one row per CG level, rule and criterion), "
             f"`{layout.CASES_REPORT}` (one row per run), `{layout.CONDITIONS_REPORT}`, the "
             f"report's `{layout.SUMMARY_REPORT}`. This README is "
             "written from them by `scripts/ladder_results.py` and checked against them by "
             "`tests/report/test_committed_ladder.py`.",
             "",
             ladder.timing,
             *([] if wall is None else [
                 "", f"Wall time of the command (`{WALL}`, from `/usr/bin/time -v`): "
                     f"{wall_minutes(wall):.1f} min; runs in all: "
                     f"{cases['core_seconds'].sum() / 3600:.2f} core-h."]),
             "", "## Looks (`rounds.json`)", "", *rounds_lines(rounds if rounds is not None
                                                             else read_rounds(OUT / "none")),
             "", "## Runs", ""]
    lines += ["| condition | runs | particles | angle of repose per run [deg] | rigid-block "
              "share per run | core-s per run |", "|---|---|---|---|---|---|"]
    lines += runs_rows(cases, [("angle_of_repose", ".2f"), ("rigid_frame_share", ".2f"),
                               ("core_seconds", ".0f")])
    lines += ["", "## Verdict (budget: the workflow's `accept:` block)", ""]
    alpha = rounds.alpha_per_look if rounds is not None and rounds.looks else 0.05
    lines += ["| condition | speedup (core-s) | verdict | criterion | state | CG-n - CG1 "
              f"[{100 * (1 - 2 * alpha):.3g} % interval] | shown within | budget |",
              "|---|---|---|---|---|---|---|---|"]
    lines += verdict_rows(verdict)
    lines += ["", "## Reading", ""]
    flow = verdict[verdict["criterion"].isin(REGISTERED)]
    lines.append("- Flow criteria decided: {} of {} ".format(*decided(verdict, REGISTERED)) +
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
    if repeated is not None:
        lines += repeat_lines(cases, repeated)
    if replanned is not None:
        lines += replanned_lines(verdict, replanned)
    if reanalysed is not None:
        lines += reanalysed_lines(verdict, cases, *reanalysed)
    return "\n".join(lines) + "\n"


def capped(cases: pd.DataFrame) -> int:
    """How many runs' steady window starts at its cap (steady_window.at_cap)."""
    return int(cases["steady_fraction"].map(at_cap).sum())


def reanalysed_lines(verdict: pd.DataFrame, cases: pd.DataFrame, verdict_again: pd.DataFrame,
                     cases_again: pd.DataFrame) -> list[str]:
    """The same runs re-analysed with the steady window of a1377ba (MSER-5 from 80 frames
    on): windows at the cap, flow criteria decided, and each state that changed."""
    (d0, n0), (d1, n1) = decided(verdict, REGISTERED), decided(verdict_again, REGISTERED)
    lines = ["", f"## The same runs re-analysed with today's steady window (`{REANALYSED[0]}`, "
             f"`{REANALYSED[1]}`)", "",
             "A copy of the run folder analysed and reported again after a1377ba changed "
             "`steady_after: auto` to MSER-5 from 80 production frames on "
             "([../../steady/README.md](../../steady/README.md)); not the registered analysis "
             "of this ladder, whose tables are above. Windows starting at the 50 % cap: "
             f"{capped(cases)} of {len(cases)} runs before, "
             f"{capped(cases_again)} of {len(cases_again)} "
             f"now. Flow criteria decided: {d0} of {n0} before, {d1} of {n1} now. States that "
             "change:", ""]
    lines += [f"- {r['condition']} {r['label']}: {r['state']} -> {r['state_new']} "
              f"({_n(r['value_new'])} [{_n(r['lo_new'])}, {_n(r['hi_new'])}], budget "
              f"{_n(r['budget_new'])})."
              for _, r in changed(verdict, verdict_again, "state").iterrows()] or ["- none."]
    return lines


def replanned_lines(verdict: pd.DataFrame, replanned: pd.DataFrame) -> list[str]:
    """What the same stored analysis says under the plans of 5c72b39 (the within-run part
    bounded by the run-mean variance): the states, and each plan that changed."""
    both = beside(verdict, replanned)
    same = len(both) - len(changed(verdict, replanned, "state"))
    lines = ["", f"## Plans re-made with the bounded within-run part (`{REPLANNED}`)", "",
             "The same stored analysis re-reported after 5c72b39 bounded the within-run part "
             "of each arm's variance by the run-mean variance "
             "([../../prediction_check/README.md](../../prediction_check/README.md)): "
             f"{same} of {len(both)} rows keep their state (the intervals do not use the "
             "bound); the looks above were planned before it. Plans that change:", ""]
    lines += [f"- {r['condition']} {r['label']}: {r['note_new']} (was: {r['note']})."
              for _, r in changed(verdict, replanned, "note").iterrows()] or ["- none."]
    return lines


def repeat_lines(cases: pd.DataFrame, repeated: pd.DataFrame) -> list[str]:
    """How many runs of the same seed (CG level, rule, replica) in both studies give the
    same angle of repose (exactly, as cases.csv stores it), and which do not."""
    both = repeated_runs(cases, repeated, "angle_of_repose")
    same = both["same"]
    differ = "; ".join(f"cg{r['cg']:g}-{r['rule']} r{int(r['replica'])} "
                       f"({r['angle_of_repose']:.2f} deg here, "
                       f"{r['angle_of_repose_then']:.2f} in the continuation)"
                       for _, r in both[~same].iterrows())
    return [f"- The same seeds as the continuation (the engine is deterministic): "
            f"{int(same.sum())} of {len(both)} runs that both studies have give the same angle of repose to "
            f"every digit of {layout.CASES_REPORT}" + (f"; not: {differ}." if differ else ".")]


def arguments(ap) -> None:
    ap.add_argument("--ladder", choices=sorted(LADDERS), default="continuation",
                    help="which committed ladder the study folder is (default continuation)")
    ap.add_argument("--replanned", type=Path, metavar="REPORT",
                    help="a report folder of the same study made by today's planner "
                         f"(ligwf report STUDY --out REPORT): its verdict.csv -> {REPLANNED}")
    ap.add_argument("--reanalysed", type=Path, metavar="REPORT",
                    help="the report folder of a copy of the study re-analysed with today's "
                         f"steady window: its verdict.csv and cases.csv -> {', '.join(REANALYSED)}")


def make(args) -> ResultsFolder:
    """Copy the study's report tables, its rounds record and what the options name."""
    if args.study is None:
        args.error("give the study folder (or --check)")
    ladder = LADDERS[args.ladder]
    folder = ladder.folder
    if args.replanned is not None:
        folder.copy(args.replanned, layout.VERDICT_TABLE, REPLANNED)
    if args.reanalysed is not None:
        for name, target in zip((layout.VERDICT_TABLE, layout.CASES_REPORT), REANALYSED):
            folder.copy(args.reanalysed, name, target)
    folder.copy_report(args.study, REPORT_FILES)
    folder.copy(args.study, layout.ROUNDS_FILE)
    first = args.study.parent / "ladder_rounds_look1_amendment2.json"
    if ladder.out == OUT and first.is_file():
        folder.copy(first.parent, first.name, FIRST_LOOK)
    timed = args.study.parent / f"{args.study.name}.time"
    if ladder.out != OUT and timed.is_file():
        (ladder.out / WALL).write_text(next(line.strip() + "\n" for line in
                                            timed.read_text().splitlines()
                                            if "Elapsed (wall clock)" in line))
    return folder


def main(argv=None) -> int:
    committed = [ladder.folder for ladder in LADDERS.values()
                 if (ladder.out / layout.VERDICT_TABLE).exists()]
    return results_command(__doc__, committed, make, argv, arguments)


def render(ladder: Ladder, folder: ResultsFolder) -> str:
    """The README of ``ladder`` from its committed tables (in ``folder``)."""
    again = [folder.optional_table(name) for name in REANALYSED]
    wall = ladder.out / WALL
    return readme(folder.table(layout.VERDICT_TABLE), folder.table(layout.CASES_REPORT),
                  read_rounds(ladder.out), ladder,
                  wall.read_text() if wall.is_file() else None,
                  None if ladder.out == OUT else pd.read_csv(OUT / layout.CASES_REPORT),
                  folder.optional_table(REPLANNED),
                  None if any(t is None for t in again) else tuple(again))


def check(ladder: Ladder) -> int:
    """0 when the committed README of ``ladder`` is what its tables give."""
    problems = ladder.folder.check()
    for problem in problems:
        print(problem, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
