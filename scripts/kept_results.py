#!/usr/bin/env python3
"""The committed results folders whose runs are kept but not made again: each README is
rendered from a template with its numbers read from the folder's committed tables.

    .venv/bin/python scripts/kept_results.py docs/results/granules   # writes that README
    .venv/bin/python scripts/kept_results.py --check                 # READMEs == tables

Each folder below is a declaration: where it is, the README's template (the prose as it was
written by hand; every number a table holds is a ``{field}``) and the function that reads
those fields from the committed tables, and the tables it recomputes (``derived``).
``--check`` (what the folders' committed-results tests run) renders every README again and
compares it, and each derived table, with the committed file.
"""

from __future__ import annotations

import contextlib
import io
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks import bench_null_splits  # noqa: E402
from ligwf.api.results_folder import ResultsFolder, results_command  # noqa: E402
from ligwf.study import layout  # noqa: E402

RESULTS = ROOT / "docs" / "results"
REMAKE = "scripts/kept_results.py docs/results/NAME"

# --------------------------------------------------------------------------- granules
GRANULES_README = """\
# The binder-regime study's report (the demo until 2026-12-04, now `workflows/granules.yaml`)

This was `make demo` until 2026-12-04; its scene is now `workflows/granules.yaml` (the demo
became a rolling bed whose verdict decides: `docs/results/demo/`). Kept for its granule
controls (`{controls}`, the granule snapshots), which docs/results/granule_definitions.md
cites. Its verdict and field tables are those of the code of 2026-12-02 (before the verdict
on run means and the drum-frame field criterion).

Made with `make demo` (`ligwf study workflows/demo.yaml --out runs/demo`): the report
folder's `{summary}`, `{html}` (open it in a browser: verdict first), its tables
(`{cases}`, `{conditions}`, `{noise_floor}`, `{verdict}` / `{verdict_record}`,
`{null_check}`), `{controls}` from `runs/demo/analysis/`, and every figure under
`{figures}/`. The ParaView series (`report/paraview/`) are not committed.

How the runs were made, which matters for the costs:
- the CG2 cases and `cg1-none-r0` with its twin ran on 2026-12-01 on an otherwise idle 2-core
  machine (their engine runs were kept: `ligwf study` resumes `done` cases whose scene hash
  matches);
- `cg1-none-r1` and its twin, first run on 2026-12-02 while other sessions' tests used part of
  the machine (407 s and 477 s), were run again on 2026-12-02 at commit dadfd23 on the idle
  machine, side by side as the rank plan packs them: {r1_wall} s and {r1_twin_wall} s, against {r0_wall} s and {r0_twin_wall} s
  for seed 0 (the folders were moved aside and `ligwf study workflows/demo.yaml --out
  runs/demo` ran only those two, then analysed and reported the whole study with that
  commit's code). The engine is deterministic: every flow, field, control and GSD number
  came out as in the first run of that seed; only the costs changed (speedups {speedups}x, were
  11-12x). The single-seed cost measurement is `docs/results/performance/cg_speedup.txt`.

What it says: no CG2 level is shown to meet the default budget. Bond-CG2 fails the
continuum-field criterion (velocity field error {bond_field} against a CG1-vs-CG1 floor of
{field_floor}); We-CG2 is undecided on every flow criterion, because {replicas} seeds of 1.25 revolutions give
intervals wider than the budget, and the verdict says how many replicas would decide each one.
The GSD criterion is not assessed: the held granules did not beat their cohesionless twin
(`{controls}`). This is a demo of the pipeline, not a converged answer.
"""


def granules_fields(folder: ResultsFolder) -> dict[str, str]:
    """The granules README's numbers: the second seed's and the first seed's wall times
    (cases), the CG2 speedups and Bond-CG2's field error (verdict), the CG1-vs-CG1 field
    floor (null check)."""
    wall = folder.table(layout.CASES_REPORT).set_index("case_id")["wall_seconds"]
    verdict = folder.table(layout.VERDICT_TABLE)
    field = verdict[verdict["criterion"] == "field_error"].set_index("condition")
    bond = field.loc["cg2-bond"]
    speedups = verdict.groupby("condition")["speedup_core"].first()
    floor = folder.table(layout.FIELD_NULL_REPORT)["field_error_floor"]
    return {"r1_wall": f"{wall['cg1-none-r1']:.0f}",
            "r1_twin_wall": f"{wall['cg1-none-r1_cohesionless']:.0f}",
            "r0_wall": f"{wall['cg1-none-r0']:.0f}",
            "r0_twin_wall": f"{wall['cg1-none-r0_cohesionless']:.0f}",
            "speedups": f"{speedups.min():.0f}-{speedups.max():.0f}",
            "bond_field": f"{bond['value']:.2f} [{bond['lo']:.2f}, {bond['hi']:.2f}]",
            "field_floor": f"{floor.iloc[0]:.2g}",
            "replicas": f"{int(verdict['replicas'].iloc[0])}",
            "controls": layout.CONTROLS_TABLE, "summary": layout.SUMMARY_REPORT,
            "html": layout.HTML_REPORT, "cases": layout.CASES_REPORT,
            "conditions": layout.CONDITIONS_REPORT, "noise_floor": layout.NOISE_FLOOR_REPORT,
            "verdict": layout.VERDICT_TABLE, "verdict_record": layout.VERDICT_RECORD,
            "null_check": layout.FIELD_NULL_REPORT, "figures": layout.FIGURES_DIR}


GRANULES = ResultsFolder(RESULTS / "granules",
                         lambda folder: GRANULES_README.format(**granules_fields(folder)),
                         REMAKE.replace("NAME", "granules"))

# ------------------------------------------------------------------------ null_splits
#: the runs split, as the study wrote them (one row per run)
NULL_CASES = f"{layout.REPORT_DIR}/{layout.CASES_REPORT}"
#: what benchmarks/bench_null_splits.py prints from them, under the command that made it
SPLITS = "splits.txt"
NULL_STUDY = ("ligwf study workflows/demo.yaml --out runs/null8 --set 'sweep.cg_levels=[2]' "
              "--set 'sweep.replicas={2: 8}' --np 1 --no-snapshots")

NULL_SPLITS_README = """\
# The verdict's difference intervals on real runs with nothing to find (issue 30, item 1)

Made by (2026-12-04, beside the ladder's runs: counts, not timings):

```
{study}
cp runs/null8/{cases} docs/results/null_splits/{report}/
.venv/bin/python benchmarks/bench_null_splits.py docs/results/null_splits > {splits}   # (plus the command line on top)
```

Eight seeds of We-CG2 and eight of Bo-CG2 on the demo scene (`{cases}`, one row
per run). Each condition's seeds are split into two disjoint pseudo-conditions of R = 2, 3
and 4 runs (every unordered split once), and the report's interval of the difference
(Welch on the run means, `equivalence.difference_estimate`) is computed for each signed
criterion's statistic (angle of repose, rigid-block share, flowing-layer thickness). The
true difference is 0. `{splits}` gives, per condition, statistic and R, how many splits'
95 % and 90 % intervals hold 0, and the totals per R. The splits share runs, so they are not
independent trials: the shares say the intervals are not too narrow on real data, not
their exact coverage (`benchmarks/bench_coverage.py` measures that on synthetic studies).
`tests/report/test_committed_null_splits.py` recomputes `{splits}` from `{cases}`
and holds the 95 % totals to the issue's >= 90 %.
"""


def null_splits_tables(folder: ResultsFolder) -> dict[str, str]:
    """splits.txt: benchmarks/bench_null_splits.py's output on the committed runs, under
    the command line that made it."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        bench_null_splits.main([str(folder.path)])
    header = (f"# .venv/bin/python benchmarks/bench_null_splits.py docs/results/null_splits   "
              f"(made from: {NULL_STUDY}; {NULL_CASES} copied here)\n")
    return {SPLITS: header + out.getvalue()}


NULL_SPLITS = ResultsFolder(
    RESULTS / "null_splits",
    lambda folder: NULL_SPLITS_README.format(study=NULL_STUDY, cases=NULL_CASES,
                                             report=layout.REPORT_DIR, splits=SPLITS),
    REMAKE.replace("NAME", "null_splits"), null_splits_tables)

FOLDERS = (GRANULES, NULL_SPLITS)


def make(args) -> ResultsFolder:
    """The declared folder ``args.study`` names (its README and derived tables are
    written again from its committed tables)."""
    if args.study is None:
        args.error("give a folder (" + ", ".join(str(f.path.relative_to(ROOT))
                                                 for f in FOLDERS) + ") or --check")
    for folder in FOLDERS:
        if args.study.resolve() == folder.path:
            return folder
    args.error(f"{args.study}: not a kept results folder (" + ", ".join(
        str(f.path.relative_to(ROOT)) for f in FOLDERS) + ")")


def main(argv=None) -> int:
    return results_command(__doc__, FOLDERS, make, argv)


if __name__ == "__main__":
    sys.exit(main())
