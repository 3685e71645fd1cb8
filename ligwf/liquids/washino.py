"""The washino capillary model (``cohesion washino/capillary/viscous`` of LIGGGHTS 3.8.0).

Mirrors ``cohesion_model_washino_capillary_viscous.h``: the bridge takes a fixed share of
both particles' surface liquid, and the force follows Rabinovich et al., Langmuir 21
(2005) as coded in LIGGGHTS (see :meth:`Washino.capillary_force`). Verified against the
engine's pair force to 1e-9 (``tests/engine/test_engine_bridge.py``).
"""

from __future__ import annotations

import math

import numpy as np

from ligwf.liquids.base import Kernels, sphere_volume
from ligwf.liquids.capillary import CapillaryModel, within_rupture
from ligwf.numba_cache import cached_jit

#: LIGGGHTS' default fraction of the two particles' liquid that forms a washino bridge
#: (``lbVolumeFraction``, used unless ``modifyLbVolume`` is switched on).
BRIDGE_VOLUME_FRACTION = 0.05


def bridge_volume(r_i, r_j, content_i, content_j, fraction: float = BRIDGE_VOLUME_FRACTION):
    """Bridge volume, m^3: ``fraction`` of both particles' surface liquid."""
    return fraction * (sphere_volume(r_i) * content_i + sphere_volume(r_j) * content_j)


@cached_jit(inline="always", error_model="numpy")
def _volume(ri, rj, lvi, lvj):
    """:func:`bridge_volume` from each partner's liquid volume (m^3), m^3."""
    return BRIDGE_VOLUME_FRACTION * (lvi + lvj)


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
    name = "washino"
    cohesion = "washino/capillary/viscous"
    kernels = Kernels(volume=_volume, within_rupture=within_rupture, force=_force)

    def bridge_volume(self, r_i, r_j, content_i, content_j):
        return bridge_volume(r_i, r_j, content_i, content_j)

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
        vol = bridge_volume(r_i, r_j, content_i, content_j)
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
        vol = float(bridge_volume(radius, radius, content, content))
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
        v_max = BRIDGE_VOLUME_FRACTION * 2.0 * float(sphere_volume(r_max)) * content_max
        r_eff = 0.5 * r_min
        return math.sqrt(2.0 * v_max / (math.pi * r_eff)) / r_eff <= (0.5 * math.pi) ** 2


WASHINO = Washino()
