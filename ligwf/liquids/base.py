"""What a liquid model is: the interface every model module implements, and its LIGGGHTS lines.

A liquid model (``washino``, ``easo``, ``none``; see :mod:`ligwf.liquids`) holds everything
about one capillary law in one module: the checks on the scene's liquid block, the lines
it writes into a LIGGGHTS input (the ``cohesion`` keyword of ``pair_style`` and its
``fix property/global`` entries, names checked here because LIGGGHTS silently accepts a
misspelled property), the force law, bridge volume and rupture distance in numpy, the same
in numba for the compiled granule kernels, and the pre-flight quantities (force and
stiffness of a bridge at contact).

A model's own settings (washino's bridge volume fraction and liquid cap) are a frozen
:class:`LiquidSettings` class the model declares (``settings_type``): the scene's
``liquid:`` block validates them per model, and scaling, rendering, the granule analysis
and the foreign-dump reader carry them as one opaque value back to the model
(:meth:`LiquidModel.configured`), never naming them.

This package knows nothing of scenes, engines or analyses: a model reads the few values
it needs through the small protocols below, and the other stages ask the registry.

Conventions: SI units, forces are positive magnitudes of attraction (the engine applies
them as negative normal forces), ``gap`` is the surface separation
``|x_i - x_j| - (r_i + r_j)`` (negative when the spheres overlap), angles in radians
unless the name says ``deg``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
import copy
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, Callable, NamedTuple, Protocol

import numpy as np
from pydantic import BaseModel, ConfigDict

#: largest liquid content (liquid volume / solid volume) and why: see PENDULAR_REASON
MAX_LIQUID_CONTENT = 0.2
PENDULAR_REASON = ("the bridge laws describe separate pendular bridges; at 0.2 of the solid "
                   "volume a bed at packing 0.6 has its pores 30 % full, the end of the "
                   "pendular regime (funicular beyond)")


class Problem(NamedTuple):
    """One refusal of the scene's liquid block: the key (``liquid.<field>``), its value and
    why, with the allowed range when the reason sets one."""

    field: str
    value: Any
    reason: str


class LiquidSettings(BaseModel):
    """A model's own settings, declared as a subclass of this (``LiquidModel.settings_type``;
    this base has none). Each field is a key of the workflow's ``liquid:`` block, validated
    with its bounds, ``description`` and ``json_schema_extra`` (``unit``, ``bound_reason``)
    like any scene field, and documented in the workflow reference. Frozen and hashable:
    :meth:`LiquidModel.configured` may keep one law object per settings value."""

    model_config = ConfigDict(frozen=True, extra="forbid", validate_default=True,
                              allow_inf_nan=False)

    def applied(self) -> "LiquidSettings":
        """These settings as the engine applies them: a value written out at the engine's
        own default reads as unset, so it is the same case (the same record and input)."""
        return self

    def problems(self, liquid: "LiquidBlock") -> list[Problem]:
        """What these settings refuse in the rest of the liquid block (none here)."""
        return []

    def record(self) -> dict[str, Any]:
        """The keys the case's scaled record stores (a setting left unset is left out, so a
        record at the defaults is the record the model had before it had settings)."""
        return {k: v for k, v in self.model_dump(mode="json").items() if v is not None}


class LiquidBlock(Protocol):
    """The scene's liquid block (``ligwf.scene.liquid.Liquid``) as a model validates it."""

    surface_tension: float      # N/m
    contact_angle_deg: float
    viscosity: float            # Pa s
    liquid_content: float       # liquid volume / solid volume
    min_separation_ratio: float
    max_separation_ratio: float
    settings: LiquidSettings    # the model's own (its settings_type)

    @property
    def start_content(self) -> float:
        """The largest liquid content a particle starts with (placed granules included)."""

    @property
    def changed_fields(self) -> frozenset[str]:
        """The keys set to a value other than their default."""


class ScaledLiquid(Protocol):
    """The CG-scaled liquid values a model renders (a scaled scene's ``liquid_values``,
    ``ligwf.scene.scaled.ScaledLiquidValues``)."""

    surface_tension: float      # N/m, CG-scaled
    viscosity: float            # Pa s, CG-scaled
    contact_angle_deg: float    # the scene's angle
    liquid_content: float
    min_separation_ratio: float
    max_separation_ratio: float     # the cut the engine applies (its own when a setting
    #                                 makes it compute one: engine_separation_ratio)


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
    #: the model's own settings (keys of ``liquid:`` only this model has); see
    #: :class:`LiquidSettings`
    settings_type: type[LiquidSettings] = LiquidSettings
    #: what else a scene can set so the engine cuts a bridge at the law's own rupture gap
    #: (the pre-flight adds it to its warning about a short cut); "": nothing
    bridge_cut_remedy: str = ""
    #: True when the engine forms a bridge only once the pair has touched
    bridge_needs_contact: bool = False
    #: per-atom columns the cohesion model creates, dumped with the particles
    dump_columns: tuple[str, ...] = ()
    #: the numba versions of the law (see :class:`Kernels`)
    kernels: Kernels

    def validate(self, liquid: LiquidBlock) -> list[str]:
        """Model-specific problems of the scene's liquid block (one message each, starting
        with ``field = value:``); none here."""
        return []

    #: the settings this law object applies (None: the defaults; see :meth:`configured`)
    _settings: LiquidSettings | None = None

    @property
    def settings(self) -> LiquidSettings:
        """The model's own settings this law object applies (the registered instance: the
        defaults)."""
        return self._settings if self._settings is not None else self.settings_type()

    def configured(self, settings: LiquidSettings | None) -> "LiquidModel":
        """This model's law at ``settings`` as the engine applies them (None or the
        defaults: the registered instance itself, so every default output stays as it was;
        otherwise one law object per settings value, :meth:`with_settings`)."""
        if settings is None:
            return self
        if not isinstance(settings, self.settings_type):
            raise TypeError(f"liquid model {self.name!r}: settings {settings!r} are not its "
                            f"{self.settings_type.__name__}")
        settings = settings.applied()
        return self if settings == self.settings else _configured(self, settings)

    def with_settings(self, settings: LiquidSettings) -> "LiquidModel":
        """A copy of this law applying ``settings`` (its methods read ``self.settings``); a
        model whose compiled kernels depend on a setting builds them here instead."""
        law = copy.copy(self)
        law._settings = settings
        return law

    def engine_separation_ratio(self, r_min: float, r_max: float, theta_rad: float,
                                written: float) -> float:
        """The ``maxSeparationDistanceRatio`` the engine applies for this law: the
        ``written`` one unless a setting makes the engine compute its own (radii in m, the
        applied angle in rad)."""
        return written

    def clip_content(self, content: np.ndarray) -> np.ndarray:
        """Each particle's liquid content as the engine uses it in a pair (a setting may
        clip it); unchanged here."""
        return content

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


@lru_cache(maxsize=None)
def _configured(model: LiquidModel, settings: LiquidSettings) -> LiquidModel:
    """One law object per model and settings (its kernels compile once per process)."""
    return model.with_settings(settings)
