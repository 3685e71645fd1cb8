"""Pre-flight stability checks: time scales, overlaps and flow regime of a scaled case.

Pure functions of a :class:`~ligwf.scene.scaled.ScaledScene` (after CG scaling, so every length,
mass and liquid property is the one LIGGGHTS will see). Each check yields a
:class:`Finding` with a verdict:

* ``ok``       -- inside the safe limit;
* ``marginal`` -- runs, but close to a limit or physically questionable: warned;
* ``refused``  -- the engine is expected to fail (atoms lost, nan, time-step warnings), or
  the bed would collapse into itself; refused unless the expert override is given.

Every finding that is not ``ok`` carries a message naming the field, its value, the limit
and a suggestion, e.g. ``dt = 6.1e-06 s is 1.2x the Rayleigh time of the smallest CG3
particle (5.1e-06 s); limit 0.2x; use dt <= 1.0e-06 s``.

Runtime detection (atom loss, nan, blow-up, engine warnings) is not here: it lives in the
runner's health checks; ``ligwf stability-report`` compares the two.

The time scales the checks grade are :mod:`ligwf.scene.timescales`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

from ligwf.errors import ConfigError
from ligwf.scene.scaled import ScaledScene
from ligwf.scene.timescales import TimeScales, time_scales

OK, MARGINAL, REFUSED = "ok", "marginal", "refused"
_RANK = {OK: 0, MARGINAL: 1, REFUSED: 2}

#: dt / t_R above which LIGGGHTS' check/timestep/gran warns (and the runner marks the case
#: unstable); the LIGGGHTS documentation recommends < 20 % of the Rayleigh time.
DT_RAYLEIGH_LIMIT = 0.2
#: Young's modulus above which ligwf renders ``hard_particles yes`` (templates/_materials.j2)
HARD_PARTICLE_MODULUS = 1e9
#: dt / t_R limit for hard particles. The engine does not hold 0.2 there: a 320-particle
#: closed drum at E = 5e9 Pa crashed the same way every time at 0.19 ("ERROR on proc 0:
#: Internal error (./src/tri_mesh_I.h:109)": TriMesh::resolveTriSphereContactBary finds
#: the contact point in no region of the triangle, i.e. the particle's position is nan --
#: the integration had blown up) and completed at 0.16 (issue 21, LIGGGHTS_NOTES
#: "Measured 2026-12-01"). A reconstruction of that scene (runner_tiny at CG2, closed,
#: 320 particles, weber and bond, alone and in an ensemble) ran past step 272,000 at 0.19
#: without the error, so the crash depends on the scene beyond dt and E; the engine
#: checks no time-step limit there, only that the contact point is finite. Refused above
#: 0.18, where the soft-particle limit turns marginal: a crash after hours costs more
#: than 12 % more steps.
DT_RAYLEIGH_LIMIT_HARD = 0.18
#: dt / t_H limit: the same 20 % that check/timestep/gran applies to the Hertz time.
DT_HERTZ_LIMIT = 0.2
#: dt / t_c limit for the capillary spring: velocity Verlet is stable for dt < 2 t_c; the
#: same 20 % accuracy margin as for contacts keeps the bridge oscillation resolved.
DT_CAPILLARY_LIMIT = 0.2
#: dt / (m* / c) of the viscous force at contact (timescales.viscous_time): an explicit
#: step damps a linear damper stably only below 2 (warned above: the damping is not
#: resolved); refused above 5. Measured 2026-12-07 on runner_tiny at CG3 (84 beads, washino,
#: s_min 0.02, 0.3 s): 4.7 ran to the end, 9.4, 14 and 19 lost atoms (runner: unstable).
DT_VISCOUS_WARN = 2.0
DT_VISCOUS_LIMIT = 5.0
#: Share of a limit above which a value is marginal (warned) rather than ok.
MARGINAL_SHARE = 0.9
#: Expected overlap / smallest diameter: above OVERLAP_WARN the Hertz contact is outside
#: its small-strain range (warned); above OVERLAP_LIMIT particles interpenetrate so far that
#: neighbours overlap through each other (refused).
OVERLAP_WARN = 0.05
OVERLAP_LIMIT = 0.2
#: Periodic slice length / largest diameter: below 1 a particle touches its own image
#: (refused); below 6 the slice constrains the flow (LIGGGHTS_NOTES: 3 CG3 diameters
#: deviate, 6 agree) -- warned.
SLICE_MIN = 1.0
SLICE_WARN = 6.0
#: Closed drum length / largest diameter below which the end caps leave no room to pour the
#: bed in (the insertion region stays 0.55 d clear of each cap): refused.
CLOSED_MIN = 3.0
#: Engine bridge cut / force-law rupture gap below which most of a bridge's range is cut off
#: (warned). The default max_separation_ratio 1.1 gives 0.58-0.85 on the shipped scenes
#: (LIGGGHTS_NOTES, measured 2026-11-28): the engine always cuts somewhat early.
BRIDGE_CUT_WARN = 0.5
#: Bed cohesion number (timescales.cohesion_number) from which the bed holds its own weight
#: over its whole depth and turns with the drum as one block (warned: it will not flow).
#: Measured on the shipped scenes: 0.17-0.2 flows (CG1, weber), 0.4-0.6 turns rigid in
#: 30-38 % of the frames (bond CG2/CG3 of we_vs_bo, LIGGGHTS_NOTES).
COHESION_NO_FLOW = 1.0


@dataclass(frozen=True)
class Finding:
    """One check of one case."""

    check: str
    field: str            # the scene field a user changes to fix it
    value: float
    limit: float
    verdict: str
    message: str


@dataclass(frozen=True)
class Preflight:
    """All findings of one case and its overall verdict (the worst finding)."""

    case_id: str
    cg: float
    rule: str
    dt: float
    scales: TimeScales
    findings: tuple[Finding, ...] = field(default_factory=tuple)

    @property
    def verdict(self) -> str:
        return max((f.verdict for f in self.findings), key=_RANK.__getitem__, default=OK)

    @property
    def problems(self) -> list[Finding]:
        return [f for f in self.findings if f.verdict != OK]

    @property
    def expected_max_overlap(self) -> float:
        """Largest overlap (m) expected: Hertz impact or static capillary."""
        cap = self.scales.capillary_overlap or 0.0
        return max(self.scales.hertz_overlap, cap)

    def to_dict(self) -> dict:
        out = {"case_id": self.case_id, "cg": self.cg, "rule": self.rule, "dt": self.dt,
               "verdict": self.verdict, "scales": asdict(self.scales),
               "expected_max_overlap": self.expected_max_overlap,
               "findings": [asdict(f) for f in self.findings]}
        return _finite(out)


def _finite(obj):
    """JSON has no inf: write it as None."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_finite(v) for v in obj]
    return obj


# ---------------------------------------------------------------------------------------
# checks
# ---------------------------------------------------------------------------------------

def _grade(ratio: float, limit: float) -> str:
    if ratio > limit:
        return REFUSED
    if ratio > MARGINAL_SHARE * limit:
        return MARGINAL
    return OK


def _dt_field(s: ScaledScene, explicit_dt: bool) -> str:
    return "numerics.dt" if explicit_dt else "numerics.dt_rayleigh_fraction"


def preflight(s: ScaledScene, case_id: str = "", explicit_dt: bool = False) -> Preflight:
    """Every pre-flight check of one scaled case (pure).

    ``explicit_dt`` says the user fixed ``numerics.dt`` (so messages point at that field).
    """
    sc = time_scales(s)
    dt, tag = s.numerics.dt, f"CG{s.cg:g}"
    dt_field = _dt_field(s, explicit_dt)
    out: list[Finding] = []

    def timestep(check: str, what: str, t: float, limit: float, cure: str,
                 why: str = "") -> None:
        ratio = dt / t
        verdict = _grade(ratio, limit)
        msg = (f"{dt_field}: dt = {dt:.2g} s is {ratio:.3g}x the {what} of the smallest {tag} "
               f"particle ({t:.2g} s); limit {limit:g}x{why}")
        if verdict != OK:
            # a marginal dt already meets the limit: suggest one below the marginal band
            safe = limit if verdict == REFUSED else MARGINAL_SHARE * limit
            msg += f"; use dt <= {safe * t:.2g} s{cure.format(safe=safe)}"
        out.append(Finding(check, dt_field, ratio, limit, verdict, msg))

    hard = s.particles.youngs_modulus > HARD_PARTICLE_MODULUS
    timestep("dt_rayleigh", "Rayleigh time", sc.rayleigh_time,
             DT_RAYLEIGH_LIMIT_HARD if hard else DT_RAYLEIGH_LIMIT,
             " (dt_rayleigh_fraction <= {safe:.2g})",
             f" (hard particles, E = {s.particles.youngs_modulus:.3g} Pa > "
             f"{HARD_PARTICLE_MODULUS:g}: "
             "the engine crashed at 0.19 with a nan position at a wall contact, "
             "tri_mesh_I.h:109)" if hard else "")
    timestep("dt_hertz", f"Hertz contact time at {2 * sc.impact_velocity:.2g} m/s", sc.hertz_time,
             DT_HERTZ_LIMIT, "")
    if sc.capillary_time is not None and math.isfinite(sc.capillary_time):
        timestep("dt_capillary", "capillary time sqrt(m*/k_bridge)", sc.capillary_time,
                 DT_CAPILLARY_LIMIT, " or lower liquid.surface_tension (scaled "
                 f"{s.liquid_values.surface_tension:.3g} N/m)")

    if sc.viscous_time is not None and math.isfinite(sc.viscous_time):
        ratio = dt / sc.viscous_time
        verdict = (REFUSED if ratio > DT_VISCOUS_LIMIT else
                   MARGINAL if ratio > DT_VISCOUS_WARN else OK)
        msg = (f"{dt_field}: dt = {dt:.2g} s is {ratio:.3g}x the viscous damping time m*/c of "
               f"the smallest {tag} pair in contact ({sc.viscous_time:.2g} s; c = 6 pi mu R* / "
               f"s_min, mu = {s.liquid_values.viscosity:.3g} Pa s scaled, s_min = "
               f"{s.liquid_values.min_separation_ratio:g}); warn above {DT_VISCOUS_WARN:g}, "
               f"limit {DT_VISCOUS_LIMIT:g}")
        if verdict != OK:
            msg += (f"; use dt <= {DT_VISCOUS_WARN * sc.viscous_time:.2g} s, or a larger "
                    "liquid.min_separation_ratio, or a lower liquid.viscosity")
        out.append(Finding("dt_viscous", dt_field, ratio, DT_VISCOUS_LIMIT, verdict, msg))

    d = s.d_min
    ratio = sc.hertz_overlap / d
    verdict = REFUSED if ratio > OVERLAP_LIMIT else (MARGINAL if ratio > OVERLAP_WARN else OK)
    msg = (f"particles.youngs_modulus: E = {s.particles.youngs_modulus:.3g} Pa "
           "gives an impact overlap "
           f"of {ratio:.2%} of the smallest {tag} diameter at {sc.impact_velocity:.2g} m/s; "
           f"warn above {OVERLAP_WARN:.0%}, limit {OVERLAP_LIMIT:.0%}")
    if verdict != OK:
        msg += "; use a stiffer material (larger youngs_modulus) or a slower drum"
    out.append(Finding("hertz_overlap", "particles.youngs_modulus", ratio, OVERLAP_LIMIT,
                       verdict, msg))

    if sc.capillary_overlap is not None:
        ratio = sc.capillary_overlap / d
        verdict = REFUSED if ratio > OVERLAP_LIMIT else (MARGINAL if ratio > OVERLAP_WARN
                                                         else OK)
        shown = "no equilibrium (the bridge pull outgrows Hertz)" if math.isinf(ratio) \
            else f"{ratio:.2%} of the smallest {tag} diameter"
        msg = (f"liquid.surface_tension: scaled gamma = {s.liquid_values.surface_tension:.3g} N/m "
               f"({s.rule} rule) gives a static capillary overlap of {shown}; warn above "
               f"{OVERLAP_WARN:.0%}, limit {OVERLAP_LIMIT:.0%}")
        if verdict != OK:
            msg += ("; lower surface_tension, use the weber rule or a stiffer material")
        out.append(Finding("capillary_overlap", "liquid.surface_tension", ratio,
                           OVERLAP_LIMIT, verdict, msg))

    if sc.rupture_distance is not None and sc.neighbor_cutoff is not None:
        ratio = sc.rupture_distance / sc.neighbor_cutoff
        verdict = MARGINAL if ratio > 1.0 else OK
        msg = (f"liquid.max_separation_ratio: bridges rupture at a gap of "
               f"{sc.rupture_distance:.2g} m; the neighbor lists reach a gap of "
               f"{sc.neighbor_cutoff:.2g} m (contact distance factor 1.1 x "
               f"max_separation_ratio = {s.liquid_values.max_separation_ratio:g}) "
               "and the bridge force "
               f"is cut at {sc.bridge_cutoff:.2g} m")
        if verdict != OK:
            need = (1.0 + sc.rupture_distance / d) / 1.1
            msg += (f"; bridges vanish from the neighbor lists before they rupture: use "
                    f"max_separation_ratio >= {need:.3g}")
        out.append(Finding("rupture_cutoff", "liquid.max_separation_ratio", ratio, 1.0,
                           verdict, msg))

    if sc.rupture_distance and sc.bridge_cutoff is not None:
        ratio = sc.bridge_cutoff / sc.rupture_distance
        verdict = MARGINAL if ratio < BRIDGE_CUT_WARN else OK
        msg = (f"liquid.max_separation_ratio = {s.liquid_values.max_separation_ratio:g}: "
               "the engine drops a "
               f"bridge at a gap of {sc.bridge_cutoff:.2g} m, {ratio:.2g} of the force law's "
               f"own rupture gap {sc.rupture_distance:.2g} m; warn below {BRIDGE_CUT_WARN:g}")
        if verdict != OK:
            msg += (f"; bridges between the two gaps never act nor show in the contact dumps:"
                    f" use max_separation_ratio >= {1.0 + sc.rupture_distance / d:.3g}")
            if s.liquid.bridge_cut_remedy:
                msg += f" or {s.liquid.bridge_cut_remedy}"
        out.append(Finding("bridge_cut", "liquid.max_separation_ratio", ratio,
                           BRIDGE_CUT_WARN, verdict, msg))

    if sc.cohesion_number is not None:
        co = sc.cohesion_number
        verdict = MARGINAL if co >= COHESION_NO_FLOW else OK
        msg = (f"liquid.surface_tension: bed cohesion number Co = {co:.3g} (bridge force "
               f"{sc.bridge_force:.2g} N at contact, {s.rule} rule, against the weight of a "
               f"{sc.bed_depth:.2g} m deep bed; Fr = {s.drum.froude:.3g}); warn at "
               f"{COHESION_NO_FLOW:g}")
        if verdict != OK:
            msg += (f"; the bed holds its own weight and will not flow: it turns with the "
                    f"drum as one rigid block (no angle of repose, no flowing layer); "
                    f"multiply liquid.surface_tension by <= {COHESION_NO_FLOW / co:.2g}, use "
                    f"the weber rule or a deeper bed")
        out.append(Finding("bed_flow", "liquid.surface_tension", co, COHESION_NO_FLOW,
                           verdict, msg))

    verdict = MARGINAL if sc.regime in ("centrifuging", "slumping") else OK
    msg = (f"process.rotation: {s.drum.rpm:.3g} rpm, Fr = {s.drum.froude:.3g} ({sc.regime}); "
           f"critical speed {sc.critical_rpm:.3g} rpm (Fr = 1)")
    if sc.regime == "centrifuging":
        msg += "; the bed rides with the wall: use rpm < critical for a granulation flow"
    elif sc.regime == "slumping":
        msg += "; the bed slumps intermittently: use a faster drum for a rolling flow"
    out.append(Finding("regime", "process.rotation", s.drum.froude, 1.0, verdict, msg))

    ratio = s.drum.length / s.d_max
    least = SLICE_MIN if s.drum.periodic else CLOSED_MIN
    # 1e-9: a slice of exactly 6 diameters (0.018 / 0.003) is not 'below 6'
    verdict = (REFUSED if ratio < least * (1 - 1e-9) else
               (MARGINAL if ratio < SLICE_WARN * (1 - 1e-9) else OK))
    msg = (f"drum.length: {'periodic slice' if s.drum.periodic else 'closed drum'} "
           f"{s.drum.length:.3g} m is {ratio:.3g} largest {tag} diameters ({s.d_max:.3g} m); "
           f"warn below {SLICE_WARN:g}, limit {least:g}")
    if verdict != OK:
        msg += f"; use drum.length >= {SLICE_WARN * s.d_max:.3g} m or a lower CG level"
    out.append(Finding("slice_length", "drum.length", ratio, SLICE_WARN, verdict, msg))

    return Preflight(case_id, s.cg, s.rule, dt, sc, tuple(out))


class UnstableCase(ConfigError):
    """A case was refused by the pre-flight checks (override: ``--allow-unstable``)."""


def enforce(reports: list[Preflight], allow_unstable: bool = False) -> list[str]:
    """Raise :class:`UnstableCase` listing every refusal, unless ``allow_unstable``.

    Returns the warning lines (marginal findings, and refusals let through).
    """
    refusals, warnings = [], []
    for rep in reports:
        for f in rep.problems:
            line = f"{rep.case_id}: {f.message}"
            (refusals if f.verdict == REFUSED else warnings).append(line)
    if refusals and not allow_unstable:
        raise UnstableCase("pre-flight refused "
                           f"{len({r.split(':')[0] for r in refusals})} case(s):\n  "
                           + "\n  ".join(refusals)
                           + "\n(--allow-unstable runs them anyway, for experts)")
    return warnings + [f"allowed by --allow-unstable: {r}" for r in refusals]


def check_rendered(rendered, allow_unstable: bool = False) -> tuple[list[Preflight], list[str]]:
    """Pre-flight of rendered cases (``ligwf.pipeline.prepare.RenderedCase``); see :func:`enforce`."""
    reports = [preflight(rc.scaled, rc.case.case_id,
                         explicit_dt=getattr(rc.case.scene.numerics, "dt", None) is not None)
               for rc in rendered]
    return reports, enforce(reports, allow_unstable)
