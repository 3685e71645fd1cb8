"""Resume: decide what to do with a case folder, and continue killed runs from restarts.

Running a study again must not redo finished work:

* ``done`` with the case's scene hash             -> skip, unless its production was
  extended (:mod:`ligwf.study.extension`): then continue from its newest own restart;
* ``unstable`` with a matching hash               -> skip (the engine is deterministic:
  re-running gives the same blow-up; pass ``retry_unstable`` to force it);
* ``failed``, no manifest, or a stale hash        -> fresh run (old outputs removed);
* ``killed`` (or ``running`` with a dead runner)  -> continue from the newest restart file
  that is the case's own (:mod:`ligwf.engine.restart_id`: its identity sidecar names this
  case, replica and seeds, its content is what the engine wrote, its step is not past the
  progress the manifest records), else fresh. Restarts that are not its own are named in
  the plan's reason and never used.

LIGGGHTS writes ``restart_forced_liggghts_<step>.data`` in the case folder (the engine's
working directory) when a rank gets SIGTERM, and the drum input writes periodic restarts
alternately to ``restart/restart_a.liggghts`` and ``restart/restart_b.liggghts`` during
production, so after a SIGKILL at least one complete periodic restart survives. The step of
each file is read from its binary header. :func:`render_resume` writes the input that
re-issues every fix with the same ID and runs the remaining phases with ``run N upto``.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path

from ligwf.engine.liggghts import restart_step
from ligwf.errors import ConfigError
from ligwf.engine.restart_id import CaseIdentity, remove_sidecar, why_not_own
from ligwf.engine.render import render_template, template_context
from ligwf.scene.scaled import ScaledScene
from ligwf.study.case import CaseFolder
from ligwf.study.layout import (ENGINE_LOG, FORCED_RESTART_RE, INPUT_NAME, MANIFEST_FILE,
                                OUTPUT_DIRS, PERIODIC_RESTARTS, RESTART_SIDECAR_SUFFIX,
                                RESUME_INPUT, SCREEN_FILE, SCREEN_LOG_RE, THERMO_FILE, screen_log)
from ligwf.study.manifest import DONE, FAILED, RUNNING, UNSTABLE, Manifest, effective_status


class Action(StrEnum):
    """What the runner does with a case (the value is the word the run output shows)."""

    SKIP = "skip"
    FRESH = "fresh"
    RESUME = "resume"


SKIP, FRESH, RESUME = Action.SKIP, Action.FRESH, Action.RESUME


class Why(StrEnum):
    """What a case needs (:func:`standing`) and so why :func:`plan_case` chose its action:
    callers branch on this, never on the reason's words (which are for people)."""

    NOT_RUN = "not_run"                   # no manifest yet
    SCENE_CHANGED = "scene_changed"       # the manifest is of another scene
    DONE = "done"
    EXTENDED = "extended"                 # done, production extended since
    UNSTABLE = "unstable"                 # left alone: the same input blows up the same way
    RERUN = "rerun"                       # failed (or unstable, asked to retry)
    HELD = "held"                         # a live runner (this or another process) has it
    KILLED = "killed"                     # stopped before its end: resume or run again


@dataclass(frozen=True)
class RestartFile:
    """A restart file of a case: path relative to the case folder and its step."""

    path: str
    step: int


@dataclass(frozen=True)
class NextAttempt:
    """What the runner does with one case, and why; ``skipped``: one line per restart file
    of the case it does not use (unreadable, or not its own) and what it does instead, for
    the run output and the manifest's issues (:data:`RESTART_SKIPPED`)."""

    action: Action
    reason: str
    restart: RestartFile | None = None
    skipped: tuple[str, ...] = ()
    why: Why = Why.NOT_RUN

    def instead(self) -> str:
        """What the case does instead of the restarts it skips, in words."""
        if self.restart is not None:
            return f"resumes from {self.restart.path} at step {self.restart.step}"
        return "runs again from step 0"


#: the manifest issue kind of a restart file a resume did not use
RESTART_SKIPPED = "restart_skipped"


def restart_files(case_dir: Path) -> list[RestartFile]:
    """Readable restart files of a case, newest step first."""
    case_dir = Path(case_dir)
    found: list[RestartFile] = []
    for p in case_dir.iterdir():
        if FORCED_RESTART_RE.match(p.name):
            step = restart_step(p)
            if step is not None:
                found.append(RestartFile(p.name, step))
    for rel in PERIODIC_RESTARTS:
        p = case_dir / rel
        if p.is_file():
            step = restart_step(p)
            if step is not None:
                found.append(RestartFile(rel, step))
    return sorted(found, key=lambda r: r.step, reverse=True)


def unreadable_restarts(case_dir: Path) -> list[str]:
    """Restart files of a case whose header cannot be read (empty or truncated: killed
    while writing, or a full disk), as ``"<path>: <reason>"``, by path."""
    case_dir = Path(case_dir)
    names = [p.name for p in case_dir.iterdir() if FORCED_RESTART_RE.match(p.name)]
    names += [rel for rel in PERIODIC_RESTARTS if (case_dir / rel).is_file()]
    return [f"{n}: header unreadable (empty or truncated)"
            for n in sorted(names) if restart_step(case_dir / n) is None]


def own_restarts(case: CaseFolder, max_step: int | None) -> tuple[list[RestartFile], list[str]]:
    """The case's own restarts, newest step first, and why each other one is refused
    (``"<path>: <reason>"``, unreadable ones first); ``max_step``: the progress the manifest
    records."""
    identity = CaseIdentity.of(case)
    mine, refused = [], unreadable_restarts(case.path)
    for r in restart_files(case.path):
        why = why_not_own(case.path / r.path, identity, max_step)
        if why is None:
            mine.append(r)
        else:
            refused.append(f"{r.path}: {why}")
    return mine, refused


def discard_restart(case_dir: Path, restart: RestartFile) -> None:
    """Set a restart file aside (renamed ``*.corrupt``) after the engine could not read it."""
    p = Path(case_dir) / restart.path
    remove_sidecar(p)
    if p.exists():
        p.rename(p.with_name(p.name + ".corrupt"))


@dataclass(frozen=True)
class Standing:
    """Where a case stands against its postcondition (a ``done`` manifest of its scene, run
    to its end step, extension included), read from its folder alone: ``why`` says what it
    still needs, ``reason`` says so in words, ``manifest`` is the one read (None: not run).
    No restart file is opened: :func:`plan_case` picks the restart of a case that needs
    one."""

    why: Why
    reason: str
    manifest: Manifest | None = None


def standing(case: CaseFolder, retry_unstable: bool = False) -> Standing:
    """The one rule of what a case still needs (see the module docstring), from its
    manifest, scene hash and production extension."""
    m = case.manifest()
    if m is None:
        return Standing(Why.NOT_RUN, "not run yet")
    if m.scene_hash != case.scene_hash:
        return Standing(Why.SCENE_CHANGED, "scene changed since the last run", m)
    status = effective_status(m)
    if status == DONE and m.steps_done < case.scaled.total_steps and case.extension_steps:
        return Standing(Why.EXTENDED, f"production extended to step {case.scaled.total_steps} "
                        f"(done at {m.steps_done})", m)
    if status == DONE:
        return Standing(Why.DONE, DONE, m)
    if status == UNSTABLE and not retry_unstable:
        return Standing(Why.UNSTABLE, f"unstable: {m.reason}", m)
    if status in (FAILED, UNSTABLE):
        return Standing(Why.RERUN, f"re-run after {status}: {m.reason}", m)
    if status == RUNNING:
        return Standing(Why.HELD, f"running in process {m.pid} on {m.host}", m)
    return Standing(Why.KILLED, f"killed at step {m.steps_done}", m)


#: the action of a case that continues from no restart (killed and extended ones pick one)
_NO_RESTART_ACTION = {Why.NOT_RUN: FRESH, Why.SCENE_CHANGED: FRESH, Why.RERUN: FRESH,
                      Why.DONE: SKIP, Why.UNSTABLE: SKIP, Why.HELD: SKIP}


def plan_case(case: CaseFolder, retry_unstable: bool = False) -> NextAttempt:
    """What to do with a case folder now: its :func:`standing`, and for a killed or
    extended case the restart it continues from (see the module docstring)."""
    now = standing(case, retry_unstable)
    m = now.manifest
    if now.why is Why.EXTENDED:
        return _extension_plan(case, m.steps_done)
    if now.why is not Why.KILLED:
        return NextAttempt(_NO_RESTART_ACTION[now.why], now.reason, why=now.why)
    limit = m.steps_done + case.scaled.numerics.thermo_every
    if m.complete_upto is not None:
        limit = min(limit, m.complete_upto)
    restarts, refused = own_restarts(case, limit)
    ignored = f" (ignored {'; '.join(refused)})" if refused else ""
    if restarts:
        return _with_skipped(NextAttempt(RESUME, f"{now.reason}; resume from "
                                         f"{restarts[0].path}{ignored}", restarts[0],
                                         why=Why.KILLED), refused)
    none = (f"no restart file of its own at or before step {limit} (its record is whole up "
            "to there)" if m.complete_upto is not None and m.complete_upto < m.steps_done
            else "before any restart file of its own was written")
    return _with_skipped(NextAttempt(FRESH, f"{now.reason} {none}{ignored}: runs "
                              "again from step 0", why=Why.KILLED), refused)


def _with_skipped(plan: NextAttempt, refused: list[str]) -> NextAttempt:
    """``plan`` with one line per refused restart and what the case does instead."""
    return dataclasses.replace(plan, skipped=tuple(
        f"restart file {why}, not used: the case {plan.instead()}" for why in refused))


def _extension_plan(case: CaseFolder, steps_done: int) -> NextAttempt:
    """A done case whose production was extended (:mod:`ligwf.study.extension`): continue
    it from its newest own restart to the new end (never from one past the steps it ran);
    afresh only when it has none."""
    target = case.scaled.total_steps
    restarts, refused = own_restarts(case, steps_done)
    ignored = f" (ignored {'; '.join(refused)})" if refused else ""
    if restarts:
        return _with_skipped(NextAttempt(RESUME, f"production extended to step {target} (done at "
                                  f"{steps_done}); continue from {restarts[0].path}{ignored}",
                                  restarts[0], why=Why.EXTENDED), refused)
    return _with_skipped(NextAttempt(FRESH, f"production extended to step {target}, but no restart "
                              f"file of its own to continue from{ignored}: run again from "
                              "step 0", why=Why.EXTENDED), refused)


def clean_outputs(case_dir: Path) -> None:
    """Remove the outputs of earlier attempts before a fresh run (inputs stay)."""
    case_dir = Path(case_dir)
    for sub in OUTPUT_DIRS:              # nothing removed through a link (checked first)
        if (case_dir / sub).is_symlink():
            raise ConfigError(f"{case_dir / sub} is a symbolic link (to "
                              f"{os.readlink(case_dir / sub)}): ligwf removes a case's "
                              "earlier outputs only inside its folder; remove the link")
    for sub in OUTPUT_DIRS:
        d = case_dir / sub
        if d.is_dir():
            shutil.rmtree(d)
        d.mkdir()
    for p in case_dir.iterdir():
        if (FORCED_RESTART_RE.match(p.name.removesuffix(RESTART_SIDECAR_SUFFIX))
                or p.name in (MANIFEST_FILE, THERMO_FILE, RESUME_INPUT, ENGINE_LOG)
                or SCREEN_LOG_RE.match(p.name)):
            p.unlink()


def resume_phase(s: ScaledScene, step: int) -> tuple[str, int, bool]:
    """Phase a run stopped at ``step`` is in: (phase, current fill wave, wave inserted).

    Wave k (1-based) inserts at its first step and runs to ``k * wave_steps``; a restart
    written exactly at a wave boundary has not inserted the next wave yet.
    """
    if step < s.insertion_steps:
        wave = step // s.fill.wave_steps + 1
        return "fill", wave, step % s.fill.wave_steps != 0
    if step < s.insertion_steps + s.numerics.settle_steps:
        return "settle", 0, False
    return "production", 0, False


def phase_steps_between(s: ScaledScene, lo: int, hi: int) -> dict[str, int]:
    """Steps ``lo+1 .. hi`` of case ``s`` per phase group (fill, settle, production): what a
    run that went from step ``lo`` to step ``hi`` spent in each (pure; empty when hi <= lo)."""
    fill_end = s.insertion_steps
    settle_end = fill_end + s.numerics.settle_steps
    # step k belongs to the phase whose span (a, b] holds it; past the end is production
    spans = (("fill", 0, fill_end), ("settle", fill_end, settle_end),
             ("production", settle_end, max(hi, s.total_steps)))
    out: dict[str, int] = {}
    for phase, a, b in spans:
        n = min(hi, b) - max(lo, a)
        if n > 0:
            out[phase] = n
    return out


def render_resume(s: ScaledScene, restart: RestartFile, template_dirs=()) -> dict[str, str]:
    """Input continuing case ``s`` from ``restart``: ``{RESUME_INPUT: text}`` (pure)."""
    phase, wave, inserted = resume_phase(s, restart.step)
    ctx = template_context(s)
    ctx.update(restart_file=restart.path, from_step=restart.step, resume_phase=phase,
               current_wave=wave, current_wave_inserted=inserted)
    return {RESUME_INPUT: render_template("resume.in.j2", ctx, template_dirs)}


def input_for(plan: NextAttempt) -> str:
    """Input file an attempt runs."""
    return RESUME_INPUT if plan.action == RESUME else INPUT_NAME


def rotate_screen(case_dir: Path) -> str | None:
    """Keep the screen of the previous attempt as ``run.<n>.log``; returns that name."""
    case_dir = Path(case_dir)
    current = case_dir / SCREEN_FILE
    if not current.exists():
        return None
    n = 1
    while (case_dir / screen_log(n)).exists():
        n += 1
    current.rename(case_dir / screen_log(n))
    return screen_log(n)
