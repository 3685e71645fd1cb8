"""A toy fourth liquid model, defined outside ligwf to prove a model is one new module.

Constant force: F = k 2 pi R* gamma cos(theta) at every gap below Lian's rupture distance
of a washino-like bridge (5 % of both particles' liquid), 0 beyond. ``k`` is the model's
own setting ``liquid.force_factor`` (default 1), declared here (:class:`ToySettings`) and
nowhere else: the scene validates it, scaling carries it, the input and the granule
analysis apply it. Its input lines use LIGGGHTS' ``sjkr`` cohesion (cohesionEnergyDensity
= F_0 / (pi R* d_min) per type pair, a rough mapping; the input is rendered, never run).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numba import njit
from pydantic import Field

from ligwf.liquids import register
from ligwf.liquids.base import Kernels, LiquidModel, LiquidSettings, sphere_volume
from ligwf.liquids.capillary import rupture_distance, within_rupture

FRACTION = 0.05


@njit(inline="always")
def _volume(ri, rj, lvi, lvj):
    return FRACTION * (lvi + lvj)


@njit(inline="always")
def _force(ri, rj, gap, gamma, theta, cos_theta, sin_theta, vol):
    return 2.0 * np.pi * (ri * rj / (ri + rj)) * gamma * cos_theta


@lru_cache(maxsize=None)
def force_kernel(factor: float):
    """The numba force at ``factor`` times the default (``_force`` itself at 1)."""
    if factor == 1.0:
        return _force

    @njit(inline="always")
    def force(ri, rj, gap, gamma, theta, cos_theta, sin_theta, vol):
        return factor * 2.0 * np.pi * (ri * rj / (ri + rj)) * gamma * cos_theta
    return force


class ToySettings(LiquidSettings):
    """The toy's own setting: a key of ``liquid:`` no other model has."""

    force_factor: float = Field(1.0, gt=0.0, le=10.0, description="toy_constant only: "
                                "the constant force in units of 2 pi R* gamma cos(theta)",
                                json_schema_extra={"unit": "1"})


class ConstantForce(LiquidModel):
    name = "toy_constant"
    cohesion = "sjkr"
    properties = ("cohesionEnergyDensity",)
    settings_type = ToySettings
    kernels = Kernels(volume=_volume, within_rupture=within_rupture, force=_force)

    def with_settings(self, settings):
        law = super().with_settings(settings)
        law.kernels = Kernels(volume=_volume, within_rupture=within_rupture,
                              force=force_kernel(settings.force_factor))
        return law

    def validate(self, liquid):
        if liquid.contact_angle_deg >= 90.0:
            return [f"contact_angle_deg = {liquid.contact_angle_deg:g}: the toy law needs "
                    "< 90 deg (a positive force)"]
        return []

    def liggghts_lines(self, s, angle):
        energy = (self.settings.force_factor * s.surface_tension
                  * math.cos(math.radians(s.contact_angle_deg)))
        return self.checked_lines((
            self.property_line("lq_ced", "cohesionEnergyDensity", "peratomtypepair", 2,
                               energy, energy, energy, energy),))

    def bridge_volume(self, r_i, r_j, content_i, content_j):
        return FRACTION * (sphere_volume(r_i) * content_i + sphere_volume(r_j) * content_j)

    def rupture_distance(self, bridge_volume, theta_rad):
        return rupture_distance(bridge_volume, theta_rad)

    def capillary_force(self, r_i, r_j, gap, surface_tension, theta_rad, content_i,
                        content_j=None):
        content_j = content_i if content_j is None else content_j
        r_i, r_j, gap = (np.asarray(a, float) for a in (r_i, r_j, gap))
        vol = self.bridge_volume(r_i, r_j, content_i, content_j)
        f = (self.settings.force_factor * 2.0 * np.pi * (r_i * r_j / (r_i + r_j))
             * surface_tension * np.cos(theta_rad))
        out = np.where(gap < self.rupture_distance(vol, theta_rad), f, 0.0)
        return out if out.ndim else float(out)

    def contact_force_and_stiffness(self, radius, surface_tension, theta_rad, content):
        return (self.settings.force_factor * math.pi * radius * surface_tension
                * math.cos(theta_rad), 0.0)

    def force_positive(self, surface_tension, theta_rad, r_min, r_max, content_min,
                       content_max):
        return surface_tension > 0.0 and 0.0 <= theta_rad < 0.5 * math.pi


TOY = register(ConstantForce())
