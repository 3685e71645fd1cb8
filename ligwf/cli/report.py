"""``ligwf report STUDY``: the flow metrics and the report folder of a finished study
(:func:`ligwf.pipeline.post.report_study`), and a sequential study's look as every command
that takes one shows it; this module parses and prints."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from rich.table import Table

from ligwf.cli.common import console, err_console, folder_to_write
from ligwf.pipeline.post import report_study
from ligwf.report.rounds import look_line
from ligwf.study import layout
from ligwf.study.rounds import Look, Rounds
from ligwf.study.study import Study


def print_report(study_dir: Path, out: Path) -> None:
    """Where the report is, its verdict, and on stderr how much it lists as not used."""
    from ligwf.report.problems import study_problems
    from ligwf.inference.verdict_records import read_verdict
    from ligwf.report.verdict_text import verdict_renderables

    console.print(f"report: {out / layout.SUMMARY_REPORT} and {out / layout.HTML_REPORT}")
    p = study_problems(Study.open(study_dir))
    if p.count:
        err_console.print(f"[yellow]ligwf: warning:[/] the report lists {len(p.cases)} skipped "
                          f"case(s), {len(p.frames)} skipped or missing frame(s) and "
                          f"{len(p.outputs)} analysis output problem(s) (see {layout.SUMMARY_REPORT})",
                          highlight=False)
    verdict = read_verdict(out)
    if verdict is not None:   # last: the answer is what the user reads
        for item in verdict_renderables(verdict):
            console.print(item, highlight=False)


def show_look(look: Look, rounds: Rounds) -> None:
    """A look on the terminal: every interval against its budget, the half-width beside
    the previous look's (the intervals shrinking), then what the next round does."""
    before = {(c["condition"], c["criterion"]): c for x in rounds.looks
              if x.number == look.number - 1 for c in x.criteria}
    table = Table(title=f"look {look.number} of at most {rounds.max_looks}", box=None)
    for col in ("condition", "criterion", "state", "value [interval]", "half-width",
                "previous", "budget"):
        table.add_column(col)
    for c in look.criteria:
        lo, hi = c.get("lo"), c.get("hi")
        half = 0.5 * (hi - lo) if lo is not None and hi is not None and math.isfinite(lo) \
            and math.isfinite(hi) else math.nan
        p = before.get((c["condition"], c["criterion"]))
        prev = (0.5 * (p["hi"] - p["lo"]) if p and p.get("lo") is not None
                and p.get("hi") is not None else math.nan)
        band = (f"{c['value']:.3g} [{lo:.3g}, {hi:.3g}]" if math.isfinite(half)
                else f"{c.get('value', math.nan):.3g}")
        table.add_row(c["condition"], c["label"], c["state"], band,
                      f"{half:.3g}" if math.isfinite(half) else "–",
                      f"{prev:.3g}" if math.isfinite(prev) else "–",
                      f"{c.get('budget', math.nan):.3g}")
    console.print(table)
    console.print(look_line(look), highlight=False, soft_wrap=True)


def cmd_report(args: argparse.Namespace) -> int:
    print_report(args.study, report_study(args.study, args.out, snapshots=not args.no_snapshots,
                                          accept_overrides=tuple(args.overrides)))
    return 0


def add_snapshots(p: argparse.ArgumentParser) -> None:
    p.add_argument("--no-snapshots", action="store_true",
                   help="skip the pyvista snapshots (the slowest figures)")


def register(subparsers) -> None:
    """Add ``report``."""
    p = subparsers.add_parser("report", help="flow metrics, tables, figures and ParaView files "
                              "of a finished study (steady window from its analysis settings)")
    p.add_argument("study", type=Path, help="study folder")
    p.add_argument("--out", type=folder_to_write, default=None,
                   help="report folder (default STUDY/report)")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="accept.KEY=VALUE",
                   help="re-decide the verdict under another budget from the stored analysis "
                        "(e.g. --set accept.angle_deg=2); only accept: keys")
    add_snapshots(p)
    p.set_defaults(func=cmd_report)
