"""``ligwf stability-report STUDY_DIR`` and ``ligwf stability-suite SUITE --out DIR``.

(The pre-flight every workflow command runs before writing is part of preparing a study,
:func:`ligwf.pipeline.prepare.prepare`.)
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from ligwf.cli.common import add_mesh_cache, err_console, folder_to_write
from ligwf.fsio import atomic_write_json
from ligwf.scene.stability import MARGINAL, REFUSED

console = Console(width=None if sys.stdout.isatty() else 200)

_STYLE = {REFUSED: "bold red", MARGINAL: "yellow"}


def _fmt(value, spec: str = ".3g") -> str:
    if value is None:
        return "-"
    if isinstance(value, float) and not math.isfinite(value):
        return "inf"
    return format(value, spec)


def report_table(reports, title: str) -> Table:
    table = Table(title=title)
    for col in ("case", "pre-flight", "outcome", "agree", "atoms", "KE drift",
                "overlap obs/exp [d]", "engine dt/t_H", "reason"):
        table.add_column(escape(col), overflow="fold")
    for r in reports:
        o, pf = r.observation, r.preflight
        s_d = r.d_min
        overlap = (f"{_fmt(o.max_overlap / s_d if o.max_overlap is not None else None, '.2%')}"
                   f" / {_fmt(pf.expected_max_overlap / s_d, '.2%')}")
        atoms = f"{_fmt(o.atoms_start, '.0f')}->{_fmt(o.atoms_end, '.0f')}"
        table.add_row(r.name, f"[{_STYLE.get(pf.verdict, '')}]{pf.verdict}[/]" if pf.verdict
                      in _STYLE else pf.verdict, o.outcome,
                      "yes" if r.agrees else "[bold red]NO[/]", atoms,
                      _fmt(o.energy_drift, "+.2f"), overlap, _fmt(o.max_dt_hertz, ".2g"),
                      o.reason if o.outcome != "stable" else "; ".join(
                          f.check for f in pf.problems))
    return table


def cmd_stability_report(args: argparse.Namespace) -> int:
    from ligwf.report.stability import report_study

    reports = report_study(args.study)
    if not reports:
        err_console.print(f"ligwf: no study or case folder at or below {args.study}")
        return 2
    console.print(report_table(reports, f"stability of {args.study}: {len(reports)} case(s)"))
    disagree = [r for r in reports if not r.agrees]
    if args.json:
        atomic_write_json(args.json, [r.to_dict() for r in reports])
    for r in disagree:
        err_console.print(f"[bold red]disagreement:[/] {r.name}: pre-flight "
                          f"{r.preflight.verdict}, observed {r.observation.outcome} "
                          f"({r.observation.reason})", highlight=False)
    return 1 if disagree else 0


def cmd_stability_suite(args: argparse.Namespace) -> int:
    """Render every variant of a stress suite (refused cases included: that is the point)."""
    from ligwf.pipeline.suite import write_suite

    for variant, prepared in write_suite(args.suite, args.out, args.templates, args.mesh_cache):
        for rc, rep in zip(prepared.rendered, prepared.preflight):
            console.print(f"{variant}/{rc.case.case_id}: pre-flight {rep.verdict}",
                          highlight=False)
    return 0


def register(sub) -> None:
    p = sub.add_parser("stability-report",
                       help="per case: pre-flight verdict, observed outcome, energy drift, "
                       "max overlap observed vs expected")
    p.add_argument("study", type=Path, help="study folder (case folders below it)")
    p.add_argument("--json", type=Path, default=None, help="also write the table as JSON")
    p.set_defaults(func=cmd_stability_report)

    p = sub.add_parser("stability-suite",
                       help="render the stress suite (workflows/stability.yaml) into one "
                       "study folder per variant, refused cases included")
    p.add_argument("suite", type=Path, help="suite YAML (base scene + variants)")
    p.add_argument("--out", type=folder_to_write, required=True)
    p.add_argument("--templates", action="append", default=[], type=Path, metavar="DIR")
    add_mesh_cache(p)
    p.set_defaults(func=cmd_stability_suite)
