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
from ligwf.api.results_folder import ResultsFolder, from_template, results_command  # noqa: E402
from ligwf.study import layout  # noqa: E402

RESULTS = ROOT / "docs" / "results"
#: each README's template: the prose as written by hand, ``{field}`` where a table holds
#: the number (scripts/readme_templates/NAME.md for docs/results/NAME)
TEMPLATES = Path(__file__).resolve().parent / "readme_templates"


def kept(name: str, fields, derived=None) -> ResultsFolder:
    """The kept folder docs/results/``name``: its README from its template, filled with
    ``fields(folder)``; ``derived`` the tables it recomputes."""
    return ResultsFolder(RESULTS / name, from_template(TEMPLATES / f"{name}.md", fields),
                         f"scripts/kept_results.py docs/results/{name}", derived)


# --------------------------------------------------------------------------- granules


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


GRANULES = kept("granules", granules_fields)

# ------------------------------------------------------------------------ null_splits
#: the runs split, as the study wrote them (one row per run)
NULL_CASES = f"{layout.REPORT_DIR}/{layout.CASES_REPORT}"
#: what benchmarks/bench_null_splits.py prints from them, under the command that made it
SPLITS = "splits.txt"
NULL_STUDY = ("ligwf study workflows/demo.yaml --out runs/null8 --set 'sweep.cg_levels=[2]' "
              "--set 'sweep.replicas={2: 8}' --np 1 --no-snapshots")



def null_splits_tables(folder: ResultsFolder) -> dict[str, str]:
    """splits.txt: benchmarks/bench_null_splits.py's output on the committed runs, under
    the command line that made it."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        bench_null_splits.main([str(folder.path)])
    header = (f"# .venv/bin/python benchmarks/bench_null_splits.py docs/results/null_splits   "
              f"(made from: {NULL_STUDY}; {NULL_CASES} copied here)\n")
    return {SPLITS: header + out.getvalue()}


NULL_SPLITS = kept("null_splits", lambda folder: {"study": NULL_STUDY, "cases": NULL_CASES,
                                                  "report": layout.REPORT_DIR,
                                                  "splits": SPLITS},
                   null_splits_tables)

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
