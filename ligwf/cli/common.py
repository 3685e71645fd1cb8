"""What every ligwf sub-command shares: consoles, the workflow arguments, the pre-flight
warnings, the case table and the stop-on-signal event. Holds no pipeline logic (that is
:mod:`ligwf.pipeline`)."""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator, Sequence

from rich.console import Console, Group
from rich.markup import escape
from rich.table import Table
from rich.text import Text

from ligwf.engine.plan import MAX_RANKS, RankPlan, Schedule, particle_steps
from ligwf.errors import ConfigError
from ligwf.pipeline.prepare import Prepared, mesh_cache_lines, prepare_workflow
from ligwf.study.layout import STUDY_FILE, is_study_folder
from ligwf.study.paths import path_text_problem, resolved, shown

console = Console(width=None if sys.stdout.isatty() else 160)
err_console = Console(stderr=True, soft_wrap=True)


class Parser(argparse.ArgumentParser):
    """argparse with its refusals in ligwf's one-line form (sub-parsers inherit it)."""

    def error(self, message: str):  # noqa: D401 - argparse's hook
        err_console.print(f"[bold red]ligwf: usage error:[/] {escape(self.prog)}: "
                          f"{escape(message)} "
                          f"(see {escape(self.prog)} --help)", highlight=False)
        raise SystemExit(2)


def positive_int(text: str, unit: str = "") -> int:
    """argparse type: a whole number >= 1 (ranks, ensemble sizes, cores); ``unit`` names
    what is counted in the message (``functools.partial(positive_int, unit="cores")``)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        what = f"a whole number of {unit}" if unit else "a whole number"
        raise argparse.ArgumentTypeError(f"must be {what}, allowed range [1, inf), "
                                         f"got {text!r}")
    return value


def number_in(low: float, high: float, unit: str = ""):
    """argparse type: a finite number in [low, high] (``unit`` shown after the range), so
    ``--dt 5e-324`` or ``--cg 0`` is refused in one line before any file is read."""
    shown = f"[{low:g}, {high:g}]" + (f" {unit}" if unit else "")

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not low <= value <= high:      # nan fails too
            raise argparse.ArgumentTypeError(f"must be a number, allowed range {shown}, "
                                             f"got {text!r}")
        return value
    return parse


def step_number(text: str) -> int:
    """argparse type: a time step of a LIGGGHTS run, a whole number in [0, 2,147,483,647]
    (the engine counts steps in a 32-bit int within one run)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if not 0 <= value <= 2**31 - 1:
        raise argparse.ArgumentTypeError(f"must be a whole step number, allowed range "
                                         f"[0, 2,147,483,647], got {text!r}")
    return value


def rank_count(text: str) -> int:
    """argparse type: a number of MPI ranks or cores, a whole number in [1, MAX_RANKS]
    (``--np 1000000000000`` would otherwise be accepted and spin in the rank layout)."""
    value = positive_int(text)
    if value > MAX_RANKS:
        raise argparse.ArgumentTypeError(f"must be a whole number, allowed range "
                                         f"[1, {MAX_RANKS}], got {text!r}")
    return value


def folder_to_write(text: str) -> Path:
    """argparse type: a folder ligwf may create or write into (refused before any work:
    an existing file, a path below a file, a read-only or unwritable place, an empty path
    that would mean the current folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is an empty path (it would write into the "
                                         "current folder); name the folder")
    if (why := path_text_problem(text)) is not None:
        raise argparse.ArgumentTypeError(f"{shown(text)}: {why}")
    path = Path(text)
    try:
        resolved(path)                   # a symbolic link loop on the way: one line
        if path.exists() and not path.is_dir():
            raise argparse.ArgumentTypeError(f"{text} is a file, not a folder")
        probe = path
        while not probe.exists():
            if probe.parent == probe:
                break
            probe = probe.parent
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    except OSError as exc:               # too long a name, no permission on the way, ...
        raise argparse.ArgumentTypeError(f"{shown(text)}: cannot be used as a folder "
                                         f"({exc.strerror or exc})") from None
    if not probe.is_dir():
        raise argparse.ArgumentTypeError(f"{text}: {probe} is a file, so no folder can be "
                                         "made below it")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"{text}: {probe} is not writable (read-only file "
                                         "system or permissions)")
    return path


def existing_folder(text: str) -> Path:
    """argparse type: a folder that exists (user template folders)."""
    path = Path(text)
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is not an existing folder")
    return path


def add_workflow_args(p: argparse.ArgumentParser) -> None:
    """WORKFLOW, ``--set``, ``--templates`` and ``--allow-unstable``."""
    p.add_argument("workflow", type=Path, help="workflow YAML file")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a workflow value, e.g. scene.drum.lifters.count=12 or "
                   "analysis.max_velocity_angle=10 (repeatable)")
    p.add_argument("--templates", action="append", default=[], type=existing_folder,
                   metavar="DIR",
                   help="user template folder searched before ligwf's own (repeatable)")
    p.add_argument("--allow-unstable", action="store_true",
                   help="run/write cases the pre-flight stability check refuses (experts)")


def add_until_decided_args(p: argparse.ArgumentParser) -> None:
    """``--until-decided``, ``--max-looks``, ``--max-core-hours``, ``--every-level``: a
    sequential study, on any executor (``ligwf study``, ``ligwf slurm submit``)."""
    from functools import partial

    from ligwf.study.rounds import DEFAULT_LOOKS

    p.add_argument("--until-decided", action="store_true",
                   help="go on in rounds (longer production or more replicas, the cheapest "
                   "that decides) until the cheapest level that can still pass is decided; "
                   "locally WORKFLOW may be a study folder; on a scheduler each round is a "
                   "dependent array whose follow-up job ('ligwf slurm next-round') takes the "
                   "look and submits the next round")
    p.add_argument("--max-looks", type=partial(positive_int, unit="looks"),
                   default=DEFAULT_LOOKS, help="with --until-decided: looks at most (each "
                   f"tests at 0.05 / looks; default {DEFAULT_LOOKS})")
    p.add_argument("--max-core-hours", type=number_in(1e-6, 1e9, "core-h"), default=None,
                   metavar="H", help="with --until-decided: stop before a round would take "
                   "the study's runs past H core-hours")
    p.add_argument("--every-level", action="store_true",
                   help="with --until-decided: the rounds work on the undecided criteria of "
                   "every CG level (a ladder: each level's error decided), not only on the "
                   "cheapest level that can still pass")


def add_replace_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--replace", action="store_true",
                   help="write over another study in --out (refused without it: another "
                   "name or other workflow values); cases it does not change keep their runs")


def add_mesh_cache(p: argparse.ArgumentParser) -> None:
    p.add_argument("--mesh-cache", type=folder_to_write, default=None,
                   help="mesh cache folder (default $LIGWF_MESH_CACHE or ./meshes)")


def prepare_from_args(args: argparse.Namespace) -> Prepared:
    """Validate, render and pre-flight the workflow of ``args``; print the warnings.
    WORKFLOW may be a study folder with ``--until-decided`` (on any executor: the workflow
    it stores goes on in rounds), and is refused in one line without. Raises (nothing
    written) on a bad value or a refused case, or when ``--out`` is the workflow file's own
    folder (a study would mix its case folders with the workflows)."""
    out = getattr(args, "out", None)
    if is_study_folder(args.workflow):
        if not getattr(args, "until_decided", False):
            raise ConfigError(f"WORKFLOW = {args.workflow}: a study folder, not a workflow "
                              "file; only 'ligwf study STUDY --out STUDY --until-decided' "
                              "goes on from one (the workflow it stores)")
        from ligwf.pipeline.rounds import prepare_study_folder    # loads the inference

        prepared = prepare_study_folder(args.workflow, args.overrides, args.templates,
                                        args.allow_unstable)
    elif out is not None and Path(out).resolve() == Path(args.workflow).resolve().parent:
        raise ConfigError(f"--out {out} is the folder of the workflow file {args.workflow}: "
                          f"a study writes {STUDY_FILE} and one folder per case there; name a "
                          "folder of the study's own")
    else:
        prepared = prepare_workflow(args.workflow, args.overrides, args.templates,
                                    args.allow_unstable)
    case_ids = [rc.case.case_id for rc in prepared.rendered]
    for line in grouped_warnings(prepared.warnings, case_ids):
        print_warning(line)
    if out is not None and hasattr(args, "mesh_cache"):     # commands that write meshes
        for line in mesh_cache_lines(prepared, args.mesh_cache):
            print_warning(line)
    return prepared


WARNING_PREFIX = "ligwf: warning: "


def wrapped_warning(line: str, width: int | None) -> list[str]:
    """One warning as the lines a terminal of ``width`` columns shows: the prefix on the
    first, the rest indented by two spaces, broken at spaces (a long path or case list is
    never cut mid-word). ``width`` None: one line, as in a log or a pipe (whole for grep).
    Pure."""
    import textwrap

    if width is None:
        return [WARNING_PREFIX + line]
    return textwrap.wrap(line, width=max(width, 40), initial_indent=WARNING_PREFIX,
                         subsequent_indent="  ", break_long_words=False,
                         break_on_hyphens=False) or [WARNING_PREFIX]


def print_warning(line: str, console: Console | None = None) -> None:
    """A warning on stderr, wrapped to the terminal's width (a terminal cuts or breaks a
    long line mid-word otherwise); unwrapped when stderr is no terminal."""
    out = console or err_console
    lines = wrapped_warning(line, out.width if out.is_terminal else None)
    head = lines[0][len(WARNING_PREFIX):]
    out.print(f"[yellow]{WARNING_PREFIX.rstrip()}[/] {escape(head)}", highlight=False)
    for rest in lines[1:]:
        out.print(escape(rest), highlight=False)


#: stands for the case a warning names while warnings are grouped (never in a warning)
_CASE = "\x00case\x00"


def grouped_warnings(lines: list[str], case_ids: list[str]) -> list[str]:
    """One line per warning that differs only in the case it names: the cases are listed
    once (a sweep of 30 cases would otherwise print the same warning 30 times). Order of
    first appearance is kept (pure)."""
    import re

    if not case_ids:
        return list(lines)
    rx = re.compile("|".join(re.escape(c) for c in sorted(case_ids, key=len, reverse=True)))
    order: list[str] = []
    named: dict[str, list[str]] = {}
    for line in lines:
        found = rx.findall(line)
        key = rx.sub(lambda _: _CASE, line) if len(set(found)) == 1 else line
        if key not in named:
            order.append(key)
            named[key] = []
        if len(set(found)) == 1 and found[0] not in named[key]:
            named[key].append(found[0])
    out = []
    for key in order:
        cases = named[key]
        if len(cases) <= 1:
            out.append(key.replace(_CASE, cases[0]) if cases else key)
        else:
            shown = ", ".join(cases[:4]) + (f", ... ({len(cases)} cases)" if len(cases) > 4
                                            else "")
            out.append(key.replace(_CASE, shown))
    return out


def case_table(prepared: Prepared, title: str) -> Table:
    """Table of cases: CG level, rule, replica, particle count, dt, steps."""
    table = Table(title=title)
    for col in ("case", "CG", "rule", "rep", "particles", "dt [s]", "dt/t_R", "steps",
                "particle-steps"):
        table.add_column(escape(col), justify="right" if col not in ("case", "rule") else "left")
    for rc in prepared.rendered:
        s = rc.scaled
        table.add_row(rc.case.case_id, f"{s.cg:g}", s.rule, str(s.replica),
                      f"{s.particles.count:,}", f"{s.numerics.dt:.3g}",
                      f"{s.numerics.dt_rayleigh_fraction:.3g}",
                      f"{s.total_steps:,}", f"{particle_steps(s):.3g}")
    return table


def add_cores_arg(p: argparse.ArgumentParser, help_text: str | None = None) -> None:
    p.add_argument("--cores", type=rank_count, default=None, metavar="N",
                   help=help_text or "cores the rank plan fills (default: the tasks of the "
                   "Slurm allocation this runs in, else the CPUs this process may use)")


def duration(seconds: float) -> str:
    """A wall time for people: '45 s', '12 min', '3.2 h'."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def case_plan_table(plans: Sequence[RankPlan], title: str, notes: Sequence[str]) -> Group:
    """Ranks per case, what limited them and the estimated wall time; ``notes`` below,
    one line each."""
    table = Table(title=title)
    for col in ("case", "particle-steps", "ranks", "limited by", "est. wall"):
        table.add_column(escape(col), justify="left" if col in ("case", "limited by") else "right")
    for c in plans:
        table.add_row(c.name, f"{c.particle_steps:.3g}", str(c.ranks), c.bound,
                      duration(c.estimated_seconds))
    return Group(table, *(Text(line) for line in notes))


def plan_table(schedule: Schedule, title: str) -> Group:
    """Ranks per case (and what limited them), then the phases in run order."""
    lines = []
    for number, ph in enumerate(schedule.phases, 1):
        if ph.ensemble:
            how = (f"side by side, {ph.groups} at a time on {ph.ranks} rank(s) each "
                   f"(one mpirun -np {ph.total_ranks} ensemble)")
        else:
            how = f"one after the other on {ph.ranks} rank(s) (mpirun -np {ph.ranks})"
        order = ", longest first" if schedule.planned and len(ph.cases) > 1 else ""
        lines.append(f"phase {number}: {len(ph.cases)} case(s) {how}{order}: "
                     f"~{duration(ph.estimated_seconds)}")
    if schedule.phases:
        lines.append(f"estimated {duration(schedule.estimated_seconds)} wall on "
                     f"{schedule.cores} core(s), ~{schedule.core_fill:.0%} of them busy "
                     "(rates measured on a 2-core machine: ligwf.engine.plan)")
    return case_plan_table(schedule.cases, title, lines or ["nothing to run"])


@contextmanager
def stop_on_signals() -> Iterator[threading.Event]:
    """An event set by SIGTERM / SIGINT, so a runner stops its engines gracefully
    (forced restart written, case marked ``killed``) instead of dying mid-write."""
    stop = threading.Event()
    previous = {}

    def handler(signum, frame):  # noqa: ARG001 - signal handler signature
        stop.signum = signum        # the pipeline's Interrupted exits 128 + signum
        stop.set()

    for sig in (signal.SIGTERM, signal.SIGINT):
        previous[sig] = signal.signal(sig, handler)
    try:
        yield stop
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
