"""Health of a LIGGGHTS run: pure checks over thermo rows and screen text.

Exit code 0 does not mean success in LIGGGHTS: with too large a time step atoms vanish and
the engine exits 0; a NaN force still ends in a normal-looking thermo table. Each check
here looks for one failure signature from ../shared/LIGGGHTS_NOTES.md and returns
:class:`HealthIssue` records (kind, step, message); :func:`verdict` turns them, with the
exit code and the step count, into the case status written to the manifest.

Every function is pure (rows and lines in, issues out), so the runtime monitor, the final
assessment and the stability suite (``ligwf.scene.stability``) share them.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Iterable, Sequence

from ligwf.study.manifest import DONE, FAILED, KILLED, UNSTABLE
from ligwf.study.thermo_table import ThermoRow, atom_fall

#: Issue kinds that make a case ``failed`` (the engine stopped on an error) rather than
#: ``unstable`` (it ran, but the physics went wrong).
FATAL_KINDS = frozenset({"error", "exit_code", "incomplete"})

#: Default factor by which the kinetic energy may exceed its physical ceiling.
KE_CEILING_FACTOR = 10.0
#: Default jump of the kinetic energy over its running maximum counted as a blow-up.
KE_JUMP_FACTOR = 1.0e3


@dataclass(frozen=True)
class HealthIssue:
    """One failure signature found in a run: what, at which step, in words."""

    kind: str
    step: int | None
    message: str

    @property
    def fatal(self) -> bool:
        return self.kind in FATAL_KINDS

    def to_dict(self) -> dict:
        return {"kind": self.kind, "step": self.step, "message": self.message}


@dataclass(frozen=True)
class Expectation:
    """What a healthy run of one case reaches (from the scaled scene)."""

    particle_count: int
    settle_end_step: int       # insertion + settling steps
    total_steps: int
    ke_ceiling: float | None   # J; see :func:`kinetic_energy_ceiling`


def kinetic_energy_ceiling(mass: float, drum_diameter: float, omega: float,
                           gravity: float = 9.81) -> float:
    """Largest kinetic energy a drum bed can physically have, J.

    A particle can at most fall the drum diameter and be carried at the wall speed, so
    KE <= m g D + m (omega R)^2 / 2 for the bed mass m (kg), drum diameter D (m) and
    rotation rate omega (rad/s). Exceeding it by an order of magnitude means energy came
    from the integrator, not from gravity or the drum: a numerical blow-up.
    """
    r = 0.5 * drum_diameter
    return mass * gravity * drum_diameter + 0.5 * mass * (omega * r) ** 2


def non_finite(rows: Sequence[ThermoRow]) -> list[HealthIssue]:
    """First row with a nan or inf value (LIGGGHTS prints ``-nan``, ``nan``, ``inf``)."""
    for row in rows:
        bad = [k for k, v in row.values.items() if not math.isfinite(v)]
        if bad:
            return [HealthIssue("nan", row.step, f"non-finite thermo value(s) "
                                f"{', '.join(bad)} at step {row.step}")]
    return []


def atom_loss(rows: Sequence[ThermoRow], target: int | None = None) -> list[HealthIssue]:
    """First drop of the atom count (atoms are only ever added, by insertion):
    :func:`ligwf.study.thermo_table.atom_fall` (``target``: the particle count asked for),
    the rule the folder model also holds a finished case's table to."""
    fall = atom_fall(list(rows), target)
    if fall is None:
        return []
    step, top, atoms = fall
    return [HealthIssue("atom_loss", step, f"atom count fell from {top:.0f} to "
                        f"{atoms:.0f} at step {step}")]


def kinetic_energy_blowup(rows: Sequence[ThermoRow], ceiling: float | None = None,
                          ceiling_factor: float = KE_CEILING_FACTOR,
                          jump_factor: float = KE_JUMP_FACTOR) -> list[HealthIssue]:
    """First row whose kinetic energy (translational + rotational, J) blows up.

    Two tests: above ``ceiling_factor`` x the physical ceiling (when known), or more than
    ``jump_factor`` x the running maximum once that maximum is a meaningful share (1e-3)
    of the ceiling -- the drum start-up itself multiplies a settled bed's KE by ~1e4, so
    a bare ratio test would flag every healthy run.
    """
    running_max = 0.0
    floor = 1e-3 * ceiling if ceiling else 0.0
    for row in rows:
        ke = row.get("ke", 0.0) + row.get("rke", 0.0)
        if not math.isfinite(ke):
            continue
        if ceiling and ke > ceiling_factor * ceiling:
            return [HealthIssue("ke_blowup", row.step, f"kinetic energy {ke:.3g} J at step "
                                f"{row.step} exceeds {ceiling_factor:g}x the physical ceiling "
                                f"{ceiling:.3g} J")]
        if running_max > floor and running_max > 0 and ke > jump_factor * running_max:
            return [HealthIssue("ke_blowup", row.step, f"kinetic energy jumped {ke / running_max:.3g}x "
                                f"to {ke:.3g} J at step {row.step}")]
        running_max = max(running_max, ke)
    return []


def insertion_shortfall(rows: Sequence[ThermoRow], particle_count: int,
                        settle_end_step: int) -> list[HealthIssue]:
    """Fewer atoms than asked for at the end of settling (the fill did not fit)."""
    at_end = [r for r in rows if r.step <= settle_end_step]
    if not at_end or at_end[-1].step < settle_end_step:
        return []  # the run has not reached the end of settling (judged elsewhere)
    atoms = at_end[-1].get("atoms")
    if math.isfinite(atoms) and atoms < particle_count:
        return [HealthIssue("insertion_shortfall", settle_end_step,
                            f"only {atoms:.0f} of {particle_count} particles in the drum at the "
                            f"end of settling (step {settle_end_step})")]
    return []


_LOST_RE = re.compile(r"original (\d+) current (\d+)")


def _step_at(lines: Sequence[str], index: int) -> int | None:
    """Last thermo step printed before line ``index`` (a line starting with an integer)."""
    for line in reversed(lines[:index]):
        tokens = line.split()
        if tokens and tokens[0].isdigit() and len(tokens) > 3:
            return int(tokens[0])
    return None


#: What an engine error line means, for the reason of a failed case: (pattern, hint).
#: The first match wins; the hint says what happened and what to change.
ENGINE_ERROR_HINTS: tuple[tuple[re.Pattern, str], ...] = (
    (re.compile(r"Internal error \(\S*tri_mesh_I\.h"),
     "LIGGGHTS found a mesh-wall contact point in no region of its triangle "
     "(TriMesh::resolveTriSphereContactBary: its barycentric coordinates are not "
     "finite), i.e. a particle position turned nan/inf: the integration blew up. Seen "
     "with stiff particles (hard_particles, E > 1e9 Pa) at dt above 0.16 of the Rayleigh "
     "time; lower numerics.dt_rayleigh_fraction (0.16 ran) or particles.youngs_modulus"),
    (re.compile(r"Internal error"),
     "an internal consistency check of LIGGGHTS failed, usually after a nan reached the "
     "particle data (look at the thermo rows before it); lower the time step"),
    (re.compile(r"Atom types must start from 1|Lost atoms"),
     "particles left the domain (a time step far too large, or a leaking drum)"),
    (re.compile(r"mesh elements have been lost|left the domain", re.I),
     "the drum mesh does not fit the simulation box (mesh or box length changed?)"),
)


def error_hint(message: str) -> str | None:
    """The hint for an engine error line (None: no known meaning)."""
    for pattern, hint in ENGINE_ERROR_HINTS:
        if pattern.search(message):
            return hint
    return None


def log_errors(lines: Sequence[str]) -> list[HealthIssue]:
    """``ERROR`` / ``ERROR on proc N`` lines, and MPI_ABORT notices without one."""
    for i, line in enumerate(lines):
        text = line.strip()
        if text.startswith("ERROR"):
            return [HealthIssue("error", _step_at(lines, i), text)]
    for i, line in enumerate(lines):
        if "MPI_ABORT was invoked" in line:
            return [HealthIssue("error", _step_at(lines, i), line.strip())]
    return []


def log_warnings(lines: Sequence[str]) -> list[HealthIssue]:
    """Time-step warnings of ``check/timestep/gran`` and ``Lost atoms`` warnings."""
    issues: list[HealthIssue] = []
    seen: set[str] = set()
    for i, line in enumerate(lines):
        text = line.strip()
        kind = None
        if "time-step is" in text and "of" in text and text.startswith("WARNING"):
            kind = "timestep_warning"
        elif "time step too large" in text:
            kind = "timestep_warning"
        elif "Lost atoms" in text:
            # LIGGGHTS also prints "original 0 current 0" once a nan reaches the atom
            # count: only a real drop is an atom loss (the nan is reported by itself)
            m = _LOST_RE.search(text)
            if m is None or int(m.group(2)) < int(m.group(1)):
                kind = "lost_atoms"
        if kind and kind not in seen:
            seen.add(kind)
            issues.append(HealthIssue(kind, _step_at(lines, i), text))
    return issues


def physics_issues(rows: Sequence[ThermoRow],
                   expect: Expectation | None = None) -> list[HealthIssue]:
    """nan, atom loss and kinetic-energy blow-up over a case's rows (all attempts: a
    resumed bed at rest must be judged against the history of its case, not its own first
    row). The live monitor and the final assessment share this rule."""
    return (non_finite(rows)
            + atom_loss(rows, expect.particle_count if expect else None)
            + kinetic_energy_blowup(rows, expect.ke_ceiling if expect else None))


def assess(rows: Sequence[ThermoRow], lines: Iterable[str],
           expect: Expectation | None = None) -> list[HealthIssue]:
    """Every failure signature in a run (rows + screen lines), earliest first."""
    lines = list(lines)
    issues = log_errors(lines) + log_warnings(lines) + physics_issues(rows, expect)
    if expect is not None:
        issues += insertion_shortfall(rows, expect.particle_count, expect.settle_end_step)
    return sorted(issues, key=lambda i: (i.step if i.step is not None else math.inf))


#: signals that stop an engine from outside (user, scheduler, OOM killer, a lost runner):
#: the case is ``killed`` and resumes from its newest restart. Other signals are crashes.
STOP_SIGNALS = frozenset({1, 2, 9, 15, 24})
#: mpirun's notice when a rank dies by a signal (OpenMPI 4.1), e.g. "... exited on signal 9"
_RANK_SIGNAL_RE = re.compile(r"exited on signal (\d+)")
#: srun's notice when a task dies by a signal: "srun: error: node2: task 1: Killed"
#: (the signal's strsignal text)
_SRUN_SIGNAL_RE = re.compile(r"srun: error: \S+: tasks? [0-9,\-\[\]]+: (.+?)\s*$")
_SIGNAL_NAMES = {"Hangup": 1, "Interrupt": 2, "Killed": 9, "Terminated": 15,
                 "CPU time limit exceeded": 24}


def engine_signal(lines: Sequence[str], exit_code: int | None) -> int | None:
    """Signal that ended the engine: the launcher's notice about a rank (mpirun's, or
    srun's for a task on any node of the allocation), the launcher's own (a negative exit
    code from ``subprocess``), or a launcher exit code of 128 + a stop signal (how srun and
    mpirun report a task killed from outside: 137 for SIGKILL). None when it exited by
    itself."""
    for line in reversed(lines[-100:]):
        m = _RANK_SIGNAL_RE.search(line)
        if m:
            return int(m.group(1))
        m = _SRUN_SIGNAL_RE.search(line)
        if m and m.group(1) in _SIGNAL_NAMES:
            return _SIGNAL_NAMES[m.group(1)]
    if exit_code is not None and exit_code < 0:
        return -exit_code
    if exit_code is not None and exit_code > 128 and exit_code - 128 in STOP_SIGNALS:
        return exit_code - 128
    return None


def verdict(issues: Sequence[HealthIssue], exit_code: int | None, steps_done: int,
            total_steps: int, killed: bool = False, signal: int | None = None,
            stop_problem: str | None = None) -> tuple[str, str]:
    """Case status and reason from the issues, the exit code and the steps reached.

    Order matters: an ERROR line explains a bad exit code; a physics issue (atom loss,
    nan, blow-up, time-step warning) makes the outputs unusable even when the engine
    finished, as does the problem the live monitor stopped the run for
    (``stop_problem``); a stop requested by the user or the scheduler, or an engine
    killed by a stop signal (:data:`STOP_SIGNALS`), is ``killed`` (resumable); any other
    signal is a crash.
    """
    errors = [i for i in issues if i.kind == "error"]
    physics = [i for i in issues if not i.fatal]
    if errors:
        hint = error_hint(errors[0].message)
        return FAILED, errors[0].message + (f" -- {hint}" if hint else "")
    if physics:
        first = physics[0]
        return UNSTABLE, f"{first.kind}: {first.message}"
    if stop_problem:
        return UNSTABLE, f"stopped by the live check: {stop_problem}"
    if killed and steps_done < total_steps:   # (a stop that came too late changes nothing)
        return KILLED, f"stopped at step {steps_done} of {total_steps}"
    if signal in STOP_SIGNALS:
        return KILLED, f"engine killed by signal {signal} at step {steps_done} of {total_steps}"
    if signal is not None:
        return FAILED, f"engine crashed (signal {signal}) at step {steps_done} of {total_steps}"
    if exit_code not in (0, None):
        return FAILED, f"engine exit code {exit_code} at step {steps_done} of {total_steps}"
    if steps_done < total_steps:
        return FAILED, f"run ended at step {steps_done} of {total_steps} without an error line"
    return DONE, f"finished: all {steps_done} steps"
