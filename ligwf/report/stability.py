"""Observed outcome of a finished case, next to its pre-flight verdict.

The runtime signatures (errors, nan, atom loss, kinetic-energy blow-up, time-step
warnings) are the runner's health checks (:mod:`ligwf.engine.health`) applied to the captured
screen output; this module only adds what the stress suite needs on top:

* the **observed outcome** class: ``stable``, ``error``, ``nan``, ``atoms lost``,
  ``blow-up``, ``dt warning``, ``fill short`` or ``overlap`` (interpenetration beyond
  :data:`ligwf.scene.stability.OVERLAP_LIMIT`, seen in the dumps);
* the **energy drift** of the production phase: relative change of the mean kinetic
  energy (translational + rotational) from its first to its last third. A turning drum is
  driven and dissipative, so total energy is not conserved; a steady bed keeps a
  statistically constant kinetic energy, and a numerical heating shows as a large drift;
* the **maximum overlap observed** in the particle dumps (pairs, across the periodic
  boundary too, and particle-shell), compared with the pre-flight expectation.

Why dumps and not a thermo quantity: the dumps exist in every case without changing the
input, they hold positions (float32, ~1e-9 m resolution in a centimetre drum, far below
the micrometre overlaps of interest) and so capture the persistent overlaps that a wet or
soft bed keeps. Impact peaks last one contact time and fall between dumps; they are what
the engine's own ``f_ts[2]`` (dt / Hertz time at the current largest speed) watches.

A case is judged to AGREE when the pre-flight refused it exactly when it was observed not
stable (``ok`` and ``marginal`` predict a stable run).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ligwf.analysis.frames.dumps import discover_frames, read_particles
from ligwf.engine import health
from ligwf.engine.attempt import expectation
from ligwf.engine.thermo import parse_screen
from ligwf.errors import DumpReadError
from ligwf.scene.scaled import ScaledScene
from ligwf.scene.stability import OVERLAP_LIMIT, REFUSED, Preflight, preflight
from ligwf.study.case import CaseFolder
from ligwf.study.study import studies_below

STABLE = "stable"
_OUTCOME_OF_KIND = {
    "error": "error", "exit_code": "error", "incomplete": "error",
    "nan": "nan",
    "atom_loss": "atoms lost", "lost_atoms": "atoms lost",
    "ke_blowup": "blow-up",
    "timestep_warning": "dt warning",
    "insertion_shortfall": "fill short",
}

#: Outcome classes, most severe first: a case is named by its worst issue.
_SEVERITY = ("error", "nan", "atoms lost", "blow-up", "fill short", "dt warning")


@dataclass(frozen=True)
class Observation:
    """What the engine did in one case."""

    outcome: str                 # STABLE or a failure class
    reason: str
    atoms_start: float | None    # largest atom count reached (after filling)
    atoms_end: float | None
    energy_drift: float | None   # relative, see module docstring
    max_overlap: float | None    # m, largest in the dumps (None: no dump)
    max_dt_hertz: float | None   # largest engine f_ts[2]


def energy_drift(rows) -> float | None:
    ke = [r.get("ke", 0.0) + r.get("rke", 0.0) for r in rows if r.phase == "production"]
    if len(ke) < 6:
        return None
    third = len(ke) // 3
    first, last = np.mean(ke[:third]), np.mean(ke[-third:])
    if not (math.isfinite(first) and math.isfinite(last)):
        return math.inf
    return (last - first) / first if first > 0 else None


def max_overlap_in_frame(positions: np.ndarray, radii: np.ndarray, s: ScaledScene) -> float:
    """Largest overlap (m) of a frame: particle pairs (periodic images included) and the
    cylindrical shell (radius R; its polygon facets lie inside, so this never overstates)."""
    from scipy.spatial import cKDTree

    ia = s.drum.axis.index
    pos, rad = positions, radii
    if s.drum.periodic:
        reach = 2.0 * rad.max()
        ax = pos[:, ia]
        lo, hi = ax < reach, ax > s.drum.length - reach
        shift = np.zeros(3)
        shift[ia] = s.drum.length
        pos = np.vstack([positions, positions[lo] + shift, positions[hi] - shift])
        rad = np.concatenate([radii, radii[lo], radii[hi]])
    n = len(positions)
    tree = cKDTree(pos)
    pairs = tree.query_pairs(2.0 * rad.max(), output_type="ndarray")
    pairs = pairs[(pairs[:, 0] < n) | (pairs[:, 1] < n)]
    best = 0.0
    if len(pairs):
        dist = np.linalg.norm(pos[pairs[:, 0]] - pos[pairs[:, 1]], axis=1)
        best = float(np.max(rad[pairs[:, 0]] + rad[pairs[:, 1]] - dist))
    radial = np.delete(positions, ia, axis=1)
    wall = np.linalg.norm(radial, axis=1) + radii - 0.5 * s.drum.diameter
    return max(best, float(wall.max()), 0.0)


def observed_max_overlap(case_dir: Path, s: ScaledScene) -> float | None:
    best = None
    for frame in discover_frames(case_dir):
        try:
            p = read_particles(frame.particles)
        except DumpReadError:
            continue
        if not np.all(np.isfinite(p.positions)):
            continue
        value = max_overlap_in_frame(p.positions, p.radii, s)
        best = value if best is None else max(best, value)
    return best


def observe(case: CaseFolder) -> Observation:
    """Observed outcome of a finished case folder (screen capture + dumps)."""
    s = case.scaled
    if not case.screen.is_file():
        return Observation("not run", f"no screen capture {case.screen.name}", None, None,
                           None, None, None)
    parsed = parse_screen(case.screen.read_text(errors="replace"))
    rows = parsed.rows
    issues = health.assess(rows, parsed.lines, expectation(s))
    last = rows[-1].step if rows else 0
    if not issues and last < s.total_steps:
        issues.append(health.HealthIssue("incomplete", last,
                                         f"run ended at step {last} of {s.total_steps}"))
    atoms = [r.get("atoms") for r in rows if math.isfinite(r.get("atoms"))]
    hertz = [r.get("dt_hertz") for r in rows if math.isfinite(r.get("dt_hertz"))]
    overlap = observed_max_overlap(case.path, s)
    outcome, reason = STABLE, f"{last} steps, no health issue"
    if issues:
        first = min(issues, key=lambda i: _SEVERITY.index(_OUTCOME_OF_KIND.get(i.kind, "error")))
        outcome, reason = _OUTCOME_OF_KIND.get(first.kind, first.kind), first.message
    elif overlap is not None and overlap > OVERLAP_LIMIT * s.d_min:
        outcome = "overlap"
        reason = (f"particles interpenetrate by {overlap / s.d_min:.1%} of the smallest "
                  f"diameter (limit {OVERLAP_LIMIT:.0%})")
    return Observation(outcome, reason, max(atoms) if atoms else None,
                       atoms[-1] if atoms else None, energy_drift(rows), overlap,
                       max(hertz) if hertz else None)


@dataclass(frozen=True)
class CaseReport:
    case_dir: Path
    scaled: ScaledScene
    preflight: Preflight
    observation: Observation

    @property
    def name(self) -> str:
        """``<variant>/<case_id>`` (the study folder's sub-folder and the case folder)."""
        return f"{self.case_dir.parent.name}/{self.case_dir.name}"

    @property
    def d_min(self) -> float:
        return self.scaled.d_min

    @property
    def predicted(self) -> str:
        return health.UNSTABLE if self.preflight.verdict == REFUSED else STABLE

    @property
    def agrees(self) -> bool:
        if self.observation.outcome == "not run":
            return False
        return (self.predicted == STABLE) == (self.observation.outcome == STABLE)

    def to_dict(self) -> dict:
        o = self.observation
        return {"case": self.name, "verdict": self.preflight.verdict,
                "predicted": self.predicted, "outcome": o.outcome, "reason": o.reason,
                "agrees": self.agrees, "atoms_start": o.atoms_start, "atoms_end": o.atoms_end,
                "energy_drift": None if o.energy_drift is None or not math.isfinite(o.energy_drift)
                else o.energy_drift,
                "max_overlap_observed": o.max_overlap,
                "max_overlap_expected": self.preflight.expected_max_overlap
                if math.isfinite(self.preflight.expected_max_overlap) else None,
                "max_dt_hertz_engine": o.max_dt_hertz,
                "findings": [f.message for f in self.preflight.problems]}


def report_case(case: CaseFolder) -> CaseReport:
    """Pre-flight verdict and observed outcome of one case."""
    return CaseReport(case.path, case.scaled,
                      preflight(case.scaled, case.case_id, case.explicit_dt), observe(case))


def report_study(root: Path) -> list[CaseReport]:
    """Every case of the study at ``root``, or of every study below it (a stress suite)."""
    return [report_case(c) for study in studies_below(root) for c in study.cases]
