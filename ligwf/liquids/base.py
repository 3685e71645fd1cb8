"""What a liquid model is: the interface every model module implements, and its LIGGGHTS lines.

A liquid model (``washino``, ``easo``, ``none``; see :mod:`ligwf.liquids`) holds everything
about one capillary law in one module: the checks on the scene's liquid block, the lines
it writes into a LIGGGHTS input (the ``cohesion`` keyword of ``pair_style`` and its
``fix property/global`` entries, names checked here because LIGGGHTS silently accepts a
misspelled property), the force law, bridge volume and rupture distance in numpy, the same
in numba for the compiled granule kernels, and the pre-flight quantities (force and
stiffness of a bridge at contact).

This package knows nothing of scenes, engines or analyses: a model reads the few values
it needs through the small protocols below, and the other stages ask the registry.

Conventions: SI units, forces are positive magnitudes of attraction (the engine applies
them as negative normal forces), ``gap`` is the surface separation
``|x_i - x_j| - (r_i + r_j)`` (negative when the spheres overlap), angles in radians
unless the name says ``deg``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np


class LiquidBlock(Protocol):
    """The scene's liquid block (``ligwf.scene.liquid.Liquid``) as a model validates it."""

    surface_tension: float      # N/m
    contact_angle_deg: float
    viscosity: float            # Pa s
    liquid_content: float       # liquid volume / solid volume
    min_separation_ratio: float
    max_separation_ratio: float
    bridge_volume_fraction: float | None    # share of both partners' liquid (None: default)
    max_liquid_content: float | None        # cap of a particle's liquid content (None: none)


class ScaledLiquid(Protocol):
    """The CG-scaled liquid values a model renders (a scaled scene's ``liquid_values``,
    ``ligwf.scene.scaled.ScaledLiquidValues``)."""

    surface_tension: float      # N/m, CG-scaled
    viscosity: float            # Pa s, CG-scaled
    contact_angle_deg: float    # the scene's angle
    liquid_content: float
    min_separation_ratio: float
    max_separation_ratio: float
    bridge_volume_fraction: float | None    # None: the model's default (unchanged by CG)
    max_liquid_content: float | None        # None: no cap (unchanged by CG)


@dataclass(frozen=True)
class InputAngle:
    """The contact angle to write into the input, deg, and a note when the engine needs it
    to differ from the scene's (built by :mod:`ligwf.liquids.contact_angle`)."""

    degrees: float
    note: str = ""


@dataclass(frozen=True)
class Line:
    """One input line as words (strings and numbers; the renderer formats and checks each)."""

    words: tuple[str | float | int, ...]
    comment: bool = False


def command(*words: str | float | int) -> Line:
    return Line(tuple(words))


def comment(*words: str | float | int) -> Line:
    return Line(tuple(words), comment=True)


@dataclass(frozen=True)
class Kernels:
    """The model's law as numba functions for the compiled granule kernels.

    * ``volume(r_i, r_j, liquid_i, liquid_j)``: bridge volume, m^3, from each partner's
      radius (m) and liquid volume (m^3);
    * ``within_rupture(gap, volume, theta)``: True while the bridge holds;
    * ``force(r_i, r_j, gap, gamma, theta, cos_theta, sin_theta, volume)``: force of a
      pair within rupture, N (cos and sin of theta precomputed once per frame).
    """

    volume: Callable
    within_rupture: Callable
    force: Callable


def sphere_volume(r):
    """4/3 pi r^3, m^3, with r^3 as r*r*r: twice as fast as numpy's pow, and the compiled
    granule kernels evaluate the same expression, so bridge volumes agree to the last bit."""
    r = np.asarray(r, dtype=float)
    return 4.0 / 3.0 * np.pi * (r * r * r)


class LiquidModel(ABC):
    """One liquid model: register an instance with :func:`ligwf.liquids.register`."""

    #: the name a scene gives in ``liquid.model``
    name: str
    #: False for the dry bed: no cohesion, no bridges, no liquid scaling
    wet: bool = True
    #: LIGGGHTS ``pair_style gran ... cohesion <keyword>`` (None: no cohesion model)
    cohesion: str | None = None
    #: every ``fix property/global`` name the cohesion model reads (all must be written)
    properties: tuple[str, ...] = ()
    #: properties the cohesion model reads only when one of its switches is on (each
    #: written at most once, together with its switch: :meth:`cohesion_settings`)
    optional_properties: tuple[str, ...] = ()
    #: the share of both partners' surface liquid a bridge takes when the scene leaves
    #: ``liquid.bridge_volume_fraction`` unset; None: the model has no such share (its
    #: bridge volume is computed otherwise, e.g. easo's caps), so the setting is refused
    default_bridge_volume_fraction: float | None = None
    #: True when the engine model can cap each particle's liquid content
    #: (``liquid.max_liquid_content``); False: the setting is refused
    limits_liquid_content: bool = False
    #: True when the engine forms a bridge only once the pair has touched
    bridge_needs_contact: bool = False
    #: per-atom columns the cohesion model creates, dumped with the particles
    dump_columns: tuple[str, ...] = ()
    #: the numba versions of the law (see :class:`Kernels`)
    kernels: Kernels

    def validate(self, liquid: LiquidBlock) -> list[str]:
        """Model-specific problems of the scene's liquid block (one message each): here,
        settings the model does not have."""
        problems = []
        fraction = getattr(liquid, "bridge_volume_fraction", None)
        if fraction is not None and self.default_bridge_volume_fraction is None:
            problems.append(f"bridge_volume_fraction = {fraction:g}: liquid model "
                            f"{self.name!r} has no bridge volume fraction (only "
                            "washino's bridge takes a share of both partners' liquid); "
                            "leave it unset")
        cap = getattr(liquid, "max_liquid_content", None)
        if cap is not None and not self.limits_liquid_content:
            problems.append(f"max_liquid_content = {cap:g}: liquid model {self.name!r} "
                            "cannot cap the liquid content (only washino can); leave it unset")
        return problems

    def configured(self, bridge_volume_fraction: float | None) -> "LiquidModel":
        """This model applying ``bridge_volume_fraction`` (None or the model's default: the
        registered instance itself, so every default output stays as it was)."""
        if bridge_volume_fraction is None or (
                bridge_volume_fraction == self.default_bridge_volume_fraction):
            return self
        raise ValueError(f"liquid model {self.name!r} has no bridge volume fraction "
                         f"(bridge_volume_fraction = {bridge_volume_fraction:g})")

    def capped_separation_ratio(self, r_min: float, r_max: float, max_liquid_content: float,
                                theta_rad: float) -> float:
        """The ``maxSeparationDistanceRatio`` the engine applies when it caps the liquid
        content at ``max_liquid_content`` (radii in m, the applied angle in rad)."""
        raise ValueError(f"liquid model {self.name!r} cannot cap the liquid content")

    def cohesion_settings(self, s: ScaledLiquid) -> tuple[str, ...]:
        """Words the ``pair_style gran`` line appends after all its models (the cohesion
        model's on/off switches); () at every default."""
        return ()

    def liggghts_lines(self, s: ScaledLiquid, angle: InputAngle) -> tuple[Line, ...]:
        """The liquid's lines of the input (before ``pair_style``), property names checked."""
        return ()

    def property_line(self, fix_id: str, name: str, style: str, *values: float) -> Line:
        """``fix <id> all property/global <name> <style> <values>``, refusing a name the
        cohesion model does not read (LIGGGHTS would accept it silently)."""
        if name not in self.properties + self.optional_properties:
            raise ValueError(f"liquid model {self.name!r}: LIGGGHTS property {name!r} is not "
                             f"one the {self.cohesion} cohesion model reads "
                             f"({', '.join(self.properties + self.optional_properties)})")
        return command("fix", fix_id, "all", "property/global", name, style, *values)

    def checked_lines(self, lines: tuple[Line, ...]) -> tuple[Line, ...]:
        """``lines`` if they set every property the cohesion model reads exactly once and
        each optional one at most once (a missing one is an engine error at run time, a
        repeated one overrides silently)."""
        written = [ln.words[4] for ln in lines if ln.words[:1] == ("fix",)
                   and len(ln.words) > 4 and ln.words[3] == "property/global"]
        optional = [w for w in written if w in self.optional_properties]
        required = [w for w in written if w not in self.optional_properties]
        if sorted(required) != sorted(self.properties) or len(set(optional)) != len(optional):
            raise ValueError(f"liquid model {self.name!r} writes properties {written}; the "
                             f"{self.cohesion} cohesion model needs each of "
                             f"{list(self.properties)} once")
        return lines

    @abstractmethod
    def bridge_volume(self, r_i, r_j, content_i, content_j):
        """Bridge volume, m^3, from radii (m) and liquid contents (fraction of volume)."""

    @abstractmethod
    def rupture_distance(self, bridge_volume, theta_rad):
        """Gap at which a bridge breaks, m."""

    @abstractmethod
    def capillary_force(self, r_i, r_j, gap, surface_tension, theta_rad, content_i,
                        content_j=None):
        """Force magnitude, N (0 beyond rupture); arrays or scalars (then a float)."""

    @abstractmethod
    def contact_force_and_stiffness(self, radius: float, surface_tension: float,
                                    theta_rad: float, content: float) -> tuple[float, float]:
        """(F_0 in N, k_b = |dF/d gap| in N/m) of a bridge between two equal spheres at
        contact: the pre-flight's capillary time and static overlap come from these."""

    def force_positive(self, surface_tension: float, theta_rad: float, r_min: float,
                       r_max: float, content_min: float, content_max: float) -> bool:
        """True when the law is provably > 0 N for every pair of radii in [r_min, r_max] and
        contents in [content_min, content_max] within rupture (the compiled granule path
        then skips evaluating it when no force threshold is set). False: no proof."""
        return False

    def engine_cutoff_gaps(self, radius: float,
                           max_separation_ratio: float) -> tuple[float, float] | None:
        """(gap at which the engine cuts the bridge force, largest gap of a pair in the
        neighbour lists), m, for two spheres of ``radius``; None when not known."""
        return None
