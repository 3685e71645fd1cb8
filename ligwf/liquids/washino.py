"""The washino capillary model (``cohesion washino/capillary/viscous`` of LIGGGHTS 3.8.0).

Mirrors ``cohesion_model_washino_capillary_viscous.h``: the bridge takes a fixed share of
both particles' surface liquid, and the force follows Rabinovich et al., Langmuir 21
(2005) as coded in LIGGGHTS (see :meth:`Washino.capillary_force`). Verified against the
engine's pair force to 1e-9 (``tests/engine/test_engine_bridge.py``).

Two switches of the engine model (3.8.0 source lines 89-92, 128-129, 153-163, 206-222,
254-260; docs/liquid_bridges.md) are washino's own settings (:class:`WashinoSettings`, keys
of the scene's ``liquid:`` block only washino has):

* ``liquid.bridge_volume_fraction`` (the engine's ``lbVolumeFraction``, read only with the
  pair_style keyword ``modifyLbVolume on``; default 0.05): the share of both particles'
  liquid a bridge takes. ``configured`` gives the law at another share, its numba volume
  kernel compiled with that share (:func:`volume_kernel`).
* ``liquid.max_liquid_content`` (``maxLiquidContent``, per atom type, read only with
  ``limitLiquidContent on``): the engine clips a particle's content to it whenever one of
  its pairs is evaluated, and REPLACES ``maxSeparationDistanceRatio`` by the ratio at
  which two of the largest particles holding the cap break their bridge
  (:func:`engine_max_separation_ratio`).
"""

from __future__ import annotations

import math

import numpy as np

from functools import lru_cache

from pydantic import Field

from ligwf.liquids.base import (MAX_LIQUID_CONTENT, PENDULAR_REASON, InputAngle, Kernels,
                                Line, LiquidBlock, LiquidSettings, Problem, ScaledLiquid,
                                sphere_volume)
from ligwf.liquids.capillary import CapillaryModel, within_rupture
from ligwf.numba_cache import cached_jit, specialised

#: LIGGGHTS' default fraction of the two particles' liquid that forms a washino bridge
#: (``lbVolumeFraction``, used unless ``modifyLbVolume`` is switched on).
BRIDGE_VOLUME_FRACTION = 0.05


class WashinoSettings(LiquidSettings):
    """washino's own settings: two switches of the engine model, None at its defaults.
    Both are fractions and stay as they are under CG scaling."""

    bridge_volume_fraction: float | None = Field(
        None, gt=0.0, le=1.0, description="washino only: share of both particles' surface "
        "liquid that forms a bridge (LIGGGHTS lbVolumeFraction, written with modifyLbVolume "
        "on); unset: the engine default 0.05. A fraction: unchanged by CG scaling",
        json_schema_extra={"unit": "1"})
    max_liquid_content: float | None = Field(
        None, gt=0.0, le=MAX_LIQUID_CONTENT, description="washino only: cap of each "
        "particle's liquid content, liquid volume / solid volume (LIGGGHTS maxLiquidContent, "
        "written with limitLiquidContent on; the engine deletes liquid above it and sets "
        "maxSeparationDistanceRatio itself, so max_separation_ratio must stay unset); unset: "
        "no cap. Unchanged by CG scaling",
        json_schema_extra={"bound_reason": PENDULAR_REASON, "unit": "1"})

    def applied(self) -> "WashinoSettings":
        if self.bridge_volume_fraction == BRIDGE_VOLUME_FRACTION:   # the default written out
            return self.model_copy(update={"bridge_volume_fraction": None})
        return self

    @property
    def fraction(self) -> float:
        """The bridge volume fraction the engine applies."""
        return (BRIDGE_VOLUME_FRACTION if self.bridge_volume_fraction is None
                else self.bridge_volume_fraction)

    def problems(self, liquid: LiquidBlock) -> list[Problem]:
        """A cap below the liquid a particle starts with deletes liquid at its first
        contact; and the engine replaces maxSeparationDistanceRatio when capping."""
        cap = self.max_liquid_content
        if cap is None:
            return []
        start = liquid.start_content
        if cap < start:
            return [Problem("max_liquid_content", cap, (
                f"below the liquid content the particles start with ({start:g}), the engine "
                f"would delete the rest at their first contact (allowed range [{start:g}, "
                f"{MAX_LIQUID_CONTENT:g}])"))]
        if "max_separation_ratio" in liquid.changed_fields:
            return [Problem("max_separation_ratio", liquid.max_separation_ratio, (
                f"with max_liquid_content = {cap:g} the engine sets "
                "maxSeparationDistanceRatio itself (the rupture gap at the cap); leave "
                "max_separation_ratio unset"))]
        return []


def bridge_volume(r_i, r_j, content_i, content_j, fraction: float = BRIDGE_VOLUME_FRACTION):
    """Bridge volume, m^3: ``fraction`` of both particles' surface liquid."""
    return fraction * (sphere_volume(r_i) * content_i + sphere_volume(r_j) * content_j)


@cached_jit(inline="always", error_model="numpy")
def _volume(ri, rj, lvi, lvj):
    """:func:`bridge_volume` from each partner's liquid volume (m^3), m^3."""
    return BRIDGE_VOLUME_FRACTION * (lvi + lvj)


@lru_cache(maxsize=None)
def volume_kernel(fraction: float):
    """The numba volume kernel of a bridge taking ``fraction`` of both partners' liquid:
    ``_volume`` itself at the default share, else a copy with the module constant bound
    to ``fraction`` (:func:`ligwf.numba_cache.specialised`). Its name carries the share, so
    the granule kernels it is inlined into are cached under a name of their own."""
    if fraction == BRIDGE_VOLUME_FRACTION:
        return _volume
    tag = "f" + float(fraction).hex().replace(".", "_").replace("+", "p").replace("-", "m")
    return specialised(_volume.py_func, tag, {"inline": "always", "error_model": "numpy"},
                       BRIDGE_VOLUME_FRACTION=float(fraction))


def engine_max_separation_ratio(r_min: float, r_max: float, max_liquid_content: float,
                                theta_rad: float,
                                fraction: float = BRIDGE_VOLUME_FRACTION) -> float:
    """The ``maxSeparationDistanceRatio`` the engine sets when ``limitLiquidContent`` is on
    (3.8.0 source lines 206-222): 1 + d / (2 r_min), with d = (1 + theta/2) V^(1/3) the
    rupture gap of a bridge between two particles of the largest radius ``r_max`` (m)
    holding ``max_liquid_content``; ``r_min`` (m) the smallest radius. ``theta_rad``: the
    angle the engine applies (3.8.0 computes it as 0.5 theta_in^2 here too, as in its force
    law: :func:`ligwf.liquids.contact_angle.applied_contact_angle_rad`). Scale-free: the
    same at every CG level."""
    vol = fraction * 2.0 * float(sphere_volume(r_max)) * max_liquid_content
    return 1.0 + 0.5 * (1.0 + 0.5 * theta_rad) * float(np.cbrt(vol)) / r_min


@cached_jit(inline="always", error_model="numpy")
def _force(ri, rj, gap, gamma, theta, cos_theta, sin_theta, vol):
    """:meth:`Washino.capillary_force` for one pair within rupture, N."""
    r_eff = ri * rj / (ri + rj)
    if gap <= 0.0:
        return 2 * np.pi * r_eff * gamma * cos_theta * (
            1.0 - gap * math.sqrt(np.pi * r_eff / (2.0 * vol)))
    p = -1.0 + math.sqrt(1.0 + 2.0 * vol / (np.pi * r_eff * gap**2))
    d_sp = 0.5 * gap * p
    alpha = math.sqrt(gap / r_eff * p)
    sin_alpha = math.sin(alpha)
    # sin(alpha + theta) by the addition theorem: one sine call instead of two (the same
    # value to rounding, ~1e-16 relative); cos(alpha) >= 0 while alpha <= pi/2
    cos_alpha = math.sqrt(1.0 - sin_alpha * sin_alpha) if alpha <= 0.5 * np.pi else math.cos(alpha)
    return 2 * np.pi * r_eff * gamma * (
        cos_theta / (1.0 + gap / (2.0 * d_sp))
        + sin_alpha * (sin_alpha * cos_theta + cos_alpha * sin_theta))


class Washino(CapillaryModel):
    """The law at one set of :class:`WashinoSettings` (the registered instance: the
    defaults; others from ``configured``)."""

    name = "washino"
    cohesion = "washino/capillary/viscous"
    optional_properties = ("lbVolumeFraction", "maxLiquidContent")
    settings_type = WashinoSettings
    bridge_cut_remedy = ("set max_liquid_content (the engine then cuts at the law's own "
                         "rupture gap of two particles holding that content)")

    def __init__(self, settings: WashinoSettings | None = None) -> None:
        self._settings = settings
        self.kernels = Kernels(volume=volume_kernel(self.bridge_volume_fraction),
                               within_rupture=within_rupture, force=_force)

    @property
    def bridge_volume_fraction(self) -> float:
        """The share of both partners' liquid this law's bridge takes."""
        return self.settings.fraction

    def with_settings(self, settings: WashinoSettings) -> "Washino":
        return Washino(settings)

    def engine_separation_ratio(self, r_min: float, r_max: float, theta_rad: float,
                                written: float) -> float:
        cap = self.settings.max_liquid_content
        if cap is None:
            return written
        return engine_max_separation_ratio(r_min, r_max, cap, theta_rad,
                                           self.bridge_volume_fraction)

    def clip_content(self, content: np.ndarray) -> np.ndarray:
        # the engine clips a content above the cap before every pair it evaluates
        cap = self.settings.max_liquid_content
        return content if cap is None else np.minimum(content, cap)

    def cohesion_settings(self, s: ScaledLiquid) -> tuple[str, ...]:
        words: tuple[str, ...] = ()
        if self.settings.bridge_volume_fraction is not None:
            words += ("modifyLbVolume", "on")
        if self.settings.max_liquid_content is not None:
            words += ("limitLiquidContent", "on")
        return words

    def liggghts_lines(self, s: ScaledLiquid, angle: InputAngle) -> tuple[Line, ...]:
        lines = super().liggghts_lines(s, angle)
        own = self.settings
        if own.bridge_volume_fraction is not None:
            lines += (self.property_line("lq_lbvol", "lbVolumeFraction", "scalar",
                                         own.bridge_volume_fraction),)
        if own.max_liquid_content is not None:
            # per atom type (particles, wall); the wall's never binds (walls hold no liquid)
            lines += (self.property_line("lq_maxlc", "maxLiquidContent", "peratomtype",
                                         own.max_liquid_content, own.max_liquid_content),)
        return self.checked_lines(lines)

    def bridge_volume(self, r_i, r_j, content_i, content_j):
        return bridge_volume(r_i, r_j, content_i, content_j, self.bridge_volume_fraction)

    def capillary_force(self, r_i, r_j, gap, surface_tension, theta_rad, content_i,
                        content_j=None):
        """Capillary force magnitude, N (0 beyond rupture).

        Touching (gap <= 0): F = 2 pi R* gamma cos(theta) (1 - gap sqrt(pi R* / (2 V)))
        (Rabinovich et al., Langmuir 21 (2005), eq. A11, as coded in LIGGGHTS).
        Separated (0 < gap < rupture): with p = -1 + sqrt(1 + 2 V / (pi R* gap^2)),
        d_sp = gap p / 2, alpha = sqrt(gap p / R*):
        F = 2 pi R* gamma (cos(theta) / (1 + gap / (2 d_sp)) + sin(alpha) sin(alpha + theta))
        (Rabinovich et al. eqs. 19, 20, A3). R* = r_i r_j / (r_i + r_j).
        """
        content_j = content_i if content_j is None else content_j
        r_i, r_j, gap = (np.asarray(a, float) for a in (r_i, r_j, gap))
        r_eff = r_i * r_j / (r_i + r_j)
        vol = self.bridge_volume(r_i, r_j, content_i, content_j)
        with np.errstate(divide="ignore", invalid="ignore"):
            touching = 2 * np.pi * r_eff * surface_tension * np.cos(theta_rad) * (
                1.0 - gap * np.sqrt(np.pi * r_eff / (2.0 * vol)))
            p = -1.0 + np.sqrt(1.0 + 2.0 * vol / (np.pi * r_eff * gap**2))
            d_sp = 0.5 * gap * p
            alpha = np.sqrt(gap / r_eff * p)
            separated = 2 * np.pi * r_eff * surface_tension * (
                np.cos(theta_rad) / (1.0 + gap / (2.0 * d_sp))
                + np.sin(alpha) * np.sin(alpha + theta_rad))
        out = np.where(gap <= 0.0, touching, separated)
        out = np.where(gap < self.rupture_distance(vol, theta_rad), out, 0.0)
        return out if out.ndim else float(out)

    def contact_force_and_stiffness(self, radius: float, surface_tension: float,
                                    theta_rad: float, content: float) -> tuple[float, float]:
        """F_0 = 2 pi R* gamma cos(theta), k_b = F_0 sqrt(pi R* / (2 V)) (the slope of
        Rabinovich's eq. A11 as coded in LIGGGHTS), R* = r / 2."""
        vol = float(self.bridge_volume(radius, radius, content, content))
        r_eff = 0.5 * radius
        f0 = 2.0 * math.pi * r_eff * surface_tension * math.cos(theta_rad)
        return f0, f0 * math.sqrt(math.pi * r_eff / (2.0 * vol))

    def force_positive(self, surface_tension: float, theta_rad: float, r_min: float,
                       r_max: float, content_min: float, content_max: float) -> bool:
        """The law is 2 pi R gamma [cos(theta) / (1 + S / 2d) + sin(alpha) sin(alpha + theta)]
        (both terms > 0 when gamma > 0, 0 <= theta < 90 deg and alpha <= 90 deg), and
        alpha^2 = S p / R <= sqrt(2 V / (pi R)) / R, bounded with a bridge volume above any
        of the pairs' (largest radius and content) and the smallest effective radius."""
        # margins keep the law far from underflow to 0 (a denormal surface tension, theta
        # at 90 deg, or a nearly dry partner: then the law itself decides)
        if not (surface_tension >= 1e-9 and 0.0 <= theta_rad <= math.radians(89.9)):
            return False
        if not content_min >= 1e-12:          # a dry partner: the law is 0 * inf at contact
            return False
        v_max = self.bridge_volume_fraction * 2.0 * float(sphere_volume(r_max)) * content_max
        r_eff = 0.5 * r_min
        return math.sqrt(2.0 * v_max / (math.pi * r_eff)) / r_eff <= (0.5 * math.pi) ** 2


WASHINO = Washino()
