"""Time scales of a scaled case for the pre-flight: contact, capillary and flow regime.

Pure formulas of a :class:`~ligwf.scene.scaled.ScaledScene` (the checks that grade them
are :mod:`ligwf.scene.stability`), for the smallest scaled particle (radius r, mass
m = 4/3 pi r^3 rho, same material):

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
* Capillary time scale (wet): t_c = sqrt(m* / k_b), with F_0 and k_b = |dF/ds| the bridge
  force and stiffness at contact, from the case's liquid model
  (``contact_force_and_stiffness`` of :mod:`ligwf.liquids`), at the angle the engine
  applies (:mod:`ligwf.liquids.contact_angle`).
* Capillary overlap (wet): in contact the bridge force F_0 + k_b delta pulls the pair
  together against Hertz (4/3) E* sqrt(R*) delta^(3/2); the equilibrium delta is the
  static overlap a wet bed keeps. When the capillary pull grows faster than Hertz there is
  no equilibrium: the pair collapses (the engine then loses atoms).
* Bed cohesion number (wet): Co = sigma_t / (rho_b g H), the tensile strength of the
  pendular bed (Rumpf 1958: sigma_t = (1 - eps) / eps * F_0 / d^2, porosity eps = 0.4)
  over the weight stress at the bed's depth H (chord height of the circular segment the
  particles fill at that porosity), bulk density rho_b = (1 - eps) rho: Co = F_0 / (eps d^2 rho g H) =
  1.31 Bo_g d / H with the granular Bond number Bo_g = F_0 / (m g). Co >= 1: the bed holds
  its own weight over its whole depth and turns with the drum as one block.
* Froude number Fr = omega^2 R / g; critical speed n_c = 60 / (2 pi) sqrt(g / R) rpm
  (Fr = 1). Regimes after Mellmann, Powder Technol. 118 (2001) 251, Table 2: slumping
  Fr < 1e-4, rolling < 3e-3, cascading < 0.1, cataracting < 1, centrifuging >= 1
  (the published bands overlap; these are their geometric middles).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ligwf.liquids.contact_angle import applied_contact_angle_rad
from ligwf.scene.model import GRAVITY
from ligwf.scene.scaled import ScaledScene

#: Froude-number band edges of the regimes (Mellmann 2001).
REGIMES = ((1e-4, "slumping"), (3e-3, "rolling"), (0.1, "cascading"), (1.0, "cataracting"),
           (math.inf, "centrifuging"))


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
    bridge_force: float | None = None   # N, bridge force at contact F_0 (wet)
    bed_depth: float = 0.0              # m, depth of the bed at rest (chord height)
    cohesion_number: float | None = None  # Co (wet), see the module docstring
    viscous_time: float | None = None   # s, m* / c of the viscous force at contact (wet)


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


#: porosity of the bed in the cohesion number (random packing of spheres)
BED_POROSITY = 0.4


def bed_depth(drum_diameter: float, fill_fraction: float) -> float:
    """Depth (m) of a bed at rest filling ``fill_fraction`` of a circle of diameter
    ``drum_diameter``: the height h of the circular segment of that area (bisection)."""
    r = 0.5 * drum_diameter
    target = fill_fraction * math.pi * r * r

    def area(h: float) -> float:
        return r * r * math.acos((r - h) / r) - (r - h) * math.sqrt(max(2 * r * h - h * h, 0.0))

    lo, hi = 0.0, 2.0 * r
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if area(mid) < target else (lo, mid)
    return 0.5 * (lo + hi)


def cohesion_number(bridge_force: float, diameter: float, density: float,
                    depth: float, gravity: float = GRAVITY) -> float:
    """Co = F_0 / (eps d^2 rho g H): the pendular bed's tensile strength (Rumpf) over its
    weight stress at depth H (see the module docstring)."""
    if depth <= 0.0:
        return math.inf
    return bridge_force / (BED_POROSITY * diameter**2 * density * gravity * depth)


def viscous_time(radius: float, density: float, viscosity: float,
                 min_separation_ratio: float) -> float:
    """m* / c of two equal particles of ``radius`` in contact: the engine's viscous normal
    force 6 pi mu R* v_n / max(s_min, gap / R*) (ligwf.liquids.capillary) is a damper of
    c = 6 pi mu R* / s_min there, which an explicit step resolves only for dt well below
    m* / c (inf without viscosity)."""
    if viscosity <= 0.0:
        return math.inf
    r_eff = 0.5 * radius
    c = 6.0 * math.pi * viscosity * r_eff / min_separation_ratio
    return 0.5 * sphere_mass(radius, density) / c


def regime(froude: float) -> str:
    for edge, name in REGIMES:
        if froude < edge:
            return name
    return REGIMES[-1][1]


def time_scales(s: ScaledScene) -> TimeScales:
    """All time scales of the smallest scaled particle of a case (pure)."""
    p, liq = s.particles, s.liquid_values
    r = 0.5 * s.d_min
    v_imp = impact_velocity(s.drum.omega, s.drum.diameter)
    t_h = hertz_time(r, p.density, p.youngs_modulus, p.poisson_ratio, 2.0 * v_imp)
    overlap = hertz_max_overlap(r, p.density, p.youngs_modulus, p.poisson_ratio, v_imp)
    t_c = cap_overlap = rupture = cutoff = reach = f0 = co = t_v = None
    # the bed the particles make (a particle_count may differ from the fill fraction)
    v_mean = sum(f * math.pi * d**3 / 6.0 for d, f in zip(p.diameters, p.number_fractions))
    fill = p.count * v_mean / ((1.0 - BED_POROSITY) * math.pi
                               * (0.5 * s.drum.diameter) ** 2 * s.drum.length)
    depth = bed_depth(s.drum.diameter, min(fill, 0.999))
    if s.wet:
        model = s.liquid
        theta = applied_contact_angle_rad(liq.contact_angle_deg, liq.contact_angle_compensation)
        f0, k_b = model.contact_force_and_stiffness(r, liq.surface_tension, theta,
                                                    liq.liquid_content)
        t_c = capillary_time(0.5 * sphere_mass(r, p.density), k_b)
        cap_overlap = capillary_overlap(r, p.youngs_modulus, p.poisson_ratio, f0, k_b)
        vol = model.bridge_volume(r, r, liq.liquid_content, liq.liquid_content)
        rupture = float(model.rupture_distance(vol, theta))
        cutoff, reach = model.engine_cutoff_gaps(r, liq.max_separation_ratio) or (None, None)
        # the bed's typical particle (number-mean diameter) holds it together
        d_mean = sum(d * f for d, f in zip(p.diameters, p.number_fractions))
        f0_mean, _ = model.contact_force_and_stiffness(0.5 * d_mean, liq.surface_tension, theta,
                                                       liq.liquid_content)
        co = cohesion_number(f0_mean, d_mean, p.density, depth)
        t_v = viscous_time(r, p.density, liq.viscosity, liq.min_separation_ratio)
    radius = 0.5 * s.drum.diameter
    return TimeScales(
        rayleigh_time=s.particles.rayleigh_time, impact_velocity=v_imp, hertz_time=t_h,
        hertz_overlap=overlap, capillary_time=t_c, capillary_overlap=cap_overlap,
        rupture_distance=rupture, bridge_cutoff=cutoff, neighbor_cutoff=reach,
        froude=s.drum.froude,
        critical_rpm=60.0 / (2.0 * math.pi) * math.sqrt(GRAVITY / radius),
        regime=regime(s.drum.froude), bridge_force=f0 if f0 is None else float(f0),
        bed_depth=depth, cohesion_number=co, viscous_time=t_v)
