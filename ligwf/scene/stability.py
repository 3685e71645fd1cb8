"""Pre-flight stability checks: time scales, overlaps and flow regime of a scaled case.

Pure functions of a :class:`~ligwf.scene.scaling.ScaledScene` (after CG scaling, so every length,
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

Time scales (smallest scaled particle, radius r, mass m = 4/3 pi r^3 rho, same material):

* Rayleigh time (LIGGGHTS' ``fix check/timestep/gran``):
  t_R = pi r sqrt(rho / G) / (0.1631 nu + 0.8766), G = E / (2 (1 + nu)).
* Hertz contact duration (Johnson, Contact Mechanics 1985, eq. 11.24, the estimate
  LIGGGHTS uses): t_H = 2.87 (m_e^2 / (R_e E*^2 v))^(1/5), E* = E / (2 (1 - nu^2)).
  As in ``fix check/timestep/gran`` m_e = m (one particle), R_e = r / 2 and v is the
  largest relative speed, 2 v_imp (two particles at v_imp head on), so ligwf's dt / t_H is
  the engine's ``f_ts[2]`` at that speed.
* Expected impact speed v_imp = omega R_drum + sqrt(2 g D_drum): a particle carried at the
  wall speed to the top of the drum and falling freely across the whole diameter. This is
  an upper bound of what the bed sees below centrifuging (a cascading bed falls much less
  than D), which is the right side to err on for a time-step limit.
* Maximum Hertz overlap at impact (energy balance, Johnson eq. 11.23):
  delta = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5), m* = m / 2, R* = r / 2, v = v_imp.
* Capillary time scale (wet): t_c = sqrt(m* / k_b), with k_b the bridge stiffness
  |dF/ds| at contact: washino F = 2 pi R* gamma cos(theta) (1 - s sqrt(pi R* / (2 V)))
  gives k_b = F_0 sqrt(pi R* / (2 V)); easo F = pi gamma sqrt(r_i r_j)(exp(A s / R2 + B) + C)
  gives k_b = pi gamma r exp(B) |A| / r (see :mod:`ligwf.liquids.bridges`).
* Capillary overlap (wet): in contact the washino force F_0 (1 + k delta) pulls the pair
  together against Hertz (4/3) E* sqrt(R*) delta^(3/2); the equilibrium delta is the
  static overlap a wet bed keeps. When the capillary pull grows faster than Hertz there is
  no equilibrium: the pair collapses (the engine then loses atoms).
* Froude number Fr = omega^2 R / g; critical speed n_c = 60 / (2 pi) sqrt(g / R) rpm
  (Fr = 1). Regimes after Mellmann, Powder Technol. 118 (2001) 251, Table 2: slumping
  Fr < 1e-4, rolling < 3e-3, cascading < 0.1, cataracting < 1, centrifuging >= 1
  (the published bands overlap; these are their geometric middles).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

from ligwf.liquids.bridges import bridge_volume, engine_contact_angle_deg, engine_effective_angle_rad, \
    rupture_distance
from ligwf.errors import ConfigError
from ligwf.scene.scaling import ScaledScene
from ligwf.scene.model import GRAVITY

OK, MARGINAL, REFUSED = "ok", "marginal", "refused"
_RANK = {OK: 0, MARGINAL: 1, REFUSED: 2}

#: dt / t_R above which LIGGGHTS' check/timestep/gran warns (and the runner marks the case
#: unstable); the LIGGGHTS documentation recommends < 20 % of the Rayleigh time.
DT_RAYLEIGH_LIMIT = 0.2
#: dt / t_H limit: the same 20 % that check/timestep/gran applies to the Hertz time.
DT_HERTZ_LIMIT = 0.2
#: dt / t_c limit for the capillary spring: velocity Verlet is stable for dt < 2 t_c; the
#: same 20 % accuracy margin as for contacts keeps the bridge oscillation resolved.
DT_CAPILLARY_LIMIT = 0.2
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
#: Froude-number band edges of the regimes (Mellmann 2001).
REGIMES = ((1e-4, "slumping"), (3e-3, "rolling"), (0.1, "cascading"), (1.0, "cataracting"),
           (math.inf, "centrifuging"))


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
class TimeScales:
    """Time scales (s), speeds (m/s) and lengths (m) of the smallest scaled particle."""

    rayleigh_time: float
    impact_velocity: float
    hertz_time: float
    hertz_overlap: float
    capillary_time: float | None
    capillary_overlap: float | None   # inf when the capillary pull outruns Hertz
    rupture_distance: float | None
    bridge_cutoff: float | None       # gap (m) at which the engine cuts the bridge force
    neighbor_cutoff: float | None     # largest gap (m) of a pair in the neighbor lists
    froude: float
    critical_rpm: float
    regime: str


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
# time scales (pure formulas, hand-checkable)
# ---------------------------------------------------------------------------------------

def effective_modulus(youngs_modulus: float, poisson_ratio: float) -> float:
    """E* = E / (2 (1 - nu^2)) of two spheres of the same material, Pa."""
    return youngs_modulus / (2.0 * (1.0 - poisson_ratio**2))


def sphere_mass(radius: float, density: float) -> float:
    return 4.0 / 3.0 * math.pi * radius**3 * density


def impact_velocity(omega: float, drum_diameter: float, gravity: float = GRAVITY) -> float:
    """v_imp = omega R + sqrt(2 g D), m/s (wall speed plus free fall across the drum)."""
    return omega * 0.5 * drum_diameter + math.sqrt(2.0 * gravity * drum_diameter)


def hertz_time(radius: float, density: float, youngs_modulus: float, poisson_ratio: float,
               relative_velocity: float) -> float:
    """t_H = 2.87 (m^2 / (r/2 E*^2 v))^(1/5), s -- LIGGGHTS' check/timestep/gran estimate."""
    m = sphere_mass(radius, density)
    e_star = effective_modulus(youngs_modulus, poisson_ratio)
    return 2.87 * (m * m / (0.5 * radius * e_star**2 * relative_velocity)) ** 0.2


def hertz_max_overlap(radius: float, density: float, youngs_modulus: float,
                      poisson_ratio: float, velocity: float) -> float:
    """delta = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5), m, for two equal spheres (m* = m/2,
    R* = r/2) meeting at relative speed ``velocity``."""
    m_eff = 0.5 * sphere_mass(radius, density)
    e_star = effective_modulus(youngs_modulus, poisson_ratio)
    return (15.0 * m_eff * velocity**2 / (16.0 * e_star * math.sqrt(0.5 * radius))) ** 0.4


def engine_theta_rad(s: ScaledScene) -> float:
    """Contact angle (rad) LIGGGHTS 3.8.0 applies for this scene (product bug included)."""
    a = engine_contact_angle_deg(s.contact_angle_deg, s.contact_angle_compensation)
    return engine_effective_angle_rad(a)


def bridge_stiffness(model: str, radius: float, surface_tension: float, theta_rad: float,
                     liquid_content: float) -> tuple[float, float]:
    """(F_0 in N, k_b in N/m) of a bridge between two equal spheres at contact.

    washino: F_0 = 2 pi R* gamma cos(theta), k_b = F_0 sqrt(pi R* / (2 V)) (the slope of
    Rabinovich's eq. A11 as coded in LIGGGHTS); easo: F_0 = pi gamma r (exp(B) + C),
    k_b = pi gamma r exp(B) |A| / r (slope of Soulie's law at s = 0+).
    """
    vol = float(bridge_volume(model, radius, radius, liquid_content))
    if model == "washino":
        r_eff = 0.5 * radius
        f0 = 2.0 * math.pi * r_eff * surface_tension * math.cos(theta_rad)
        return f0, f0 * math.sqrt(math.pi * r_eff / (2.0 * vol))
    if model == "easo":
        vs = vol / radius**3
        a = -1.1 * vs ** (-0.53)
        b = (-0.148 * math.log(vs) - 0.96) * theta_rad**2 - 0.0082 * math.log(vs) + 0.48
        c = 0.0018 * math.log(vs) + 0.078
        f0 = math.pi * surface_tension * radius * (math.exp(b) + c)
        return f0, math.pi * surface_tension * radius * math.exp(b) * abs(a) / radius
    raise ConfigError(f"no bridge law for liquid model {model!r}")


def capillary_time(mass_eff: float, stiffness: float) -> float:
    """t_c = sqrt(m* / k_b), s (inf for a dry or tension-free bridge)."""
    return math.inf if stiffness <= 0.0 else math.sqrt(mass_eff / stiffness)


def capillary_overlap(radius: float, youngs_modulus: float, poisson_ratio: float,
                      f0: float, k_b: float) -> float:
    """Static overlap (m) of two equal spheres held by a bridge: the smallest delta > 0 with
    (4/3) E* sqrt(R*) delta^(3/2) = F_0 + k_b delta; inf when no delta below r exists
    (the capillary pull outgrows the Hertz repulsion: the pair collapses)."""
    if f0 <= 0.0:
        return 0.0
    c = 4.0 / 3.0 * effective_modulus(youngs_modulus, poisson_ratio) * math.sqrt(0.5 * radius)
    excess = lambda d: c * d**1.5 - f0 - k_b * d  # noqa: E731  < 0 below equilibrium
    # the excess is convex in delta and negative at 0: one root, found by bisection
    hi = radius
    if excess(hi) < 0.0:
        return math.inf
    lo = 0.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(mid) < 0.0 else (lo, mid)
    return hi


def regime(froude: float) -> str:
    for edge, name in REGIMES:
        if froude < edge:
            return name
    return REGIMES[-1][1]


def time_scales(s: ScaledScene) -> TimeScales:
    """All time scales of the smallest scaled particle of a case (pure)."""
    r = 0.5 * s.d_min
    v_imp = impact_velocity(s.omega, s.drum_diameter)
    t_h = hertz_time(r, s.density, s.youngs_modulus, s.poisson_ratio, 2.0 * v_imp)
    overlap = hertz_max_overlap(r, s.density, s.youngs_modulus, s.poisson_ratio, v_imp)
    t_c = cap_overlap = rupture = cutoff = reach = None
    if s.wet:
        theta = engine_theta_rad(s)
        f0, k_b = bridge_stiffness(s.liquid_model, r, s.surface_tension, theta, s.liquid_content)
        t_c = capillary_time(0.5 * sphere_mass(r, s.density), k_b)
        cap_overlap = capillary_overlap(r, s.youngs_modulus, s.poisson_ratio, f0, k_b)
        rupture = float(rupture_distance(bridge_volume(s.liquid_model, r, r, s.liquid_content),
                                         theta))
        # LIGGGHTS cuts the bridge at max_separation_ratio x (r_i + r_j) and registers a
        # contact distance factor 1.1 x max_separation_ratio for the neighbor lists
        cutoff = (s.max_separation_ratio - 1.0) * 2.0 * r
        reach = (1.1 * s.max_separation_ratio - 1.0) * 2.0 * r
    radius = 0.5 * s.drum_diameter
    return TimeScales(
        rayleigh_time=s.rayleigh_time, impact_velocity=v_imp, hertz_time=t_h,
        hertz_overlap=overlap, capillary_time=t_c, capillary_overlap=cap_overlap,
        rupture_distance=rupture, bridge_cutoff=cutoff, neighbor_cutoff=reach, froude=s.froude,
        critical_rpm=60.0 / (2.0 * math.pi) * math.sqrt(GRAVITY / radius),
        regime=regime(s.froude))


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
    dt, tag = s.dt, f"CG{s.cg:g}"
    dt_field = _dt_field(s, explicit_dt)
    out: list[Finding] = []

    def timestep(check: str, what: str, t: float, limit: float, cure: str) -> None:
        ratio = dt / t
        verdict = _grade(ratio, limit)
        msg = (f"{dt_field}: dt = {dt:.2g} s is {ratio:.3g}x the {what} of the smallest {tag} "
               f"particle ({t:.2g} s); limit {limit:g}x")
        if verdict != OK:
            msg += f"; use dt <= {limit * t:.2g} s{cure}"
        out.append(Finding(check, dt_field, ratio, limit, verdict, msg))

    timestep("dt_rayleigh", "Rayleigh time", sc.rayleigh_time, DT_RAYLEIGH_LIMIT,
             f" (dt_rayleigh_fraction <= {DT_RAYLEIGH_LIMIT:g})")
    timestep("dt_hertz", f"Hertz contact time at {2 * sc.impact_velocity:.2g} m/s", sc.hertz_time,
             DT_HERTZ_LIMIT, "")
    if sc.capillary_time is not None and math.isfinite(sc.capillary_time):
        timestep("dt_capillary", "capillary time sqrt(m*/k_bridge)", sc.capillary_time,
                 DT_CAPILLARY_LIMIT, " or lower liquid.surface_tension (scaled "
                 f"{s.surface_tension:.3g} N/m)")

    d = s.d_min
    ratio = sc.hertz_overlap / d
    verdict = REFUSED if ratio > OVERLAP_LIMIT else (MARGINAL if ratio > OVERLAP_WARN else OK)
    msg = (f"particles.youngs_modulus: E = {s.youngs_modulus:.3g} Pa gives an impact overlap "
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
        msg = (f"liquid.surface_tension: scaled gamma = {s.surface_tension:.3g} N/m "
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
               f"max_separation_ratio = {s.max_separation_ratio:g}) and the bridge force "
               f"is cut at {sc.bridge_cutoff:.2g} m")
        if verdict != OK:
            need = (1.0 + sc.rupture_distance / d) / 1.1
            msg += (f"; bridges vanish from the neighbor lists before they rupture: use "
                    f"max_separation_ratio >= {need:.3g}")
        out.append(Finding("rupture_cutoff", "liquid.max_separation_ratio", ratio, 1.0,
                           verdict, msg))

    verdict = MARGINAL if sc.regime in ("centrifuging", "slumping") else OK
    msg = (f"process.rotation: {s.rpm:.3g} rpm, Fr = {s.froude:.3g} ({sc.regime}); "
           f"critical speed {sc.critical_rpm:.3g} rpm (Fr = 1)")
    if sc.regime == "centrifuging":
        msg += "; the bed rides with the wall: use rpm < critical for a granulation flow"
    elif sc.regime == "slumping":
        msg += "; the bed slumps intermittently: use a faster drum for a rolling flow"
    out.append(Finding("regime", "process.rotation", s.froude, 1.0, verdict, msg))

    if s.periodic:
        ratio = s.drum_length / s.d_max
        # 1e-9: a slice of exactly 6 diameters (0.018 / 0.003) is not 'below 6'
        verdict = (REFUSED if ratio < SLICE_MIN * (1 - 1e-9) else
                   (MARGINAL if ratio < SLICE_WARN * (1 - 1e-9) else OK))
        msg = (f"drum.length: periodic slice {s.drum_length:.3g} m is {ratio:.3g} largest "
               f"{tag} diameters ({s.d_max:.3g} m); warn below {SLICE_WARN:g}, limit "
               f"{SLICE_MIN:g}")
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
    """Pre-flight of rendered cases (``ligwf.study.prepare.RenderedCase``); see :func:`enforce`."""
    reports = [preflight(rc.scaled, rc.case.case_id,
                         explicit_dt=getattr(rc.case.scene.numerics, "dt", None) is not None)
               for rc in rendered]
    return reports, enforce(reports, allow_unstable)
