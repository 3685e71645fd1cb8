"""The scaled scene: what one LIGGGHTS run gets, after CG scaling (:mod:`ligwf.scene.scaling`).

:class:`ScaledScene` groups its values by what they are: the ``drum`` as it turns, the
scaled ``particles``, the scaled liquid (``liquid_values``), the ``numerics`` (time step,
phase lengths, output intervals) and the ``fill`` (insertion waves and seeds). Values that
follow from stored ones by a formula (the rotation period, rpm and Froude number of the
drum, the Rayleigh time of the smallest particle) are properties, never stored.

On disk (the ``scaled`` block of a case folder's scene record, and the case's content hash) the
record is the flat mapping it has always been: :data:`FLAT_KEYS` names each key's place in
the groups; :meth:`ScaledScene.to_dict` writes the derived values too (older readers and
the hash expect them) and :meth:`ScaledScene.from_dict` checks them against its own
computation, refusing a record whose derived values do not follow from its stored ones
(an edited or damaged record) rather than silently using either.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from ligwf import liquids
from ligwf.liquids.base import LiquidModel, LiquidSettings
from ligwf.scene.axis import Axis
from ligwf.scene.model import GRAVITY
from ligwf.scene.neighbour import fill_skin


def shear_modulus(youngs_modulus: float, poisson_ratio: float) -> float:
    """G = E / (2 (1 + nu)), Pa."""
    return youngs_modulus / (2.0 * (1.0 + poisson_ratio))


def rayleigh_time(radius: float, density: float, youngs_modulus: float,
                  poisson_ratio: float) -> float:
    """Rayleigh wave time of a sphere, s.

    t_R = pi R sqrt(rho / G) / (0.1631 nu + 0.8766) -- the formula LIGGGHTS' own
    ``fix check/timestep/gran`` uses, so ligwf's time step fraction and the engine's
    ``f_ts[1]`` report agree.
    """
    g = shear_modulus(youngs_modulus, poisson_ratio)
    return math.pi * radius * math.sqrt(density / g) / (0.1631 * poisson_ratio + 0.8766)


@dataclass(frozen=True)
class ScaledDrum:
    """The drum as it turns (unchanged by CG): geometry, walls, speed and fill."""

    diameter: float              # m, inner shell
    length: float                # m, along the axis (the periodic length)
    axis: Axis                   # rotation axis through the origin
    periodic: bool               # periodic boundary along the axis (else closed ends)
    lifter_count: int
    lifter_height: float         # m
    lifter_width_deg: float
    omega: float                 # rad/s, signed (right-handed about +axis)
    fill_fraction: float         # bed volume / drum volume
    wall_friction: float
    wall_restitution: float

    @property
    def radius(self) -> float:
        """Inner shell radius, m."""
        return 0.5 * self.diameter

    @property
    def periodic_axis(self) -> Axis | None:
        """The axis when the drum is a periodic slice; None for a closed drum."""
        return self.axis if self.periodic else None

    @property
    def rotation_period(self) -> float:
        """Time of one revolution, s."""
        return 2.0 * math.pi / self.omega

    @property
    def rpm(self) -> float:
        """Revolutions per minute."""
        return self.omega * 60.0 / (2.0 * math.pi)

    @property
    def froude(self) -> float:
        """Froude number omega^2 R / g (centrifugal over gravity at the shell)."""
        return self.omega**2 * self.radius / GRAVITY


@dataclass(frozen=True)
class ScaledParticles:
    """The particles after CG: SSW size classes, count and materials (SI)."""

    diameters: tuple[float, ...]            # m, largest first
    number_fractions: tuple[float, ...]
    count: int                              # particles of this CG level
    original_count: int                     # particles at CG1
    density: float                          # kg/m^3
    youngs_modulus: float                   # Pa
    poisson_ratio: float
    restitution: float
    friction: float
    rolling_friction: float

    @property
    def d_min(self) -> float:
        return min(self.diameters)

    @property
    def d_max(self) -> float:
        return max(self.diameters)

    @property
    def rayleigh_time(self) -> float:
        """Rayleigh time of the smallest particle, s (the time step's scale)."""
        return rayleigh_time(0.5 * self.d_min, self.density, self.youngs_modulus,
                             self.poisson_ratio)


@dataclass(frozen=True)
class ScaledLiquidValues:
    """The liquid after CG (the values :class:`ligwf.liquids.base.ScaledLiquid` names):
    surface tension and viscosity scaled by the rule, the rest as the scene gives it."""

    model: str                               # a name in ligwf.liquids' registry
    surface_tension: float                   # N/m, CG-scaled
    viscosity: float                         # Pa s, CG-scaled
    contact_angle_deg: float                 # the scene's angle
    liquid_content: float                    # liquid volume / solid volume
    min_separation_ratio: float
    max_separation_ratio: float              # the cut the engine applies (a setting may
    #                                          make it its own: engine_separation_ratio)
    contact_angle_compensation: bool         # 3.8.0's 0.5 theta_i theta_j compensated
    # placed liquid (liquid.placement: granules, ligwf.scene.placement): (axial, across,
    # vertical, radius) per wet sphere, m, and their liquid content; empty for a
    # uniformly wetted bed
    wet_spheres: tuple[tuple[float, float, float, float], ...] = ()
    wet_sphere_content: float = 0.0
    # the model's own settings as the engine applies them (its settings_type; unchanged by
    # CG): opaque here, read by the model's law (ScaledScene.liquid)
    settings: LiquidSettings = dataclasses.field(default_factory=LiquidSettings)


@dataclass(frozen=True)
class ScaledNumerics:
    """Time step, neighbour skin, phase lengths and output intervals (in steps)."""

    dt: float                    # s
    dt_rayleigh_fraction: float  # dt / Rayleigh time (the setting, or what a fixed dt gives)
    skin: float                  # m, neighbour skin of the settle and production phases
    settle_steps: int            # drum at rest after the fill
    run_steps: int               # production (drum turning)
    dump_every: int
    thermo_every: int
    restart_every: int


@dataclass(frozen=True)
class FillPlan:
    """How the drum is filled: insertion waves into a cylinder inside the lifter tips."""

    radius: float                # m, of the insertion cylinder
    waves: tuple[int, ...]       # capacity of each insertion wave
    wave_steps: int              # steps between waves (time to fall across the drum)
    seeds: tuple[int, ...]       # per particle template, then the distribution, then per wave


@dataclass(frozen=True)
class ScaledScene:
    """What one LIGGGHTS run gets: the scene after CG scaling, in SI units.

    Everything a template needs is here, so rendering never recomputes physics.
    """

    name: str
    cg: float
    rule: str
    replica: int
    drum: ScaledDrum
    particles: ScaledParticles
    liquid_values: ScaledLiquidValues
    numerics: ScaledNumerics
    fill: FillPlan
    contact_dumps: bool          # write contact dumps (granule analysis reads them)

    @property
    def wet(self) -> bool:
        return self.liquid.wet

    @property
    def liquid(self) -> LiquidModel:
        """The liquid model of this case (from :mod:`ligwf.liquids`' registry), applying
        the case's settings of that model."""
        return liquids.get(self.liquid_values.model).configured(self.liquid_values.settings)

    @property
    def insertion_steps(self) -> int:
        """Steps of the filling phase (all insertion waves), before ``settle_steps``."""
        return len(self.fill.waves) * self.fill.wave_steps

    @property
    def total_steps(self) -> int:
        """Insertion + settling (drum at rest) + production (drum turning)."""
        return self.insertion_steps + self.numerics.settle_steps + self.numerics.run_steps

    @property
    def skin_fill(self) -> float:
        """Neighbour skin of the fill phase (m): the falling particles' skin, never thinner
        than ``numerics.skin`` (that of the settle and production phases)."""
        return max(self.numerics.skin,
                   fill_skin(self.drum.diameter, self.numerics.dt, self.d_min))

    @property
    def d_min(self) -> float:
        return self.particles.d_min

    @property
    def d_max(self) -> float:
        return self.particles.d_max

    def with_run_steps(self, run_steps: int) -> "ScaledScene":
        """This scene with another production length (a study's extension)."""
        return dataclasses.replace(
            self, numerics=dataclasses.replace(self.numerics, run_steps=run_steps))

    @classmethod
    def from_dict(cls, data: dict) -> "ScaledScene":
        """From :meth:`to_dict` (a case folder's stored scaled scene): lists back to tuples;
        a missing or unknown key is a TypeError, never a default; a derived value that does
        not follow from the stored ones is a ValueError naming it."""
        settings_type = (liquids.get(data["liquid_model"]).settings_type
                         if data.get("liquid_model") in liquids.names() else LiquidSettings)
        own = {k: data[k] for k in data if k in settings_type.model_fields}
        unknown = sorted(set(data) - set(FLAT_KEYS) - set(DERIVED_KEYS) - set(own))
        if unknown:
            raise TypeError(f"scaled scene record: unknown key(s) {', '.join(unknown)}")
        groups: dict[str, dict[str, Any]] = {g: {} for g in GROUPS}
        top: dict[str, Any] = {}
        for key, (group, field) in FLAT_KEYS.items():
            if key not in data:
                if key in OPTIONAL_KEYS:
                    continue
                raise TypeError(f"scaled scene record: missing key {key!r}")
            value = data[key]
            value = tuple(value) if isinstance(value, list) else value
            (groups[group] if group else top)[field] = value
        liquid = groups["liquid_values"]
        if "wet_spheres" in liquid:
            liquid["wet_spheres"] = tuple(tuple(w) for w in liquid["wet_spheres"])
        liquid["settings"] = settings_type.model_validate(own)
        groups["drum"]["axis"] = Axis(groups["drum"]["axis"])
        scaled = cls(**top, **{g: GROUPS[g](**values) for g, values in groups.items()})
        for key in DERIVED_KEYS:
            expected = DERIVED_KEYS[key](scaled)
            if key not in data:
                raise TypeError(f"scaled scene record: missing key {key!r}")
            if data[key] != expected:
                raise ValueError(f"scaled scene record: {key} = {data[key]!r} does not follow "
                                 f"from the stored values (they give {expected!r}): edited?")
        return scaled

    def to_dict(self) -> dict:
        """The flat record (:data:`FLAT_KEYS` plus the derived :data:`DERIVED_KEYS`), in
        the key order and with the omissions it has always had: a case's content hash
        covers it byte for byte."""
        out: dict[str, Any] = {}
        for key, (group, field) in FLAT_KEYS.items():
            value = getattr(getattr(self, group) if group else self, field)
            out[key] = list(value) if key in LIST_KEYS else value
            if key in DERIVED_AFTER:
                for derived in DERIVED_AFTER[key]:
                    out[derived] = DERIVED_KEYS[derived](self)
        out["axis"] = self.drum.axis.value
        if not self.liquid_values.wet_spheres:   # records of uniform beds stay as they were
            del out["wet_spheres"], out["wet_sphere_content"]
        # the model's own settings last, each left out when unset (as records at the
        # model's defaults always were)
        out.update(self.liquid_values.settings.record())
        return out


#: the sub-records of :class:`ScaledScene` by attribute
GROUPS = {"drum": ScaledDrum, "particles": ScaledParticles,
          "liquid_values": ScaledLiquidValues, "numerics": ScaledNumerics, "fill": FillPlan}

#: flat record key -> (sub-record, field) of a stored value ("" for the scene itself), in
#: the record's historical key order
FLAT_KEYS: dict[str, tuple[str, str]] = {
    "name": ("", "name"), "cg": ("", "cg"), "rule": ("", "rule"), "replica": ("", "replica"),
    "drum_diameter": ("drum", "diameter"), "drum_length": ("drum", "length"),
    "axis": ("drum", "axis"), "periodic": ("drum", "periodic"),
    "lifter_count": ("drum", "lifter_count"), "lifter_height": ("drum", "lifter_height"),
    "lifter_width_deg": ("drum", "lifter_width_deg"), "omega": ("drum", "omega"),
    "fill_fraction": ("drum", "fill_fraction"),
    "diameters": ("particles", "diameters"),
    "number_fractions": ("particles", "number_fractions"),
    "particle_count": ("particles", "count"),
    "original_particle_count": ("particles", "original_count"),
    "density": ("particles", "density"), "youngs_modulus": ("particles", "youngs_modulus"),
    "poisson_ratio": ("particles", "poisson_ratio"),
    "restitution": ("particles", "restitution"), "friction": ("particles", "friction"),
    "rolling_friction": ("particles", "rolling_friction"),
    "wall_friction": ("drum", "wall_friction"), "wall_restitution": ("drum", "wall_restitution"),
    "liquid_model": ("liquid_values", "model"),
    "surface_tension": ("liquid_values", "surface_tension"),
    "viscosity": ("liquid_values", "viscosity"),
    "contact_angle_deg": ("liquid_values", "contact_angle_deg"),
    "liquid_content": ("liquid_values", "liquid_content"),
    "min_separation_ratio": ("liquid_values", "min_separation_ratio"),
    "max_separation_ratio": ("liquid_values", "max_separation_ratio"),
    "contact_angle_compensation": ("liquid_values", "contact_angle_compensation"),
    "dt": ("numerics", "dt"), "dt_rayleigh_fraction": ("numerics", "dt_rayleigh_fraction"),
    "settle_steps": ("numerics", "settle_steps"), "run_steps": ("numerics", "run_steps"),
    "dump_every": ("numerics", "dump_every"), "thermo_every": ("numerics", "thermo_every"),
    "restart_every": ("numerics", "restart_every"), "skin": ("numerics", "skin"),
    "insertion_radius": ("fill", "radius"), "insertion_waves": ("fill", "waves"),
    "wave_steps": ("fill", "wave_steps"), "seeds": ("fill", "seeds"),
    "granules": ("", "contact_dumps"),
    "wet_spheres": ("liquid_values", "wet_spheres"),
    "wet_sphere_content": ("liquid_values", "wet_sphere_content"),
}

#: keys stored as JSON lists (wet_spheres stays a tuple of tuples, as it always was)
LIST_KEYS = ("diameters", "number_fractions", "seeds", "insertion_waves")

#: keys a record leaves out at their defaults (a uniform bed; the liquid model's own
#: settings, stored after these, are left out when unset: ``LiquidSettings.record``)
OPTIONAL_KEYS = ("wet_spheres", "wet_sphere_content")

#: derived values the flat record carries (written by to_dict, checked by from_dict)
DERIVED_KEYS = {
    "rotation_period": lambda s: s.drum.rotation_period,
    "rpm": lambda s: s.drum.rpm,
    "froude": lambda s: s.drum.froude,
    "rayleigh_time": lambda s: s.particles.rayleigh_time,
}

#: the sub-record whose property each derived key is
DERIVED_PLACES = {"rotation_period": "drum", "rpm": "drum", "froude": "drum",
                  "rayleigh_time": "particles"}


def nested_name(flat_key: str) -> str | None:
    """Where a flat record key lives on the nested scene (``"dt"`` -> ``"numerics.dt"``,
    ``"rpm"`` -> ``"drum.rpm"``); None for a name the record never had."""
    if flat_key in DERIVED_PLACES:
        return f"{DERIVED_PLACES[flat_key]}.{flat_key}"
    if flat_key not in FLAT_KEYS:
        return None
    return ".".join(part for part in FLAT_KEYS[flat_key] if part)


#: where the derived keys sat in the record's historical key order (after which stored key)
DERIVED_AFTER = {"omega": ("rotation_period", "rpm", "froude"),
                 "contact_angle_compensation": ("rayleigh_time",)}
