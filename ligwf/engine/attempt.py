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
from ligwf.fsio import atomic_write_text
from ligwf.engine.health import (FAILED, RUNNING, UNSTABLE, Expectation, assess,
                                 kinetic_energy_ceiling, verdict)
from ligwf.engine.resume import (FRESH, RESUME, Plan, clean_outputs, input_for, render_resume,
                                 rotate_screen)
from ligwf.engine.thermo import ThermoRow, parse_screen, phase_group, rows_from_csv, rows_to_csv
from ligwf.scene.scaling import ScaledScene
from ligwf.study.case import CaseFolder
from ligwf.study.manifest import Attempt, Manifest, now_iso

_VERSION_RE = re.compile(r"^LIGGGHTS \((Version .*)\)\s*$")


def expectation(s: ScaledScene) -> Expectation:
    """Healthy end state of a scaled scene: particle count, step counts, KE ceiling."""
    mean_volume = sum(f * math.pi * d**3 / 6.0 for d, f in zip(s.diameters, s.number_fractions))
    mass = s.particle_count * s.density * mean_volume
    return Expectation(particle_count=s.particle_count,
                       settle_end_step=s.insertion_steps + s.settle_steps,
                       total_steps=s.total_steps,
                       ke_ceiling=kinetic_energy_ceiling(mass, s.drum_diameter, s.omega))


def engine_version(lines: list[str]) -> str | None:
    """The ``LIGGGHTS (Version ...)`` banner of a screen capture."""
    for line in lines[:20]:
        m = _VERSION_RE.match(line.strip())
        if m:
            return "LIGGGHTS " + m.group(1)
    return None


def begin_attempt(case: CaseFolder, plan: Plan, nprocs: int, launcher: str,
                  command: list[str] | None = None, template_dirs=()) -> tuple[Manifest, Attempt]:
    """Prepare the folder for ``plan`` (clean or write the resume input) and record the
    attempt as ``running`` in the manifest. Returns the manifest and the new attempt."""
    previous = case.manifest()
    if plan.action == FRESH or previous is None:
        clean_outputs(case.path)
        manifest = Manifest(case_id=case.case_id, index=case.index, scene_hash=case.scene_hash,
                            ligwf_version=__version__, liggghts_version="")
        from_step, restart_path = 0, None
    elif plan.action == RESUME and plan.restart is not None:
        for name, text in render_resume(case.scaled, plan.restart, template_dirs).items():
            atomic_write_text(case.path / name, text)
        rotate_screen(case.path)
        manifest = previous
        from_step, restart_path = plan.restart.step, plan.restart.path
    else:
        raise ValueError(f"begin_attempt: nothing to run for plan {plan}")
    manifest.status, manifest.reason, manifest.reason_step = RUNNING, plan.reason, None
    manifest.host, manifest.pid = os.uname().nodename, os.getpid()
    manifest.launcher, manifest.nprocs = launcher, nprocs
    manifest.command = list(command or [])
    manifest.total_steps = case.scaled.total_steps
    manifest.ended = None
    attempt = Attempt(number=len(manifest.attempts) + 1, started=now_iso(), nprocs=nprocs,
                      command=list(command or []), input=input_for(plan),
                      from_restart=restart_path, from_step=from_step)
    manifest.attempts.append(attempt)
    case.write_manifest(manifest)
    return manifest, attempt


def _merge_rows(previous: list[ThermoRow], new: list[ThermoRow], from_step: int,
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


def finish_attempt(case: CaseFolder, manifest: Manifest, attempt: Attempt,
                   exit_code: int | None, wall_seconds: float, killed: bool = False,
                   engine_version_line: str | None = None) -> Manifest:
    """Judge the attempt from its screen capture and write thermo table + manifest."""
    s = case.scaled
    screen = case.path / attempt.screen
    text = screen.read_text(errors="replace") if screen.exists() else ""
    parser = parse_screen(text)
    previous: list[ThermoRow] = []
    if attempt.from_step and case.thermo.exists():
        previous = rows_from_csv(case.thermo.read_text())
    rows = _merge_rows(previous, parser.rows, attempt.from_step, s.dt)
    expect = expectation(s)
    issues = assess(rows, parser.lines, expect)
    steps_done = rows[-1].step if rows else attempt.from_step
    status, reason = verdict(issues, exit_code, steps_done, s.total_steps, killed)

    attempt.ended = now_iso()
    attempt.wall_seconds = wall_seconds
    attempt.exit_code = exit_code
    attempt.status, attempt.reason = status, reason
    manifest.status, manifest.reason = status, reason
    manifest.reason_step = _cause_step(issues, status)
    manifest.issues = [i.to_dict() for i in issues]
    manifest.liggghts_version = (engine_version(parser.lines) or engine_version_line
                                 or manifest.liggghts_version)
    manifest.ended = attempt.ended
    manifest.wall_seconds += wall_seconds
    manifest.core_seconds += wall_seconds * attempt.nprocs
    manifest.steps_done = steps_done
    for phase, wall in parser.phase_walls().items():
        rec = manifest.phases.setdefault(phase, {"wall_seconds": 0.0, "core_seconds": 0.0,
                                                 "steps": 0})
        rec["wall_seconds"] += wall
        rec["core_seconds"] += wall * attempt.nprocs
    for phase, steps in parser.phase_steps().items():
        manifest.phases.setdefault(phase, {"wall_seconds": 0.0, "core_seconds": 0.0, "steps": 0})
        manifest.phases[phase]["steps"] += steps
    if rows:
        manifest.atoms_start = int(rows[0].get("atoms")) if manifest.atoms_start is None else \
            manifest.atoms_start
        manifest.atoms_end = _int_or_none(rows[-1].get("atoms"))
        manifest.simulated_time = rows[-1].get("time", 0.0)
        settled = [r for r in rows if r.step <= expect.settle_end_step]
        if settled and settled[-1].step == expect.settle_end_step:
            manifest.atoms_after_settle = _int_or_none(settled[-1].get("atoms"))
    atomic_write_text(case.thermo, rows_to_csv(rows))
    case.write_manifest(manifest)
    return manifest


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


__all__ = ["begin_attempt", "finish_attempt", "expectation", "engine_version", "phase_group",
           "restart_unreadable"]
