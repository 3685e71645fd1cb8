"""The easo capillary model (``cohesion easo/capillary/viscous`` of LIGGGHTS 3.8.0).

Mirrors ``cohesion_model_easo_capillary_viscous.h``: each partner gives the liquid on its
spherical cap facing the other, and the force is Soulie et al.'s fit, Int. J. Numer.
Anal. Meth. Geomech. 30 (2006) eqs. 13-14, as coded in LIGGGHTS (see
:meth:`Easo.capillary_force`). The engine forms an easo bridge only when the pair has
touched (the engine bridge test approaches first). easo on walls only supports dry walls.
"""

from __future__ import annotations

import math

import numpy as np

from ligwf.liquids.base import Kernels, sphere_volume
from ligwf.liquids.capillary import CapillaryModel, within_rupture
from ligwf.numba_cache import cached_jit


def bridge_volume(r_i, r_j, content_i, content_j):
    """Bridge volume, m^3: each partner gives the liquid on its spherical cap facing the other."""
    r_i, r_j = np.asarray(r_i, float), np.asarray(r_j, float)
    s = r_i + r_j
    cap_i = 0.5 * (1.0 - np.sqrt(1.0 - r_j**2 / s**2))
    cap_j = 0.5 * (1.0 - np.sqrt(1.0 - r_i**2 / s**2))
    return sphere_volume(r_i) * content_i * cap_i + sphere_volume(r_j) * content_j * cap_j


def _fit(vol, r2, theta_rad):
    """Soulie's coefficients (A, B, C) for bridge volume ``vol`` (m^3) and the larger radius
    ``r2`` (m): V* = V / r2^3, A = -1.1 V*^-0.53,
    B = (-0.148 ln V* - 0.96) theta^2 - 0.0082 ln V* + 0.48, C = 0.0018 ln V* + 0.078."""
    vs = vol / r2**3
    a = -1.1 * vs ** (-0.53)
    b = (-0.148 * np.log(vs) - 0.96) * theta_rad**2 - 0.0082 * np.log(vs) + 0.48
    c = 0.0018 * np.log(vs) + 0.078
    return a, b, c


@cached_jit(inline="always", error_model="numpy")
def _volume(ri, rj, lvi, lvj):
    """:func:`bridge_volume` from each partner's liquid volume (m^3), m^3."""
    s = ri + rj
    cap_i = 0.5 * (1.0 - math.sqrt(1.0 - rj**2 / s**2))
    cap_j = 0.5 * (1.0 - math.sqrt(1.0 - ri**2 / s**2))
    return lvi * cap_i + lvj * cap_j


@cached_jit(inline="always", error_model="numpy")
def _force(ri, rj, gap, gamma, theta, cos_theta, sin_theta, vol):
    """:meth:`Easo.capillary_force` for one pair within rupture, N."""
    r2 = max(ri, rj)
    vs = vol / r2**3
    log_vs = math.log(vs)
    a = -1.1 * vs ** (-0.53)
    b = (-0.148 * log_vs - 0.96) * theta**2 - 0.0082 * log_vs + 0.48
    c = 0.0018 * log_vs + 0.078
    expo = a * gap / r2 + b if gap > 0.0 else b
    return np.pi * gamma * math.sqrt(ri * rj) * (math.exp(expo) + c)


class Easo(CapillaryModel):
    name = "easo"
    cohesion = "easo/capillary/viscous"
    bridge_needs_contact = True
    kernels = Kernels(volume=_volume, within_rupture=within_rupture, force=_force)

    def bridge_volume(self, r_i, r_j, content_i, content_j):
        return bridge_volume(r_i, r_j, content_i, content_j)

    def capillary_force(self, r_i, r_j, gap, surface_tension, theta_rad, content_i,
                        content_j=None):
        """Capillary force magnitude, N (0 beyond rupture).

        With R2 = max(r_i, r_j) and Soulie's A, B, C (:func:`_fit`):
        F = pi gamma sqrt(r_i r_j) (exp(A gap / R2 + B) + C); the gap term is dropped while
        the spheres touch.
        """
        content_j = content_i if content_j is None else content_j
        r_i, r_j, gap = (np.asarray(a, float) for a in (r_i, r_j, gap))
        vol = bridge_volume(r_i, r_j, content_i, content_j)
        r2 = np.maximum(r_i, r_j)
        a, b, c = _fit(vol, r2, theta_rad)
        expo = np.where(gap > 0.0, a * gap / r2 + b, b)
        out = np.pi * surface_tension * np.sqrt(r_i * r_j) * (np.exp(expo) + c)
        out = np.where(gap < self.rupture_distance(vol, theta_rad), out, 0.0)
        return out if out.ndim else float(out)

    def contact_force_and_stiffness(self, radius: float, surface_tension: float,
                                    theta_rad: float, content: float) -> tuple[float, float]:
        """F_0 = pi gamma r (exp(B) + C), k_b = pi gamma r exp(B) |A| / r (the slope of
        Soulie's law at gap 0+) for two spheres of radius r."""
        vol = float(bridge_volume(radius, radius, content, content))
        a, b, c = (float(x) for x in _fit(vol, radius, theta_rad))
        f0 = math.pi * surface_tension * radius * (math.exp(b) + c)
        return f0, math.pi * surface_tension * radius * math.exp(b) * abs(a) / radius


EASO = Easo()
