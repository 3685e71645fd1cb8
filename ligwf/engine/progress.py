"""Live progress and the end-of-run summary (rich).

One progress bar per running case: steps done of total, simulated time (s), ETA, atoms and
kinetic energy (J), all read from the thermo output while the engine runs. After the run
a table summarises every case: status, steps, atoms, wall and core-seconds, and the reason.
"""

from __future__ import annotations

from typing import Iterable

from rich.console import Console
from rich.progress import (BarColumn, MofNCompleteColumn, Progress, TaskID, TextColumn,
                           TimeRemainingColumn)
from rich.markup import escape
from rich.table import Table

from ligwf.engine.resume import NextAttempt
from ligwf.engine.thermo import ThermoParser, parse_screen
from ligwf.study.case import CaseFolder
from ligwf.study.manifest import (DONE, FAILED, KILLED, MISSING, RUNNING, UNSTABLE, Manifest,
                                  effective_status)

_STATUS_STYLE = {DONE: "green", FAILED: "red", UNSTABLE: "yellow", KILLED: "magenta",
                 RUNNING: "cyan"}


class RichMonitor:
    """A :class:`ligwf.engine.launch.Monitor` drawing rich progress bars."""

    def __init__(self, console: Console | None = None) -> None:
        self.console = console or Console()
        self.progress = Progress(
            TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
            TextColumn("t={task.fields[sim_time]:.3g} s"), TimeRemainingColumn(),
            TextColumn("atoms {task.fields[atoms]}"), TextColumn("KE {task.fields[ke]:.3g} J"),
            console=self.console, transient=False, refresh_per_second=2)
        self.tasks: dict[str, TaskID] = {}
        self.results: list[tuple[str, Manifest | None, NextAttempt]] = []

    def __enter__(self) -> "RichMonitor":
        self.progress.start()
        return self

    def __exit__(self, *exc) -> None:
        self.progress.stop()

    def start(self, case_id: str, total_steps: int, from_step: int) -> None:
        if case_id in self.tasks:
            self.progress.reset(self.tasks[case_id], total=total_steps, completed=from_step)
            return
        self.tasks[case_id] = self.progress.add_task(case_id, total=total_steps,
                                                     completed=from_step, sim_time=0.0,
                                                     atoms="-", ke=0.0)

    def update(self, case_id: str, parser: ThermoParser) -> None:
        row = parser.last_row
        task = self.tasks.get(case_id)
        if row is None or task is None:
            return
        self.progress.update(task, completed=row.step, sim_time=row.get("time", 0.0),
                             atoms=f"{row.get('atoms'):.0f}", ke=row.get("ke", 0.0))

    def end(self, case_id: str, manifest: Manifest | None, plan: NextAttempt) -> None:
        self.results.append((case_id, manifest, plan))
        task = self.tasks.get(case_id)
        if task is not None and manifest is not None:
            style = _STATUS_STYLE.get(manifest.status, "")
            self.progress.update(task, description=f"{case_id} [{style}]{manifest.status}[/]")


def shown_reason(status: str, reason: str) -> str:
    """A case's reason as the status tables print it: a finished case says so (manifests
    written before said only "106879 steps")."""
    if status == DONE and (not reason or reason.split()[0].isdigit()):
        return f"finished: all {reason}" if reason else "finished"
    return reason


def summary_table(cases: Iterable[CaseFolder], title: str = "cases") -> Table:
    """Status of every case folder from its manifest (``ligwf status`` and run summary)."""
    table = Table(title=title)
    for col in ("case", "status", "steps", "atoms start->end", "wall [s]",
                "cores x wall [core-s]", "settle wall [s]", "production wall [s]", "reason"):
        # (escape: the units in [ ] are not rich markup, "[s]" would strike the text through)
        table.add_column(escape(col),
                         justify="left" if col in ("case", "status", "reason") else "right")
    for case in cases:
        m = case.manifest()
        if m is None:
            table.add_row(case.path.name, MISSING, "", "", "", "", "", "", "")
            continue
        status = effective_status(m)
        style = _STATUS_STYLE.get(status, "")
        phases = m.phases
        steps, reason = live_state(case, m, status)
        table.add_row(
            m.case_id, f"[{style}]{status}[/]", steps,
            f"{m.atoms_start if m.atoms_start is not None else '-'}->"
            f"{m.atoms_end if m.atoms_end is not None else '-'}",
            f"{m.wall_seconds:.1f}", f"{m.core_seconds:.1f}",
            f"{phases.get('settle', {}).get('wall_seconds', 0.0):.1f}",
            f"{phases.get('production', {}).get('wall_seconds', 0.0):.1f}",
            escape(reason[:80]))
    return table


def live_step(case: CaseFolder) -> int | None:
    """The last thermo step the case's current screen shows (None: none yet)."""
    try:
        text = case.screen.read_text(errors="replace")
    except OSError:
        return None
    row = parse_screen(text).last_row
    return row.step if row is not None else None


def live_state(case: CaseFolder, m: Manifest, status: str) -> tuple[str, str]:
    """The steps and reason a status table shows for a case: a manifest records the steps
    of finished attempts only, so a case whose attempt is under way (alone or inside an
    ensemble) or was cut off by a dead runner shows the step its screen reached."""
    steps, reason = f"{m.steps_done:,}/{m.total_steps:,}", shown_reason(status, m.reason)
    if m.status != RUNNING:
        return steps, reason
    live = live_step(case)
    if live is None:
        return steps, ("starting (no thermo row on its screen yet)" if status == RUNNING
                       else "killed: its runner is gone before the engine's first thermo row")
    steps = f"{live:,}/{m.total_steps:,}"
    if status == RUNNING:
        return steps, f"running: step {live:,} of {m.total_steps:,} (live, {case.screen.name})"
    return steps, (f"killed: its runner is gone; the screen reached step {live:,} (the same "
                   "run command resumes it)")
