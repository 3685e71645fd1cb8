"""Coarse-graining (CG) rules: pure functions from an original scene to engine parameters.

A CG-n particle is n times larger in diameter than the original it stands for. Density,
Young's modulus, Poisson ratio, restitution and friction are kept (Hertz contacts of
n-times larger spheres then give the same overlap *ratio* and the same restitution), the
drum, gravity and rotation are kept, and the liquid is rescaled so the inter-particle
liquid-bridge forces grow as the chosen rule says:

===========  =======================  ==========  =========  =============================
rule         keeps                    bridge F x   gamma x    viscosity x
===========  =======================  ==========  =========  =============================
``none``     (geometry only)          n            1          1
``weber``    We = rho R v^2/(gamma    n^2          n          n
             cos theta)
``bond``     Bo = 3 gamma cos theta   n^3          n^2        n^2
             / (2 R^2 g rho)
===========  =======================  ==========  =========  =============================

Why gamma and mu scale by n^(k-1): both LIGGGHTS capillary models (washino, easo) give a
bridge force ~ R_eff * gamma * f(dimensionless gap, V_bridge/R^3, theta) and a viscous
force ~ mu * R_eff * v * g(gap/R_eff) (see ``ligwf.liquids``). Under CG the liquid content
is a fraction of solid volume, so V_bridge/R^3 is unchanged, as are the separation ratios
and the contact angle; at the same dimensionless gap and the same velocity the forces
therefore grow like n * gamma' and n * mu'. Forces x n^k need gamma' = n^(k-1) gamma.

A liquid model's own settings (``scene.liquid.settings``, e.g. washino's bridge volume
fraction and liquid cap, both fractions) pass through every rule unchanged, as one value
scaling does not look into, in the form the engine applies them (``applied``: a value at
the engine's default reads as unset). A setting may make the engine compute its own
``maxSeparationDistanceRatio`` (washino's cap: the rupture gap of two of the largest
particles at the cap over twice the smallest radius, a ratio of lengths unchanged by CG);
the scaled scene carries the ratio the engine applies (the model's
``engine_separation_ratio``), so rendering, pre-flight and analysis use the cut the engine
applies.

Particle sizes follow Same Statistic Weight (SSW): every class of the size distribution is
multiplied by n and keeps its number fraction, so the distribution keeps its shape and the
particle count drops by n^3. The time step is a fixed fraction of the Rayleigh time of the
smallest scaled particle, which is n times longer: with n^3 fewer particles a CG-n run is
ideally n^4 cheaper.
"""

from __future__ import annotations

import math
from enum import Enum

from ligwf import liquids
from ligwf.errors import ConfigError
from ligwf.scene.placement import wet_sphere_fields
from ligwf.liquids.contact_angle import applied_contact_angle_rad
from ligwf.scene.model import GRAVITY, Scene
from ligwf.scene.neighbour import turning_skin
from ligwf.scene.scaled import (FillPlan, ScaledDrum, ScaledLiquidValues, ScaledNumerics,
                                ScaledParticles, ScaledScene, rayleigh_time)
from ligwf.scene.seeds import replica_seeds


class Rule(str, Enum):
    """CG scaling rule for the liquid-bridge forces."""

    NONE = "none"
    WEBER = "weber"
    BOND = "bond"


#: Exponent k of n in the inter-particle force factor n^k of each rule.
FORCE_EXPONENT = {Rule.NONE: 1, Rule.WEBER: 2, Rule.BOND: 3}


def parse_rule(value: str | Rule) -> Rule:
    """Rule from its name, with a clear error for unknown names."""
    try:
        return Rule(value)
    except ValueError:
        allowed = ", ".join(r.value for r in Rule)
        raise ConfigError(f"rule = {value!r}: unknown CG scaling rule (allowed: {allowed})") from None


def liquid_factor(cg: float, rule: Rule) -> float:
    """Factor applied to surface tension and viscosity so bridge forces scale as the rule."""
    return cg ** (FORCE_EXPONENT[rule] - 1)


def weber_number(density: float, radius: float, velocity: float, surface_tension: float,
                 contact_angle_deg: float) -> float:
    """We = rho R v^2 / (gamma cos theta)."""
    return density * radius * velocity**2 / (surface_tension * math.cos(math.radians(contact_angle_deg)))


def bond_number(density: float, radius: float, surface_tension: float,
                contact_angle_deg: float, gravity: float = GRAVITY) -> float:
    """Bo = 3 gamma cos theta / (2 R^2 g rho) (capillary over gravity force)."""
    return 3.0 * surface_tension * math.cos(math.radians(contact_angle_deg)) / (
        2.0 * radius**2 * gravity * density)


def drum_free_volume(scene: Scene) -> float:
    """Drum volume available to particles (lifters removed), m^3."""
    drum = scene.drum
    r = drum.radius
    area = math.pi * r**2
    lif = drum.lifters
    if lif.count:
        # annular sector of each lifter bar
        area -= lif.count * math.radians(lif.width_deg) * 0.5 * (r**2 - (r - lif.height) ** 2)
    return area * drum.length


#: the largest solid volume / drum free volume a bed can have (fill 0.7 x packing 0.74)
MAX_SOLID_SHARE = 0.7 * 0.74


def mean_particle_volume(classes: list[tuple[float, float]]) -> float:
    """Number-weighted mean sphere volume of (diameter, number fraction) classes, m^3."""
    return sum(f * math.pi * d**3 / 6.0 for d, f in classes)


def original_particle_count(scene: Scene) -> int:
    """CG1 particle count: given, or fill fraction x packing x drum volume / mean volume."""
    if scene.process.particle_count is not None:
        n = scene.process.particle_count
        free = drum_free_volume(scene)
        share = n * mean_particle_volume(scene.particles.size_classes()) / free
        if share > MAX_SOLID_SHARE:
            raise ConfigError(
                f"scene.process.particle_count = {n}: their solid volume is {share:.3g} x the "
                f"drum's free volume ({free:.3g} m^3); allowed at most {MAX_SOLID_SHARE:.2f} "
                "(fill fraction 0.7 at the densest random packing 0.74)")
        return n
    solid = scene.process.fill_fraction * scene.numerics.packing_fraction * drum_free_volume(scene)
    return max(1, round(solid / mean_particle_volume(scene.particles.size_classes())))


#: Solid fraction one insertion wave may reach in the insertion region. Random sequential
#: insertion jams near 0.38; 0.25 inserts quickly and leaves room to fall.
INSERT_PACKING = 0.2


def insertion_waves(scene: Scene, diameters: tuple[float, ...], fractions: tuple[float, ...],
                    count: int) -> tuple[float, tuple[int, ...]]:
    """Insertion radius (m) and the per-wave insertion capacities.

    Particles are poured into a cylinder inside the lifter tips; a dense fill does not fit
    in one random packing, so it comes in waves, each after the previous one has fallen.
    """
    drum = scene.drum
    d_max = max(diameters)
    h = drum.lifters.height if drum.lifters.count else 0.0
    r_ins = drum.radius - h - 0.55 * d_max
    if r_ins < d_max:
        raise ConfigError(
            f"scene.particles.size_distribution: largest scaled diameter {d_max:g} m does not "
            f"fit inside the drum (radius {drum.radius:g} m, lifters {h:g} m); use a lower CG "
            "level or a larger drum")
    v_mean = sum(f * math.pi * d**3 / 6.0 for d, f in zip(diameters, fractions))
    cap = math.floor(INSERT_PACKING * math.pi * r_ins**2 * drum.length / v_mean)
    if cap < 1:
        raise ConfigError(
            f"scene.drum.length = {drum.length:g} m is too short to hold one particle of "
            f"{d_max:g} m; use a lower CG level or a longer drum")
    # every wave inserts min(cap, still missing); the extra last wave tops up what random
    # insertion could not place earlier (it inserts nothing when the count is reached)
    n_waves = math.ceil(count / cap) + 1
    return r_ins, (cap,) * n_waves


def _steps(duration: float, dt: float) -> int:
    return max(0, math.ceil(duration / dt - 1e-9))


def _every(interval: float, dt: float) -> int:
    return max(1, round(interval / dt))


def scale(scene: Scene, cg: float, rule: Rule | str, replica: int = 0) -> ScaledScene:
    """Apply CG level ``cg`` under ``rule`` to ``scene``; pure.

    At cg == 1 every rule is the identity, so the rule is recorded as ``none``.
    """
    rule = parse_rule(rule)
    if not (isinstance(cg, (int, float)) and math.isfinite(cg) and cg >= 1.0):
        raise ConfigError(f"cg = {cg!r}: CG level must be a number >= 1")
    if cg == 1:
        rule = Rule.NONE
    p, liq, num, drum = scene.particles, scene.liquid, scene.numerics, scene.drum

    classes = p.size_classes()
    diameters = tuple(d * cg for d, _ in classes)
    fractions = tuple(f for _, f in classes)
    n1 = original_particle_count(scene)
    count = max(1, round(n1 / cg**3))

    factor = liquid_factor(cg, rule) if liq.wet else 1.0
    t_r = rayleigh_time(0.5 * min(diameters), p.density, p.youngs_modulus, p.poisson_ratio)
    # the time step comes from the safety fraction unless the scene fixes it
    dt = num.dt if num.dt is not None else num.dt_rayleigh_fraction * t_r
    omega = scene.process.rotation.omega(drum.radius)
    thermo_every = _every(num.thermo_interval, dt)
    r_ins, waves = insertion_waves(scene, diameters, fractions, count)
    fall_time = math.sqrt(2.0 * drum.diameter / GRAVITY)
    settings = liq.settings.applied()    # a default written out: the same case as unset
    max_separation_ratio = liquids.get(liq.model).configured(settings).engine_separation_ratio(
        0.5 * min(diameters), 0.5 * max(diameters),
        applied_contact_angle_rad(liq.contact_angle_deg, num.contact_angle_compensation),
        liq.max_separation_ratio)

    return ScaledScene(
        name=scene.name, cg=float(cg), rule=rule.value, replica=replica,
        drum=ScaledDrum(
            diameter=drum.diameter, length=drum.length, axis=drum.axis,
            periodic=drum.periodic, lifter_count=drum.lifters.count,
            lifter_height=drum.lifters.height, lifter_width_deg=drum.lifters.width_deg,
            omega=omega, fill_fraction=scene.process.fill_fraction,
            wall_friction=drum.wall_friction if drum.wall_friction is not None else p.friction,
            wall_restitution=(drum.wall_restitution if drum.wall_restitution is not None
                              else p.restitution)),
        particles=ScaledParticles(
            diameters=diameters, number_fractions=fractions, count=count, original_count=n1,
            density=p.density, youngs_modulus=p.youngs_modulus, poisson_ratio=p.poisson_ratio,
            restitution=p.restitution, friction=p.friction,
            rolling_friction=p.rolling_friction),
        liquid_values=ScaledLiquidValues(
            model=liq.model,
            surface_tension=liq.surface_tension * factor, viscosity=liq.viscosity * factor,
            contact_angle_deg=liq.contact_angle_deg, liquid_content=liq.liquid_content,
            min_separation_ratio=liq.min_separation_ratio,
            max_separation_ratio=max_separation_ratio,
            contact_angle_compensation=num.contact_angle_compensation,
            **wet_sphere_fields(scene, max(diameters), cg),
            settings=settings),
        numerics=ScaledNumerics(
            dt=dt, dt_rayleigh_fraction=num.dt_rayleigh_fraction if num.dt is None else dt / t_r,
            skin=(num.skin_ratio * min(diameters) if num.skin_ratio is not None
                  else turning_skin(omega, drum.radius, dt, min(diameters))),
            settle_steps=_steps(scene.process.settle_time, dt),
            run_steps=_steps(scene.process.run_time, dt),
            dump_every=_every(num.dump_interval, dt),
            thermo_every=thermo_every,
            restart_every=max(thermo_every, _every(num.restart_interval, dt) // thermo_every
                              * thermo_every)),
        fill=FillPlan(
            radius=r_ins, waves=waves,
            wave_steps=max(thermo_every, _steps(fall_time, dt) // thermo_every * thermo_every),
            seeds=replica_seeds(num.seed, replica, count=len(diameters) + 1 + len(waves))),
        contact_dumps=scene.analysis.contact_dumps,
    )
