"""docs/results/granule_screen/: the registered granule screen (issue 47 item 3,
criterion.md committed before the runs). Phase 1: one seed of each condition scored on the
four registered points, the best picked by the registered rule. Phase 2: the pick on five
seeds, each beside its cohesionless twin and a uniform twin at the pick's mean liquid
content, judged by the registered per-seed criteria (>= 4 of 5 seeds).

Writes ``growth_rows.csv`` (every start frame of every phase-1 run: held granules, survival,
co-movement, the wall test; ligwf.analysis.granules.growth), ``conditions.csv`` (one row per
condition: its measures, points and rank), and when phase 2 ran ``phase2_rows.csv`` (every
start frame of its runs) and ``phase2_seeds.csv`` (one row per seed and null); the verdict
``phase2_verdict.csv`` is derived from the seeds table, and README.md is rendered from the
committed tables (a ResultsFolder: ``--check`` recomputes both and fails when one differs).

    bash scripts/granule_screen.sh runs            # runs/granule_screen/S1..S4
    bash scripts/granule_screen_phase2.sh runs     # runs/granule_screen/P2 and P2U
    .venv/bin/python scripts/granule_screen_results.py runs/granule_screen
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

from ligwf.analysis.granules.screen import POINTS, REGISTERED, SEEDS, SETTINGS, phase2_verdict
from ligwf.analysis.granules.screen_study import measure_phase1, measure_phase2
from ligwf.api.results_folder import ResultsFolder, csv_text, number, results_command

ROOT = Path(__file__).resolve().parents[1]

OUT = ROOT / "docs" / "results" / "granule_screen"
#: the tables this script measures (named here, once); the verdict is derived from the seeds
GROWTH_ROWS, CONDITIONS_TABLE = "growth_rows.csv", "conditions.csv"
PHASE2_ROWS, PHASE2_RUNS, PHASE2_SEEDS = "phase2_rows.csv", "phase2_runs.csv", "phase2_seeds.csv"
PHASE2_VERDICT = "phase2_verdict.csv"
#: phase 1's conditions (criterion.md): (liquid model, how the liquid is placed)
CONDITIONS = {"S1": ("washino", "placed nuclei"), "S2": ("washino", "uniform"),
              "S3": ("easo", "placed nuclei"), "S4": ("easo", "uniform")}


def phase1_lines(cond: pd.DataFrame) -> list[str]:
    """The phase-1 sections of the README."""
    lines = [f"Held granules: bridges present through W = {SETTINGS.hold_time:g} s sampled "
             f"every {SETTINGS.cadence:g} s; start frames every {SETTINGS.stride:g} s from "
             f"{SETTINGS.start_after:g} s; granules of >= {SETTINGS.min_particles} particles.",
             "", "## Points (one seed each; criterion.md's phase-1 pick)", "",
             "| rank | condition | model | liquid | status | " + " | ".join(
                 f"{p} ({t})" for p, t in POINTS) + " | points |",
             "|---|---|---|---|---|" + "---|" * len(POINTS) + "---|"]
    for _, r in cond.iterrows():
        lines.append(f"| {int(r['rank'])} | {r.condition} | {r.model} | {r.liquid} | "
                     f"{r.status} | " + " | ".join("yes" if r[p] else "no" for p, _ in POINTS)
                     + f" | {int(r.points)}"
                     + (" (0: spans the slice, a wet mass; amendment 1)" if r.wet_mass else "")
                     + " |")
    lines += ["", "## Measures", "",
              "| condition | share_10 (mean / first rev / last 10 rev) | slope [1/s] (95 %) | "
              "survival | co-movement | d50 [particles] | largest | spanning frames | wall "
              "share (bed) | wet share start / end | angle [deg] | core-min |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for _, r in cond.iterrows():
        lines.append(
            f"| {r.condition} | {number(r.get('share_10'))} / "
            f"{number(r.get('share_10_first_rev'))} / {number(r.get('share_10_last'))} | "
            f"{number(r.get('slope_per_s'))} [{number(r.get('slope_low'))}, "
            f"{number(r.get('slope_high'))}] | {number(r.get('survival'))} | "
            f"{number(r.get('comove_ratio'))} | {number(r.get('d50_particles'))} | "
            f"{number(r.get('largest'))} | {number(r.get('spanning_frames'))} | "
            f"{number(r.get('wall_share'))} ({number(r.get('bed_wall_share'))}) | "
            f"{number(r.get('wet_share_start'))} / {number(r.get('wet_share_end'))} | "
            f"{number(r.get('angle_deg'))} | {number(r.core_minutes)} |")
    best = cond.iloc[0]
    total = float(cond.core_minutes.sum())
    lines += ["", f"Best by the registered rule: **{best.condition}** ({best.model}, "
              f"{best.liquid}), {int(best.points)} of {len(POINTS)} points. Phase 1 used "
              f"{total:.0f} core-minutes of the 480 budgeted for the item (cores x wall of "
              "each run, on a machine shared with other work).", ""]
    for _, r in cond[cond.status != "done"].iterrows():
        lines += [f"{r.condition} did not finish ({r.status}: {r.reason}); the registered "
                  "rule scores it 0.", ""]
    lines += ["Which ingredient failed, per condition (from the table above):", ""]
    lines += [f"- {r.condition} ({r.model}, {r.liquid}): {ingredient(r)}"
              for _, r in cond.iterrows()]
    return lines + [""]


def ingredient(r) -> str:
    """What a condition's phase-1 row says failed: no run, one wet mass, no granules,
    granules that broke, granules that did not grow, or none of these."""
    if r.status != "done":
        return "the run did not reach its end (" + str(r.status) + ")"
    wet = (f"; its beads wet went from {number(r.wet_share_start, 2)} to "
           f"{number(r.wet_share_end, 2)}")
    if bool(r.wet_mass):
        return (f"no granule population: the held bridges bound the bed into one mass "
                f"spanning the slice in {number(r.spanning_frames, 2)} of start frames "
                f"(largest {int(r.largest)} beads){wet}")
    if not bool(r.exists):
        return f"no granules formed (share_10 {number(r.share_10, 2)}){wet}"
    if not (bool(r.survives) and bool(r.comoves)):
        grew = " while share_10 grew" if bool(r.grows) else ""
        return (f"granules formed and broke{grew}: survival {number(r.survival, 2)}, "
                f"co-movement {number(r.comove_ratio, 2)}{wet}")
    if not bool(r.grows):
        return f"granules formed and survived but did not grow{wet}"
    return f"granules formed, survived, moved together and grew{wet}"


#: phase 2 (criterion.md): the uniform twin's content and the item's budget
UNIFORM_CONTENT = 0.012
BUDGET_CORE_MIN = 480.0


def phase2_lines(folder: "ResultsFolder") -> list[str]:
    """The phase-2 sections of the README (from the committed phase-2 tables)."""
    if not folder.has(PHASE2_SEEDS):
        return ["## Phase 2", "", "Not run yet.", ""]
    seeds, runs = folder.table(PHASE2_SEEDS), folder.table(PHASE2_RUNS)
    verdict = folder.table(PHASE2_VERDICT)
    cond = folder.table(CONDITIONS_TABLE)
    lines = ["## Phase 2: the pick on five seeds against two nulls", "",
             f"The pick (S3, easo, placed nuclei) on seeds r0-r{SEEDS - 1} (phase 1's r0 is r0), "
             f"each beside its cohesionless twin and a uniform twin at content "
             f"{UNIFORM_CONTENT:g} (S3 r0's mean content at its first production frame, two "
             "significant figures). A criterion passes in >= 4 of 5 seeds. Run by "
             "`bash scripts/granule_screen_phase2.sh runs`, with the uniform twins (P2U) "
             "started early beside it by the same `ligwf run` line with `--cores 1` (to fill "
             "a core the pairs left idle; a case runs in one process only, each case locks "
             "its folder).", "",
             "| criterion | registered | seeds passing | passes |", "|---|---|---|---|"]
    for _, r in verdict.iterrows():
        lines.append(f"| {r.criterion}: {r.meaning} | {'yes' if r.registered else 'reported'}"
                     f" | {int(r.seeds_pass)} of {int(r.seeds)} | "
                     f"{'yes' if r.passes else '**no**'} |")
    lines += ["", "| seed | share_10 | cohesionless | uniform | slope [1/s] (95 %) | survival "
              "| co-movement | spanning frames | wet share start / end | control | survival "
              "| growth | co-movement |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    yn = lambda v: "yes" if bool(v) else "no"  # noqa: E731
    for _, r in seeds.iterrows():
        if not bool(r.complete):
            lines.append(f"| {r.seed} | – | – | – | – | – | – | – | – | no | no | no | no |")
            continue
        lines.append(
            f"| {r.seed} | {number(r.share_10)} | {number(r.cohesionless_share_10)} | "
            f"{number(r.uniform_share_10)} | {number(r.slope_per_s)} [{number(r.slope_low)}, "
            f"{number(r.slope_high)}] | {number(r.survival)} | {number(r.comove_ratio)} | "
            f"{number(r.spanning_frames)} | {number(r.wet_share_start)} / "
            f"{number(r.wet_share_end)} | {yn(r.pass_control)} | {yn(r.pass_survival)} | "
            f"{yn(r.pass_growth)} | {yn(r.pass_comovement)} |")
    used1, used2 = float(cond.core_minutes.sum()), float(runs.core_minutes.sum())
    lines += ["", f"Phase 2 used {used2:.0f} core-minutes in {len(runs)} runs "
              f"({int((runs.status == 'done').sum())} finished); with phase 1's {used1:.0f}, "
              f"{used1 + used2:.0f} of the {BUDGET_CORE_MIN:g} budgeted.", ""]
    for _, r in runs[runs.status != "done"].iterrows():
        lines += [f"{r.case_id} did not finish ({r.status}: {r.reason}).", ""]
    found = bool(verdict[verdict.criterion == "finds_growth"].passes.iloc[0])
    failed = [r.criterion for _, r in verdict.iterrows()
              if r.registered and r.criterion != "finds_growth" and not r.passes]
    lines += ["**The screen " + ("finds growth**." if found else
              "does not find growth**: " + ", ".join(failed) + " failed the registered "
              "4-of-5 rule."), ""]
    if not found:
        lines += ["## What the engine lacks for growth here", "",
                  *lacks(seeds[seeds.complete.astype(bool)], failed), ""]
    return lines


def control_sentence(seeds: pd.DataFrame, mean) -> str:
    """Which null held too much of the wet bed's share (each judged per seed: <= 1/5)."""
    share = pd.to_numeric(seeds.share_10, errors="coerce")
    over = {name: int((pd.to_numeric(seeds[col], errors="coerce") > 0.2 * share).sum())
            for name, col in (("uniform", "uniform_share_10"),
                              ("cohesionless", "cohesionless_share_10"))}
    said = {"uniform": "**placement makes no difference**: the uniform twins at the same "
                       f"mean content hold share_10 {mean('uniform_share_10')}",
            "cohesionless": "**cohesion makes no difference**: the cohesionless twins hold "
                            f"share_10 {mean('cohesionless_share_10')}"}
    kept = {"uniform": f"the uniform twins hold {mean('uniform_share_10')}",
            "cohesionless": f"the cohesionless twins hold {mean('cohesionless_share_10')}"}
    parts = [f"{said[n]} ({over[n]} of {len(seeds)} seeds above 1/5 of the wet bed's)"
             if over[n] else f"{kept[n]} (within 1/5 in every seed)" for n in over]
    return (f"- The wet beds hold share_10 {mean('share_10')}; " + "; ".join(parts) + ".")


def lacks(seeds: pd.DataFrame, failed: list[str]) -> list[str]:
    """Per failed registered criterion, the ingredient it measures and the seeds' numbers
    (means over the complete seeds), as README bullets."""
    if seeds.empty:
        return ["- No seed has its wet run and both nulls: nothing is measured."]
    mean = lambda col: number(pd.to_numeric(seeds[col], errors="coerce").mean(), 2)  # noqa: E731
    said = {
        "control": control_sentence(seeds, mean),
        "survival": f"- **Held granules do not survive**: mean survival {mean('survival')} "
                    "(< 0.5: most member pairs are apart a quarter revolution after their "
                    "window).",
        "growth": f"- **The held share does not grow**: slope {mean('slope_per_s')} /s, its "
                  "95 % interval's lower end not above 0 in most seeds.",
        "comovement": f"- **Members do not move together**: co-movement ratio "
                      f"{mean('comove_ratio')} (> 0.5: they separate about as fast as "
                      "non-members at the same distance).",
    }
    out = [said[c] for c in failed if c in said]
    out.append(f"- Liquid leaves the nuclei: the wet share of the beads goes from "
               f"{mean('wet_share_start')} to {mean('wet_share_end')} over the run (the "
               "engine pools and splits a bridge's liquid at every rupture).")
    return out


def readme(folder: "ResultsFolder") -> str:
    """README.md from the committed tables."""
    cond = folder.table(CONDITIONS_TABLE)
    tables = (f"`{GROWTH_ROWS}` (every start frame of every phase-1 run), `{CONDITIONS_TABLE}` "
              "(one row per condition, its registered points and rank)")
    if folder.has(PHASE2_SEEDS):
        tables += (f", `{PHASE2_ROWS}` (every start frame of every phase-2 run), "
                   f"`{PHASE2_RUNS}` (each run's status and cores x wall), `{PHASE2_SEEDS}` "
                   "(one row per seed: its measures, both nulls', each criterion) and "
                   f"`{PHASE2_VERDICT}` (derived from the seeds table)")
    lines = ["# Granule screen (issue 47 item 3)", "",
             "Registered before the runs: [criterion.md](criterion.md). Made by:", "", "```",
             "bash scripts/granule_screen.sh runs",
             "bash scripts/granule_screen_phase2.sh runs",
             ".venv/bin/python scripts/granule_screen_results.py runs/granule_screen", "```",
             "", f"Tables: {tables}. This README is written from them by "
             "`scripts/granule_screen_results.py` and checked by "
             "`tests/report/test_committed_granule_screen.py`.", "", "## Phase 1", ""]
    return "\n".join(lines + phase1_lines(cond) + phase2_lines(folder))


def derived(folder: "ResultsFolder") -> dict[str, str]:
    """phase2_verdict.csv from the committed phase2_seeds.csv (when phase 2 ran)."""
    if not folder.has(PHASE2_SEEDS):
        return {}
    return {PHASE2_VERDICT: csv_text(phase2_verdict(folder.table(PHASE2_SEEDS)))}


FOLDER = ResultsFolder(OUT, readme, "scripts/granule_screen_results.py runs/granule_screen",
                       derived)


def make(args) -> ResultsFolder:
    """Measure phase 1's conditions (and phase 2 when it ran) into the folder's tables."""
    if args.study is None:
        args.error("the screen's folder is required (or --check)")
    OUT.mkdir(parents=True, exist_ok=True)
    phase1 = None if args.phase2_only else measure_phase1(args.study, CONDITIONS)
    if phase1 is not None:
        (OUT / GROWTH_ROWS).write_text(csv_text(phase1.rows))
        (OUT / CONDITIONS_TABLE).write_text(csv_text(phase1.conditions))
    phase2 = measure_phase2(args.study)
    if phase2 is not None:
        for name, t in ((PHASE2_ROWS, phase2.rows), (PHASE2_RUNS, phase2.runs),
                        (PHASE2_SEEDS, phase2.seeds)):
            (OUT / name).write_text(csv_text(t))
    return FOLDER


def arguments(ap) -> None:
    ap.add_argument("--phase2-only", action="store_true",
                    help="keep the committed phase-1 tables; measure phase 2 only")


def main(argv=None) -> int:
    return results_command(__doc__, [FOLDER], make, argv, arguments)


if __name__ == "__main__":
    sys.exit(main())
