"""Scene model: typed, validated, frozen parameters of one drum simulation, in SI units.

A :class:`Scene` describes the *original* (CG1) system: the drum, the particles, the liquid (:mod:`ligwf.scene.liquid`),
the process and the numerics. Coarse graining is a separate, pure stage (``scaling``) that
turns a Scene plus a CG level and a rule into the parameters LIGGGHTS will see.

Every field is checked when the scene is built, so bad input is refused with the field,
the value and the allowed range before any file is written or any engine launched.
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import Field, ValidationError, model_validator

from ligwf import liquids
from ligwf.errors import ConfigError
from ligwf.scene.axis import Axis
from ligwf.scene.liquid import Liquid
from ligwf.scene.messages import format_validation_error
from ligwf.scene.values import MIN_LENGTH, MIN_RESTITUTION, MIN_TIME, Frozen, SafeStr


# ---------------------------------------------------------------------------------------
# Drum
# ---------------------------------------------------------------------------------------

class Lifters(Frozen):
    """Rectangular lifter bars cut radially into the drum shell, evenly spaced."""

    count: int = Field(0, ge=0, le=360, description="number of lifters")
    height: float = Field(0.0, ge=0.0, description="radial height, m (> 0 with lifters; "
                          f"at least {MIN_LENGTH:g} m)")
    width_deg: float = Field(3.0, ge=0.1, lt=180.0, description="angular width, degrees")

    @model_validator(mode="after")
    def _fit_around(self) -> "Lifters":
        if self.count and self.count * self.width_deg >= 360.0:
            most = math.ceil(360.0 / self.width_deg) - 1
            raise ValueError(f"count = {self.count}: {self.count} lifters of width_deg = "
                             f"{self.width_deg:g} span {self.count * self.width_deg:g} deg; "
                             f"they must leave gaps (allowed range [0, {most}] lifters)")
        return self


class Drum(Frozen):
    """The rotating drum: a cylinder shell (with lifters), axis through the origin."""

    diameter: float = Field(ge=1e-3, le=10.0, description="inner shell diameter, m")
    length: float = Field(ge=MIN_LENGTH, le=10.0,
                          description="axial length, m (the periodic length)")
    axis: Axis = Field(Axis.Y, description="rotation axis")
    periodic: bool = Field(True, description="periodic boundary along the axis; "
                           "otherwise the drum has end walls")
    lifters: Lifters = Field(default_factory=Lifters)
    wall_friction: float | None = Field(None, ge=0.0, le=10.0,
                                        description="particle-wall friction (default: particles')")
    wall_restitution: float | None = Field(None, ge=MIN_RESTITUTION, le=1.0,
                                           description="particle-wall restitution "
                                           "(default: particles')")

    @property
    def radius(self) -> float:
        return 0.5 * self.diameter

    @model_validator(mode="after")
    def _lifters_fit(self) -> "Drum":
        if self.lifters.count and self.lifters.height >= self.radius:
            raise ValueError(f"lifters.height = {self.lifters.height:g}: must be < the drum "
                             f"radius {self.radius:g} m (allowed range [{MIN_LENGTH:g}, "
                             f"{self.radius:g}) m)")
        if self.lifters.count and self.lifters.height < MIN_LENGTH:
            raise ValueError(f"lifters.height = {self.lifters.height:g}: with lifters.count "
                             f"= {self.lifters.count} the lifters need a height (allowed range "
                             f"[{MIN_LENGTH:g}, {self.radius:g}) m)")
        return self


# ---------------------------------------------------------------------------------------
# Particles
# ---------------------------------------------------------------------------------------

class SizeClass(Frozen):
    """One class of the size distribution: a diameter, or a diameter range split into bins.

    ``fraction`` is a NUMBER fraction (share of particles), not a mass fraction.
    A range is discretised into ``bins`` classes of equal width, equally populated, which
    approximates a uniform number distribution between the two diameters.
    """

    diameter: float | None = Field(None, ge=MIN_LENGTH, le=1.0, description="diameter, m")
    diameter_range: tuple[float, float] | None = Field(None, description="[min, max] diameter, m")
    bins: int = Field(4, ge=1, le=64, description="classes a range is split into")
    fraction: float = Field(ge=1e-6, le=1.0, description="number fraction (a class below "
                            "1e-6 of the particles is a typo, not a size class)")

    @model_validator(mode="after")
    def _one_of(self) -> "SizeClass":
        if (self.diameter is None) == (self.diameter_range is None):
            raise ValueError("give exactly one of diameter or diameter_range")
        if self.diameter_range is not None:
            lo, hi = self.diameter_range
            if not (MIN_LENGTH <= lo < hi <= 1.0):
                raise ValueError(f"diameter_range = [{lo:g}, {hi:g}]: need {MIN_LENGTH:g} m "
                                 "<= min < max <= 1 m")
        return self

    def discrete(self) -> list[tuple[float, float]]:
        """(diameter, number fraction) pairs this class stands for."""
        if self.diameter is not None:
            return [(self.diameter, self.fraction)]
        lo, hi = self.diameter_range  # type: ignore[misc]
        width = (hi - lo) / self.bins
        return [(lo + (k + 0.5) * width, self.fraction / self.bins) for k in range(self.bins)]


class Particles(Frozen):
    """Material and size distribution of the primary (CG1) particles."""

    density: float = Field(ge=10.0, le=1e5, description="kg/m^3")
    youngs_modulus: float = Field(ge=1e3, le=1e13, description="Pa")
    poisson_ratio: float = Field(0.3, gt=0.0, lt=0.5, description="Poisson's ratio")
    restitution: float = Field(ge=MIN_RESTITUTION, le=1.0, description="coefficient of "
                               "restitution of particle-particle impacts")
    friction: float = Field(ge=0.0, le=10.0, description="sliding friction coefficient")
    rolling_friction: float = Field(0.0, ge=0.0, le=10.0,
                                    description="rolling friction coefficient (model cdt); "
                                    "0 switches rolling friction off")
    size_distribution: tuple[SizeClass, ...] = Field(
        min_length=1, description="size classes of the primary particles (number "
        "fractions summing to 1)")

    @model_validator(mode="after")
    def _fractions_sum(self) -> "Particles":
        total = sum(c.fraction for c in self.size_distribution)
        if not math.isclose(total, 1.0, abs_tol=1e-6):
            raise ValueError(f"size_distribution: the fractions sum to {total:g}; they must "
                             "sum to 1")
        return self

    def size_classes(self) -> list[tuple[float, float]]:
        """All (diameter, number fraction) classes, ranges expanded, largest first."""
        out: list[tuple[float, float]] = []
        for c in self.size_distribution:
            out.extend(c.discrete())
        return sorted(out, key=lambda t: -t[0])


# ---------------------------------------------------------------------------------------
# Process and numerics
# ---------------------------------------------------------------------------------------

GRAVITY = 9.81  # m/s^2, the value written to the LIGGGHTS input


class Rotation(Frozen):
    """Drum speed, as rpm or as Froude number Fr = omega^2 R / g (give exactly one)."""

    rpm: float | None = Field(None, ge=0.01, le=1e4, description="revolutions per minute")
    froude: float | None = Field(None, ge=1e-6, le=100.0, description="Froude number "
                                 "omega^2 R / g (1: the critical, centrifuging speed)")

    @model_validator(mode="after")
    def _one_of(self) -> "Rotation":
        if (self.rpm is None) == (self.froude is None):
            raise ValueError("give exactly one of rpm or froude")
        return self

    def omega(self, drum_radius: float) -> float:
        """Angular speed, rad/s."""
        if self.rpm is not None:
            return self.rpm * 2.0 * math.pi / 60.0
        return math.sqrt(self.froude * GRAVITY / drum_radius)  # type: ignore[operator]


class Process(Frozen):
    """How the drum is filled and turned."""

    rotation: Rotation
    fill_fraction: float = Field(ge=0.01, le=0.7,
                                 description="bed volume (solids + voids) / drum volume")
    particle_count: int | None = Field(None, gt=0, le=10**9,
                                       description="CG1 particle count; overrides the count "
                                       "derived from fill_fraction")
    settle_time: float = Field(0.5, ge=0.0, le=1e3, description="s, drum at rest")
    run_time: float = Field(ge=MIN_TIME, le=1e4, description="s, drum rotating")


class Numerics(Frozen):
    """Integration and output settings."""

    dt_rayleigh_fraction: float = Field(0.15, ge=1e-3, le=2.0,
                                        description="time step / Rayleigh time of the "
                                        "smallest (scaled) particle")
    dt: float | None = Field(None, ge=1e-10, le=1.0,
                             description="fixed time step, s; unset (default): "
                             "dt_rayleigh_fraction x Rayleigh time at every CG level")
    dump_interval: float = Field(0.05, ge=MIN_TIME, le=1e3, description="s between dumps "
                                 "(at most the run time)")
    thermo_interval: float = Field(0.005, ge=MIN_TIME, le=1e3, description="s between thermo "
                                   "lines (at most the run time and the fill's fall time)")
    restart_interval: float = Field(0.25, ge=MIN_TIME, le=1e4,
                                    description="s between periodic restart files")
    packing_fraction: float = Field(0.6, ge=0.1, le=0.74,
                                    description="solid fraction of the settled bed")
    skin_ratio: float | None = Field(
        None, ge=0.01, le=5.0,
        description="neighbour skin / smallest diameter of the settle and production "
        "phases (the fill phase takes at least its free-fall skin); unset (default): from "
        "the drum speed and the time step (ligwf.scene.neighbour)")
    contact_angle_compensation: bool = Field(
        True, description="compensate LIGGGHTS 3.8.0's effective contact angle "
        "0.5*theta_i*theta_j so the engine applies the scene's angle; switch off for "
        "engines with the upstream fix")
    seed: int = Field(10007, ge=10000, le=2**31 - 1,
                      description="base random seed (ligwf derives primes > 10000 from it)")


class Analysis(Frozen):
    """Which analyses the run must prepare output for."""

    contact_dumps: bool = Field(False, description="write contact dumps (the granule "
                                "analysis reads them; the study's analysis: block says how)")

    @model_validator(mode="before")
    @classmethod
    def _renamed_granules(cls, data: Any) -> Any:
        """``granules`` is this switch's old name (scene records written before the rename
        hold it; a workflow that uses it gets a warning, ligwf.scene.renamed)."""
        if isinstance(data, dict) and RENAMED_ANALYSIS_KEY in data:
            if "contact_dumps" in data:
                raise ValueError(f"analysis.{RENAMED_ANALYSIS_KEY} and analysis.contact_dumps "
                                 "are both set: they are one switch (contact_dumps is its "
                                 "name now); keep contact_dumps")
            data = {("contact_dumps" if k == RENAMED_ANALYSIS_KEY else k): v
                    for k, v in data.items()}
        return data


#: the old name of ``analysis.contact_dumps`` (still read, with a warning in workflows)
RENAMED_ANALYSIS_KEY = "granules"


#: most particle (+ contact) dumps and thermo lines one production run may write
MAX_DUMPS = 20_000
MAX_THERMO_LINES = 2_000_000


class Scene(Frozen):
    """One original-size (CG1) drum simulation."""

    name: SafeStr = Field("scene", min_length=1, max_length=80, description="scene name "
                          "(default: the workflow's name)")
    drum: Drum
    particles: Particles
    liquid: Liquid = Field(default_factory=Liquid)
    process: Process
    numerics: Numerics = Field(default_factory=Numerics)
    analysis: Analysis = Field(default_factory=Analysis)

    @model_validator(mode="after")
    def _contact_dumps_need_liquid(self) -> "Scene":
        if self.analysis.contact_dumps and not self.liquid.wet:
            wet = " or ".join(n for n in liquids.names() if liquids.get(n).wet)
            raise ValueError("analysis.contact_dumps = true: needs a liquid model (granules are "
                             f"held by liquid bridges); set liquid.model to {wet}")
        return self

    @model_validator(mode="after")
    def _output_counts(self) -> "Scene":
        """A dump or thermo interval so short that the run writes millions of files/lines
        (1e-12 s: one dump per step) is a typo, not a study."""
        run, num = self.process.run_time, self.numerics
        for name, interval, most in (("dump_interval", num.dump_interval, MAX_DUMPS),
                                     ("thermo_interval", num.thermo_interval, MAX_THERMO_LINES)):
            if run / interval > most:
                raise ValueError(f"numerics.{name} = {interval:g}: {run:g} s of production "
                                 f"would write {run / interval:.3g} outputs; allowed at most "
                                 f"{most:,} (numerics.{name} >= {run / most:.3g} s)")
        return self

    @model_validator(mode="after")
    def _intervals_fit_the_run(self) -> "Scene":
        """A dump interval longer than the production run leaves it without a frame to
        analyse; the fill's insertion waves last whole thermo intervals, so a thermo
        interval longer than the free fall across the drum stretches the fill (30x at 3 s)."""
        run, num = self.process.run_time, self.numerics
        if num.dump_interval > run:
            raise ValueError(f"numerics.dump_interval = {num.dump_interval:g}: longer than "
                             f"process.run_time = {run:g} s, production would write no frame "
                             f"(allowed range [{MIN_TIME:g}, {run:g}] s)")
        fall = math.sqrt(2.0 * self.drum.diameter / GRAVITY)
        most = min(run, fall)
        if num.thermo_interval > most:
            why = []
            if num.thermo_interval > run:
                why.append(f"longer than process.run_time = {run:g} s (no thermo line in "
                           "production)")
            if num.thermo_interval > fall:
                why.append(f"longer than the fall across the drum ({fall:.3g} s): every "
                           "insertion wave of the fill would last a thermo interval")
            raise ValueError(f"numerics.thermo_interval = {num.thermo_interval:g}: "
                             f"{'; '.join(why)} (allowed range [{MIN_TIME:g}, {most:.3g}] s)")
        return self


def build_scene(data: dict[str, Any], prefix: str = "scene") -> Scene:
    """Validate a plain mapping (from YAML) into a :class:`Scene` or raise ConfigError."""
    try:
        return Scene.model_validate(data)
    except ValidationError as exc:
        raise ConfigError("invalid scene:\n" + format_validation_error(exc, Scene, prefix)) from None
