"""One attempt at a case: prepare the folder before a launch, judge and record it after.

Shared by every launcher (local ``mpirun`` in :mod:`ligwf.engine.launch`, the MPI ensemble in
:mod:`ligwf.engine.ensemble_worker`, Slurm array tasks through ``ligwf run-case``), so a case gets
the same manifest, thermo table, health verdict and resume behaviour however it ran.
"""

from __future__ import annotations

import math
import os
import re

from ligwf import __version__
from ligwf.fsio import LOW_SPACE_BYTES, FolderNotWritable, atomic_write_text, space_left
from ligwf.engine.dump_hasher import dump_problem
from ligwf.engine.health import (Expectation, assess, engine_signal, kinetic_energy_ceiling,
                                 verdict)
from ligwf.engine.restart_id import CaseIdentity, stamp
from ligwf.engine.site import EngineIdentity
from ligwf.engine.resume import (FRESH, RESTART_SKIPPED, RESUME, NextAttempt, clean_outputs,
                                 input_for, own_restarts, phase_steps_between, render_resume,
                                 rotate_screen)
from ligwf.engine.thermo import parse_screen, phase_group
from ligwf.scene.scaled import ScaledScene
from ligwf.study.case import NO_DIGESTS, CaseFolder, KnownDigests
from ligwf.study.manifest import DONE, FAILED, KILLED, RUNNING, UNSTABLE
from ligwf.study.processes import start_time
from ligwf.study.thermo_table import ThermoRow, rows_from_csv, rows_to_csv
from ligwf.study.layout import POST_DIR, SCREEN_FILE, particle_dump
from ligwf.study.manifest import (DISK_FULL_REASON, Attempt, Manifest, Stop, now_iso,
                                  overwrite_manifest)

_VERSION_RE = re.compile(r"^LIGGGHTS \((Version .*)\)\s*$")


def expectation(s: ScaledScene) -> Expectation:
    """Healthy end state of a scaled scene: particle count, step counts, KE ceiling."""
    p = s.particles
    mean_volume = sum(f * math.pi * d**3 / 6.0 for d, f in zip(p.diameters, p.number_fractions))
    mass = p.count * p.density * mean_volume
    return Expectation(particle_count=p.count,
                       settle_end_step=s.insertion_steps + s.numerics.settle_steps,
                       total_steps=s.total_steps,
                       ke_ceiling=kinetic_energy_ceiling(mass, s.drum.diameter, s.drum.omega))


def engine_version(lines: list[str]) -> str | None:
    """The ``LIGGGHTS (Version ...)`` banner of a screen capture."""
    for line in lines[:20]:
        m = _VERSION_RE.match(line.strip())
        if m:
            return "LIGGGHTS " + m.group(1)
    return None


def begin_attempt(case: CaseFolder, plan: NextAttempt, nprocs: int, launcher: str,
                  command: list[str] | None = None, template_dirs=(),
                  engine: EngineIdentity | None = None) -> tuple[Manifest, Attempt]:
    """Prepare the folder for ``plan`` (clean or write the resume input) and record the
    attempt as ``running`` in the manifest, with the ``engine`` that runs it. Returns the
    manifest and the new attempt."""
    previous = case.manifest()
    if plan.action == FRESH or previous is None:
        clean_outputs(case.path)
        manifest = Manifest(case_id=case.case_id, index=case.index, scene_hash=case.scene_hash,
                            ligwf_version=__version__, liggghts_version="")
        if previous is not None and previous.scene_hash == case.scene_hash:
            # the same case again from step 0 (killed before a restart of its own, or
            # failed): its earlier attempts cost what they cost and stay in the record
            manifest.attempts = list(previous.attempts)
            for a in manifest.attempts:
                a.screen = ""       # removed with the old outputs; the name may be reused
        from_step, restart_path = 0, None
    elif plan.action == RESUME and plan.restart is not None:
        for name, text in render_resume(case.scaled, plan.restart, template_dirs).items():
            atomic_write_text(case.path / name, text)
        manifest = previous
        kept = rotate_screen(case.path)
        if kept and manifest.attempts and manifest.attempts[-1].screen == SCREEN_FILE:
            manifest.attempts[-1].screen = kept   # its rows are read from there from now on
        from_step, restart_path = plan.restart.step, plan.restart.path
        credit_restart(case.scaled, manifest, from_step)
    else:
        raise ValueError(f"begin_attempt: nothing to run for plan {plan}")
    # restarts the plan did not use are said in the record too (not only on the screen)
    said = [i for i in (previous.issues if previous is not None else [])
            if isinstance(i, dict) and i.get("kind") == RESTART_SKIPPED]
    manifest.issues = said + [{"kind": RESTART_SKIPPED, "step": from_step, "message": line}
                              for line in plan.skipped]
    manifest.status, manifest.reason, manifest.reason_step = RUNNING, plan.reason, None
    manifest.stop = Stop.NONE
    manifest.host, manifest.pid = os.uname().nodename, os.getpid()
    manifest.pid_start, manifest.engine = start_time(os.getpid()), []
    manifest.launcher, manifest.nprocs = launcher, nprocs
    manifest.command = list(command or [])
    manifest.total_steps = case.scaled.total_steps
    manifest.ended = None
    if engine is not None:
        manifest.liggghts_executable, manifest.liggghts_library = engine.executable, engine.library
        manifest.liggghts_version = engine_version([engine.version]) or engine.version
    attempt = Attempt(number=len(manifest.attempts) + 1, started=now_iso(), nprocs=nprocs,
                      command=list(command or []), input=input_for(plan),
                      from_restart=restart_path, from_step=from_step)
    manifest.attempts.append(attempt)
    case.write_manifest(manifest)
    return manifest, attempt


def launcher_failed(attempt: Attempt, exit_code: int, lines: list[str]) -> str:
    """The reason of an attempt whose launcher failed before LIGGGHTS started (no banner on
    its screen): "engine exit code 1" would blame an engine that never ran."""
    launcher = attempt.command[0] if attempt.command else "the launcher"
    said = next((x.strip() for x in reversed(lines) if x.strip()), "")
    return (f"launcher {launcher} exited {exit_code} before the engine started (no LIGGGHTS "
            f"banner in {attempt.screen}; "
            + (f"its last line: {said[:200]}" if said else "it printed nothing")
            + "): check LIGWF_MPIRUN / mpirun_args")


def credit_restart(s: ScaledScene, manifest: Manifest, restart_step: int) -> None:
    """Count the steps up to ``restart_step`` as run by the attempt that wrote the restart.

    An attempt's steps come from the last thermo row of its screen. A run killed with
    SIGKILL (or recorded by the next runner while its orphaned engine was still writing
    the forced restart) can have written a restart past the last row its screen shows:
    the engine's buffered screen output is lost. The restart proves the run got there, so
    the latest attempt that started before it is credited the missing steps, in the phases
    they belong to, and the manifest's per-phase totals stay the sums over the attempts.
    """
    reached = max((a.from_step + a.steps for a in manifest.attempts), default=0)
    if restart_step <= reached:
        return
    writer = next((a for a in reversed(manifest.attempts) if a.from_step < restart_step), None)
    if writer is None:
        return
    lo = writer.from_step + writer.steps
    for phase, n in phase_steps_between(s, lo, restart_step).items():
        rec = writer.phases.setdefault(phase, {"wall_seconds": 0.0, "steps": 0})
        rec["steps"] = int(rec.get("steps", 0)) + n
    writer.steps = restart_step - writer.from_step
    manifest.add_up_attempts()


_DUMP_STEP_RE = re.compile(r"_(\d+)\.vt[ur]$")


def record_hole(case: CaseFolder, rows: list[ThermoRow]) -> tuple[int, str] | None:
    """The first hole in a case's record: (last step a resume may restart from, why).

    A full disk (or a writer killed mid-file) leaves thermo rows missing from a screen and
    dump files empty; a run that resumes from a restart past the hole never writes them
    again. Holes: a thermo gap wider than ``thermo_every`` (restart at or before the row
    before it), an empty or truncated (no closing ``</VTKFile>``) file in ``post/`` or a
    missing particle dump at a step the run has reached (restart before that step). None
    when the record is whole.
    """
    holes: list[tuple[int, str]] = []
    every = case.scaled.numerics.thermo_every
    for a, b in zip(rows, rows[1:]):
        if not 0 < b.step - a.step <= every:
            holes.append((a.step, f"thermo rows missing or repeated between steps {a.step} "
                          f"and {b.step}"))
            break
    post = case.path / POST_DIR
    reached = rows[-1].step if rows else 0
    if post.is_dir():
        names = set()
        for f in post.iterdir():
            names.add(f.name)
            m = _DUMP_STEP_RE.search(f.name)
            if m and f.is_file() and int(m.group(1)) <= reached:
                why = dump_problem(f)
                if why is not None:
                    holes.append((int(m.group(1)) - 1, why))
        for step in case.expected_dump_steps(reached):
            if particle_dump(step) not in names:
                holes.append((step - 1, f"particle dump of step {step} missing"))
                break
    return min(holes) if holes else None


def resume_before(case: CaseFolder, step: int) -> str:
    """What a case whose record is whole only up to ``step`` does next, in words: resume
    from its newest own restart at or before it, or run again from step 0 (none is; the
    periodic restarts may all lie past a hole a full disk left)."""
    restarts, _ = own_restarts(case, step)
    if restarts:
        return (f"resumes from {restarts[0].path} at step {restarts[0].step} (the newest "
                f"restart of its own at or before step {step})")
    return f"no restart of its own at or before step {step}: runs again from step 0"


def merge_rows(previous: list[ThermoRow], new: list[ThermoRow], from_step: int,
               dt: float) -> list[ThermoRow]:
    """Thermo of earlier attempts up to the restart step, then this attempt's rows.

    LIGGGHTS restarts its ``time`` thermo column at 0 after ``read_restart``; the
    simulated time of a resumed row is put back on the case's clock (+ from_step x dt, s).
    """
    if not from_step:
        return list(new)
    kept = [r for r in previous if r.step < from_step]
    shifted = [ThermoRow(r.step, {**r.values, "time": r.get("time", 0.0) + from_step * dt},
                         r.phase) for r in new if r.step >= from_step]
    return kept + shifted


def case_rows(case: CaseFolder, attempts: list[Attempt]) -> list[ThermoRow]:
    """The case's thermo series rebuilt from the screen of every attempt (an attempt whose
    runner was SIGKILLed never wrote ``thermo.csv``, but its screen holds its rows): no
    gap, no duplicate step. A screen removed by hand falls back to the old table."""
    rows: list[ThermoRow] = []
    for a in attempts:
        screen = case.path / a.screen
        if a.screen and screen.is_file():
            new = parse_screen(screen.read_text(errors="replace")).rows
            rows = merge_rows(rows, new, a.from_step, case.scaled.numerics.dt)
        elif case.thermo.is_file():
            table = rows_from_csv(case.thermo.read_text())
            rows = [r for r in rows if r.step < a.from_step] + \
                [r for r in table if r.step >= a.from_step]
    return rows


def history(case: CaseFolder, manifest: Manifest, attempt: Attempt) -> list[ThermoRow]:
    """Rows of the earlier attempts before ``attempt`` starts (what the live check of a
    resumed attempt judges its rows against)."""
    earlier = [a for a in manifest.attempts if a.number < attempt.number]
    return [r for r in case_rows(case, earlier) if r.step < attempt.from_step]


def finish_attempt(case: CaseFolder, manifest: Manifest, attempt: Attempt,
                   exit_code: int | None, wall_seconds: float, killed: bool = False,
                   engine_version_line: str | None = None,
                   stop_problem: str | None = None, stamp_new: bool = True,
                   digests: KnownDigests = NO_DIGESTS) -> Manifest:
    """Judge the attempt from its screen capture and write thermo table + manifest.
    ``stop_problem``: why the live check stopped the run (None: it did not). The restarts
    the attempt wrote get their identity sidecars first (the engine has ended), unless
    ``stamp_new`` is False: a runner recording a DEAD runner's attempt cannot tell the
    engine's files from ones dropped in since (the watchdog stamped them when it stopped
    that engine). ``digests``: the dumps hashed while the engine ran
    (:mod:`ligwf.engine.dump_hasher`), so the done record hashes only the rest."""
    s = case.scaled
    if stamp_new:
        stamp_restarts(case, attempt)
    screen = case.path / attempt.screen
    text = screen.read_text(errors="replace") if screen.exists() else ""
    parser = parse_screen(text)
    rows = case_rows(case, manifest.attempts)
    expect = expectation(s)
    issues = assess(rows, parser.lines, expect)
    steps_done = rows[-1].step if rows else attempt.from_step
    signal = engine_signal(parser.lines, exit_code)
    status, reason = verdict(issues, exit_code, steps_done, s.total_steps, killed, signal,
                             stop_problem)
    if status == FAILED and not issues and exit_code not in (0, None) \
            and engine_version(parser.lines) is None:
        reason = launcher_failed(attempt, exit_code, parser.lines)
    hole = record_hole(case, rows) if status in (DONE, KILLED) else None
    stop = Stop.NONE
    if hole is not None and status == DONE:
        # never done with a gap or an empty frame: resume from a restart before the hole
        status, reason = KILLED, f"incomplete record ({hole[1]}): {resume_before(case, hole[0])}"
        stop = Stop.INCOMPLETE_RECORD
    left = space_left(case.path)
    if status in (FAILED, KILLED) and left < LOW_SPACE_BYTES:
        # a full disk makes LIGGGHTS segfault: the case resumes once there is room
        status = KILLED
        reason = f"{DISK_FULL_REASON} ({left} bytes left in {case.path}): {reason}"
        stop = Stop.DISK_FULL

    attempt.ended = now_iso()
    attempt.wall_seconds = wall_seconds
    attempt.exit_code = exit_code
    attempt.status, attempt.reason = status, reason
    attempt.steps = parser.rows[-1].step - attempt.from_step if parser.rows else 0
    walls, steps = parser.phase_walls(), parser.phase_steps()
    attempt.phases = {ph: {"wall_seconds": walls.get(ph, 0.0), "steps": steps.get(ph, 0)}
                      for ph in walls.keys() | steps.keys()}
    manifest.status, manifest.reason, manifest.stop = status, reason, stop
    manifest.reason_step = _cause_step(issues, status)
    manifest.issues = ([i for i in manifest.issues if isinstance(i, dict)
                        and i.get("kind") == RESTART_SKIPPED] + [i.to_dict() for i in issues])
    manifest.liggghts_version = (engine_version(parser.lines) or engine_version_line
                                 or manifest.liggghts_version)
    manifest.ended = attempt.ended
    manifest.engine = []
    manifest.add_up_attempts()
    manifest.steps_done = steps_done
    manifest.complete_upto = hole[0] if hole is not None else None
    if rows:
        manifest.atoms_start = int(rows[0].get("atoms")) if manifest.atoms_start is None else \
            manifest.atoms_start
        manifest.atoms_end = _int_or_none(rows[-1].get("atoms"))
        manifest.simulated_time = rows[-1].get("time", 0.0)
        settled = [r for r in rows if r.step <= expect.settle_end_step]
        if settled and settled[-1].step == expect.settle_end_step:
            manifest.atoms_after_settle = _int_or_none(settled[-1].get("atoms"))
    try:
        atomic_write_text(case.thermo, rows_to_csv(rows))
    except FolderNotWritable:
        pass  # the table is rebuilt from the screens by the next attempt; the manifest counts
    try:
        case.write_manifest(manifest, digests)
    except FolderNotWritable:
        overwrite_manifest(case.path, manifest)   # read-only: raises FolderNotWritable
    return manifest


def stamp_restarts(case: CaseFolder, attempt: Attempt, settle: float = 0.0) -> list[str]:
    """Identity sidecars for the restarts ``attempt`` of ``case`` wrote (changed since it
    began, 1 s of clock granularity allowed; :mod:`ligwf.engine.restart_id`)."""
    return stamp(case.path, CaseIdentity.of(case), attempt.number, attempt.started_at - 1.0,
                 settle)


def close_lost_attempt(case: CaseFolder, manifest: Manifest) -> Manifest:
    """Record the last attempt of a case whose runner died (SIGKILL, crash, lost node)
    from its screen: rows, steps, and wall time up to the screen's last write. The
    case becomes ``killed`` (or whatever its rows show) and resumes."""
    attempt = manifest.attempts[-1]
    screen = case.path / attempt.screen
    parser = parse_screen(screen.read_text(errors="replace") if screen.exists() else "")
    wall = sum(parser.phase_walls().values())
    if screen.exists():
        wall = max(wall, screen.stat().st_mtime - attempt.started_at)
    return finish_attempt(case, manifest, attempt, None, wall, killed=True, stamp_new=False)


def _cause_step(issues, status: str) -> int | None:
    """Step of the issue behind a failed / unstable verdict."""
    if status == FAILED:
        cause = [i for i in issues if i.kind == "error"]
    elif status == UNSTABLE:
        cause = [i for i in issues if not i.fatal]
    else:
        cause = []
    return cause[0].step if cause else None


def _int_or_none(value: float) -> int | None:
    return int(value) if math.isfinite(value) else None


def restart_unreadable(manifest: Manifest, attempt: Attempt) -> bool:
    """True when a resumed attempt failed before taking a step (bad restart file)."""
    return (attempt.from_restart is not None and manifest.status == FAILED
            and manifest.steps_done <= attempt.from_step)


__all__ = ["begin_attempt", "finish_attempt", "stamp_restarts", "close_lost_attempt", "case_rows", "history",
           "expectation", "engine_version", "phase_group", "restart_unreadable"]
