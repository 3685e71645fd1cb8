#!/usr/bin/env python3
"""docs/results/demo/: the report of `make demo` and a README whose every number is read from
its tables.

    /usr/bin/time -f %e ligwf study workflows/demo.yaml --out runs/demo     # = make demo
    .venv/bin/python scripts/demo_results.py runs/demo --wall-seconds S --machine "..."
    .venv/bin/python scripts/demo_results.py --check                # README == text from tables

The first form copies the report (tables, summary.md, index.html, figures; not the ParaView
series), writes ``timing.csv`` (the study's measured wall time and the machine it ran on)
and the README. ``--check`` (what tests/report/test_committed_demo.py runs) rebuilds the
README from the committed tables and fails when the committed README differs.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ligwf.api.results_folder import (ResultsFolder, number as _n, results_command,  # noqa: E402
                                      runs_rows, verdict_rows)
from ligwf.inference.budget import criteria  # noqa: E402
from ligwf.study import layout  # noqa: E402
from ligwf.yamlio import read_yaml_mapping  # noqa: E402

WORKFLOW = ROOT / "workflows" / "demo.yaml"
OUT = ROOT / "docs" / "results" / "demo"
#: the report files committed (the ParaView series are not)
REPORT_FILES = (layout.VERDICT_TABLE, layout.VERDICT_RECORD, layout.CASES_REPORT,
                layout.CONDITIONS_REPORT, layout.NOISE_FLOOR_REPORT, layout.FIELD_NULL_REPORT,
                layout.SUMMARY_REPORT, layout.HTML_REPORT)
#: the study's measured wall time and the machine it ran on (written by this script)
TIMING = "timing.csv"
COMMAND = "ligwf study workflows/demo.yaml --out runs/demo"
#: the flow criteria whose decisions the README counts: every criterion of the budget that
#: is not gated on the granules beating their control
FLOW = tuple(c.name for c in criteria() if not c.gated)


def scene_text(wf: dict) -> str:
    """The demo's scene in one sentence, read from the workflow file."""
    sc = wf["scene"]
    drum, part, liq, proc = sc["drum"], sc["particles"], sc["liquid"], sc["process"]
    d = [b["diameter"] for b in part["size_distribution"]]
    reps = wf["sweep"]["replicas"]
    return (f"The scene (`workflows/demo.yaml`): a {drum['diameter'] * 1e3:g} mm drum with "
            f"{drum['lifters']['count']} lifters at {proc['rotation']['rpm']:g} rpm, "
            f"{drum['length'] * 1e3:g} mm periodic slice, fill {proc['fill_fraction']:g}, "
            f"{', '.join(f'{x * 1e3:g}' for x in d)} mm beads with a water-like liquid "
            f"({liq['viscosity'] * 1e3:g} mPa s, {liq['surface_tension']:g} N/m) at CG1, "
            f"their We- and Bo-scaled CG2 stand-ins; {reps[1]} CG1 seeds and {reps[2]} of "
            f"each CG2 rule, {proc['run_time']:g} s of production. Flow only (granules need "
            "the slumping binder regime: `workflows/granules.yaml`).")


def readme(verdict: pd.DataFrame, cases: pd.DataFrame, null: pd.DataFrame,
           timing: pd.DataFrame) -> str:
    """The README text, every number from the committed tables."""
    t = timing.iloc[0]
    lines = ["# The demo study's report (`make demo`)", "",
             "Made by `make demo` (the study: `" + COMMAND + "`), then "
             "`scripts/demo_results.py runs/demo` copied the report folder's tables "
             f"(`{layout.VERDICT_TABLE}` / `{layout.VERDICT_RECORD}`, `{layout.CASES_REPORT}`, "
             f"`{layout.CONDITIONS_REPORT}`, `{layout.NOISE_FLOOR_REPORT}`, "
             f"`{layout.FIELD_NULL_REPORT}`), `{layout.SUMMARY_REPORT}`, `{layout.HTML_REPORT}` (open "
             "it in a browser: verdict first) and `figures/`, and wrote this README from "
             "them (checked by `tests/report/test_committed_demo.py`). The ParaView series "
             "are not committed.", "",
             scene_text(read_yaml_mapping(WORKFLOW, "demo workflow")), "",
             f"Wall time of the whole study (run, analysis, report) after install: "
             f"{_n(t['wall_seconds'], 4)} s ({_n(t['wall_seconds'] / 60, 2)} min) on "
             f"{t['machine']}" + ("." if bool(t["quiet"]) else
                                  ", which other work shared (light, niced): an upper bound, "
                                  "not a measure of the demo's cost on a quiet machine."),
             "", "## Runs", "",
             "| condition | runs | particles | angle of repose per run [deg] | its std over "
             "frames [deg] | rigid-block share per run | wall s per run |",
             "|---|---|---|---|---|---|---|"]
    lines += runs_rows(cases, [("angle_of_repose", ".2f"), ("angle_of_repose_std", ".2f"),
                               ("rigid_frame_share", ".2f"), ("wall_seconds", ".0f")])
    lines += ["", "## Verdict (budget: the workflow's `accept:` block, the defaults)", "",
              "| condition | speedup (core-s) | verdict | criterion | state | value [bounds] | "
              "shown within | budget |", "|---|---|---|---|---|---|---|---|"]
    lines += verdict_rows(verdict)
    lines += ["", "## Reading", ""]
    for cond, sub in verdict.groupby("condition", sort=True):
        decided = sub[sub["state"].isin(["pass", "fail"])]
        what = "; ".join(f"{r['label']} {r['state']}s ({_n(r['value'])} [{_n(r['lo'])}, "
                         f"{_n(r['hi'])}])" for _, r in decided.iterrows()) or "nothing"
        lines.append(f"- {cond}: {len(decided)} of {len(sub[sub['criterion'].isin(FLOW)])} "
                     f"flow criteria decided: {what}.")
    same = null[null["comparison"] == "CG1 vs CG1"] if "comparison" in null else null.iloc[:0]
    for _, r in same.iterrows():
        lines.append(f"- Field criterion CG1 against CG1 ({r['split']}): {_n(r['field_error'])} "
                     f"[{_n(r['field_error_lo'])}, {_n(r['field_error_hi'])}] at the "
                     f"verdict's kernel; at 1 / 2 / 4 CG1 diameters {_n(r['field_error_k1'])} / "
                     f"{_n(r['field_error_k2'])} / {_n(r['field_error_k4'])}.")
    lines.append("- A demo of the pipeline on a small scene, not a converged answer: "
                 "`docs/results/ladder/` is the decided ladder on the we_vs_bo drum.")
    return "\n".join(lines) + "\n"


def render(folder: ResultsFolder) -> str:
    return readme(folder.table(layout.VERDICT_TABLE), folder.table(layout.CASES_REPORT),
                  folder.table(layout.FIELD_NULL_REPORT), folder.table(TIMING))


FOLDER = ResultsFolder(OUT, render, "scripts/demo_results.py runs/demo --wall-seconds S")


def arguments(ap) -> None:
    ap.add_argument("--wall-seconds", type=float, help="measured wall time of the study")
    ap.add_argument("--machine", default="2 cores", help="where it ran (for timing.csv)")
    ap.add_argument("--loaded", action="store_true",
                    help="the machine was shared: the wall time is no claim")


def make(args) -> ResultsFolder:
    """Copy the study's report (and figures) and write timing.csv."""
    if args.study is None or args.wall_seconds is None:
        args.error("give the study folder and --wall-seconds (or --check)")
    FOLDER.copy_report(args.study, REPORT_FILES, figures=True)
    pd.DataFrame([{"wall_seconds": args.wall_seconds, "machine": args.machine,
                   "quiet": not args.loaded}]).to_csv(OUT / TIMING, index=False)
    return FOLDER


def main(argv=None) -> int:
    return results_command(__doc__, [FOLDER], make, argv, arguments)


if __name__ == "__main__":
    sys.exit(main())
