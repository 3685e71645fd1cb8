"""Measure the granule-growth study and write its committed tables and README.

    .venv/bin/python scripts/granule_growth_results.py RUNDIR docs/results/granule_growth [CALIBRATION_DIR ...]
    .venv/bin/python scripts/granule_growth_results.py --measure-finished RUNDIR
    .venv/bin/python scripts/granule_growth_results.py --check      # README == text from tables

RUNDIR is the folder of ``ligwf run workflows/granule_growth.yaml --out RUNDIR``. Writes
``growth_rows.csv`` (every start frame of every run), ``cadence.csv`` (the held share at
window cadences 0.01 / 0.02 / 0.05 s), ``flow.csv`` (angle of repose per frame), ``seeds.csv``
(one row per wet seed beside its control, each criterion judged) and
``controls_verdict.csv`` (k of n seeds per criterion), then README.md from those tables
(``tests/report/test_committed_granule_growth.py`` recomputes its numbers from them).
``--check`` renders the README from the committed tables and fails when it differs.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

from ligwf.analysis.granules.growth import GrowthSettings
from ligwf.analysis.granules.growth_study import (CRITERIA, calibration_rounds,
                                                  measure_finished, measure_study)
from ligwf.api.results_folder import ResultsFolder, csv_text, results_command
from ligwf.study.layout import CALIBRATION_TABLE

OUT = Path(__file__).resolve().parents[1] / "docs" / "results" / "granule_growth"
#: the tables this script measures (a results folder's own, not a study's)
GROWTH_ROWS = "growth_rows.csv"      # every start frame of every run
CADENCE = "cadence.csv"              # the held share at three window cadences
FRAME_FLOW = "flow.csv"              # angle of repose per frame
SEEDS = "seeds.csv"                  # one row per wet seed beside its control
SEED_VERDICT = "controls_verdict.csv"   # k of n seeds per criterion
RUNS = "cases.csv"                   # the runs

COMMAND = ("ligwf run workflows/granule_growth.yaml --out runs/granule_growth\n"
           "ligwf calibrate-control workflows/granule_growth.yaml --out runs/cal1 "
           "--reference runs/granule_growth/cg1-none-r0 --friction 0.8,1.0 "
           "--rolling-friction 0.6,1.0 --run-time 3\n"
           "ligwf calibrate-control workflows/granule_growth.yaml --out runs/cal2 "
           "--reference runs/granule_growth/cg1-none-r0 --friction 0.65 "
           "--rolling-friction 0.3,0.6 --run-time 3\n"
           ".venv/bin/python scripts/granule_growth_results.py runs/granule_growth "
           "docs/results/granule_growth runs/cal1 runs/cal2")


def _fmt(x: float, digits: int = 3) -> str:
    return "–" if pd.isna(x) else f"{x:.{digits}g}"


def calibration_lines(cal: pd.DataFrame | None) -> list[str]:
    """The flow-match calibration section (criterion.md, amendment 2) from calibration.csv."""
    if cal is None or cal.empty:
        return []
    ref = cal[cal["role"] == "wet reference"].iloc[0]
    cands = cal[cal["role"] == "candidate"]
    lines = ["", "## Flow-match calibration (criterion.md, amendment 2)", "",
             "`ligwf calibrate-control` against the wet seed r0 (its production after 30 %): "
             "cohesionless twins of 3 s production each, one row per candidate "
             "(`calibration.csv`, both rounds).", "",
             "| round | friction | rolling friction | angle [deg] | angle std [deg] | "
             "angle gap [deg] | std gap [deg] |", "|---|---|---|---|---|---|---|",
             f"| wet r0 | {ref.friction:g} | {ref.rolling_friction:g} | {ref.angle_deg:.2f} | "
             f"{ref.angle_std_deg:.2f} | – | – |"]
    for r in cands.itertuples():
        lines.append(f"| {r.round} | {r.friction:g} | {r.rolling_friction:g} | "
                     f"{r.angle_deg:.2f} | {r.angle_std_deg:.2f} | {r.angle_gap_deg:+.2f} | "
                     f"{r.std_gap_deg:+.2f} |")
    within = cands[cands["angle_gap_deg"].abs() <= 1.0]
    best = cands.loc[cands["angle_gap_deg"].abs().idxmin()]
    lines += ["", (f"- {len(within)} of {len(cands)} candidates match the wet angle within 1 deg"
                   + (f" (closest: friction {best.friction:g}, rolling friction "
                      f"{best.rolling_friction:g}, {best.angle_gap_deg:+.2f} deg)" ) + "; the "
                   f"largest angle fluctuation of any candidate is "
                   f"{cands['angle_std_deg'].max():.2f} deg against the wet bed's "
                   f"{ref.angle_std_deg:.2f} deg: friction and rolling friction "
                   + ("match the mean angle but not the slumping." if len(within) else
                      "match neither the mean angle within 1 deg nor the slumping."))]
    lo, hi = cands["angle_gap_deg"].min(), cands["angle_gap_deg"].max()
    if not len(within) and lo < 0.0 < hi:
        lines.append(f"- The candidates bracket the wet angle (gaps {lo:+.2f} to {hi:+.2f} deg): "
                     "a candidate between them would match the mean angle; the largest "
                     f"fluctuation any reaches is {cands['angle_std_deg'].max() / ref.angle_std_deg:.2f} "
                     "of the wet bed's.")
    return lines


def readme(seeds: pd.DataFrame, ver: pd.DataFrame, cad: pd.DataFrame, cases: pd.DataFrame,
           calibration: pd.DataFrame | None = None) -> str:
    """The README, every number from the tables beside it."""
    s = GrowthSettings()
    lines = [
        "# Granule growth against a control that flows like the wet bed (issue 31)",
        "",
        "Pre-registration (committed before the runs): [criterion.md](criterion.md). Made by:",
        "", "```", COMMAND, "```", "",
        f"Tables: `{SEEDS}` (one row per wet seed beside its cohesionless twin, every measure and "
        f"criterion), `{SEED_VERDICT}` (k of n seeds per criterion), `{GROWTH_ROWS}` "
        f"(every start frame), `{CADENCE}` (held share at three window cadences), `{FRAME_FLOW}` "
        f"(angle of repose per frame), `{RUNS}` (the runs). This README is written from them by "
        "`scripts/granule_growth_results.py` and checked against them by "
        "`tests/report/test_committed_granule_growth.py`.",
        "",
        f"Held granules: bridges present through W = {s.hold_time:g} s sampled every "
        f"{s.cadence:g} s; start frames every {s.stride:g} s from {s.start_after:g} s; "
        f"granules of >= {s.min_particles} particles.",
        "", "## Runs", "",
        "| case | particles | production [s] | frames | status |", "|---|---|---|---|---|",
    ]
    for r in cases.itertuples():
        lines.append(f"| {r.case_id} | {r.particles:,} | {r.production_s:g} | {r.frames} | {r.status} |")
    lines += ["", "## Verdict (criterion.md: a criterion passes in >= 4 of 5 seeds)", "",
              "| criterion | meaning | seeds passing | passes |", "|---|---|---|---|"]
    for r in ver.itertuples():
        lines.append(f"| {r.criterion} | {r.meaning} | {r.seeds_pass} of {r.seeds} | "
                     f"{'yes' if r.passes else 'no'} |")
    lines += ["", "## Per seed (wet / control)", "",
              "| seed | share_10 | first rev. | last rev. | slope [1/s] (95 %) | survival | "
              "spanning frames | wall share (bed) | co-movement | angle [deg] | angle std [deg] |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in seeds.itertuples():
        lines.append(
            f"| {r.seed} | {_fmt(r.share_10)} / {_fmt(r.control_share_10)} | "
            f"{_fmt(r.share_10_first_rev)} | {_fmt(r.share_10_last_rev)} | "
            f"{_fmt(r.slope_per_s)} [{_fmt(r.slope_low)}, {_fmt(r.slope_high)}] | "
            f"{_fmt(r.survival)} / {_fmt(r.control_survival)} | "
            f"{_fmt(r.spanning_frames)} / {_fmt(r.control_spanning_frames)} | "
            f"{_fmt(r.wall_share)} ({_fmt(r.bed_wall_share)}) / {_fmt(r.control_wall_share)} | "
            f"{_fmt(r.comove_ratio)} / {_fmt(r.control_comove_ratio)} | "
            f"{_fmt(r.angle_deg)} / {_fmt(r.control_angle_deg)} | "
            f"{_fmt(r.angle_std_deg)} / {_fmt(r.control_angle_std_deg)} |")
    lines += ["", "## Granules followed in time (wet seeds)", "",
              "Events between successive start frames (0.1 s apart), summed over the run: a "
              "granule of >= 10 particles continues, breaks, coalesces, is born or dies; "
              "particles are accreted by or eroded from continuing granules, or dispersed "
              "with a dying one.", "",
              "| seed | granules >= 10 (mean) | d50 first / last rev. [particles] | continued | "
              "born | died | broke | coalesced | accreted | eroded | dispersed |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in seeds.itertuples():
        lines.append(f"| {r.seed} | {_fmt(r.count_10)} / {_fmt(r.control_count_10)} | "
                     f"{_fmt(r.d50_first_rev)} / {_fmt(r.d50_last_rev)} | {r.continued:.0f} | "
                     f"{r.born:.0f} | {r.died:.0f} | {r.broke:.0f} | {r.coalesced:.0f} | "
                     f"{r.accreted:.0f} | {r.eroded:.0f} | {r.dispersed:.0f} |")
    lines += ["", "## Held share against the window cadence", "",
              "| case | " + " | ".join(f"{c:g} s" for c in sorted(cad.cadence.unique())) + " |",
              "|---|" + "---|" * cad.cadence.nunique()]
    for case_id, g in cad.groupby("case_id", sort=True):
        vals = g.set_index("cadence")["share_10"]
        lines.append(f"| {case_id} | " + " | ".join(_fmt(vals[c]) for c in sorted(vals.index)) + " |")
    lines += calibration_lines(calibration)
    lines += ["", "## Reading", ""] + reading(seeds, ver, cad)
    return "\n".join(lines) + "\n"


def reading(seeds: pd.DataFrame, ver: pd.DataFrame, cad: pd.DataFrame) -> list[str]:
    """The finding in sentences, each number from the tables."""
    v = ver.set_index("criterion")
    out = []
    regime = v.loc["regime"]
    if regime.passes:
        out.append(f"- The regime passes every pre-registered criterion ({regime.seeds_pass} of "
                   f"{regime.seeds} seeds pass all of them).")
    else:
        failed = [c for c, _ in CRITERIA if not v.loc[c.removeprefix("pass_")].passes]
        names = ", ".join(f"{c.removeprefix('pass_')} ({v.loc[c.removeprefix('pass_')].seeds_pass} "
                          f"of {v.loc[c.removeprefix('pass_')].seeds})" for c in failed)
        out.append(f"- The regime does not pass: it fails {names}. No granule has been shown to "
                   "exist here, so GSD transfer across CG levels stays unvalidated in this engine "
                   "for this regime.")
    fm = v.loc["flow_matched"]
    out.append(f"- The cohesionless twin flows like the wet bed (angle within 1 deg) in "
               f"{fm.seeds_pass} of {fm.seeds} seeds; angle wet / twin per seed: "
               + ", ".join(f"{_fmt(r.angle_deg)} / {_fmt(r.control_angle_deg)}"
                           for r in seeds.itertuples()) + " deg.")
    out.append("- The liquid spreads (the engine passes it on when a bridge ruptures): share of "
               "the wet bed's particles carrying liquid, first frame -> last, per seed: "
               + ", ".join(f"{_fmt(r.wet_share_start)} -> {_fmt(r.wet_share_end)}"
                           for r in seeds.itertuples()) + ".")
    out.append("- Revolutions of production measured per seed: "
               + ", ".join(f"{r.revolutions:.1f}" for r in seeds.itertuples()) + ".")
    out.append("- Held share of the bed in granules of >= 10 (wet seeds), first revolution -> "
               "last: " + ", ".join(f"{_fmt(r.share_10_first_rev)} -> {_fmt(r.share_10_last_rev)}"
                                    for r in seeds.itertuples()) + ".")
    if not cad.empty:
        means = cad.groupby("cadence")["share_10"].mean()
        out.append("- The held share depends on how densely the window is sampled (mean over "
                   "the runs, cadence: share): "
                   + ", ".join(f"{c:g} s: {_fmt(v)}" for c, v in means.items())
                   + "; the registered definition samples at a fixed 0.05 s, so it does not "
                   "depend on the dump interval (any interval dividing 0.05 s gives the same "
                   "granules).")
    return out


def render(folder: ResultsFolder) -> str:
    """The README of a granule-growth folder from its committed tables."""
    return readme(folder.table(SEEDS), folder.table(SEED_VERDICT), folder.table(CADENCE),
                  folder.table(RUNS), folder.optional_table(CALIBRATION_TABLE))


FOLDER = ResultsFolder(OUT, render, "scripts/granule_growth_results.py runs/granule_growth "
                       "docs/results/granule_growth runs/cal1 runs/cal2")


def measure(run: Path, out: Path, calibrations: tuple[str, ...] = ()) -> ResultsFolder:
    """Measure every run of the study folder ``run`` into the tables of ``out``."""
    folder = ResultsFolder(out, render, FOLDER.remake)
    out.mkdir(parents=True, exist_ok=True)
    measured = measure_study(run)
    for name, table in {GROWTH_ROWS: measured.rows, CADENCE: measured.cadence,
                        FRAME_FLOW: measured.flow, SEEDS: measured.seeds}.items():
        (out / name).write_text(csv_text(table))
    measured.verdict.to_csv(out / SEED_VERDICT, index=False)
    measured.runs.to_csv(out / RUNS, index=False)
    if calibrations:
        (out / CALIBRATION_TABLE).write_text(
            csv_text(calibration_rounds(tuple(Path(c) for c in calibrations))))
    print(folder.table(SEED_VERDICT).to_string(index=False))
    return folder


def arguments(ap) -> None:
    ap.add_argument("out", nargs="?", type=Path, help="the results folder to write")
    ap.add_argument("calibrations", nargs="*", help="calibrate-control output folders")
    ap.add_argument("--measure-finished", action="store_true",
                    help="only measure (and cache) the runs of STUDY that are done")


def make(args) -> ResultsFolder | None:
    """Measure the run folder into the results folder (None: --measure-finished only
    caches the measures of the runs that are done)."""
    if args.study is None or (args.out is None and not args.measure_finished):
        args.error("give the run folder and the results folder (or --check)")
    if args.measure_finished:
        measure_finished(args.study)
        return None
    return measure(args.study, args.out, tuple(args.calibrations))


def main(argv=None) -> int:
    return results_command(__doc__, [FOLDER], make, argv, arguments)


if __name__ == "__main__":
    sys.exit(main())
