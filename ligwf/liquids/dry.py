"""The dry bed (``liquid.model: none``): no cohesion model, no bridges, no liquid scaling.

The input then has no ``cohesion`` keyword and no liquid properties; granule analysis
finds no bonds (every particle is its own granule).
"""

from __future__ import annotations

import numpy as np

from ligwf.liquids.base import Kernels, LiquidModel
from ligwf.numba_cache import cached_jit


@cached_jit(inline="always")
def _volume(ri, rj, lvi, lvj):
    return 0.0


@cached_jit(inline="always")
def _never(gap, vol, theta):
    return False


@cached_jit(inline="always")
def _force(ri, rj, gap, gamma, theta, cos_theta, sin_theta, vol):
    return 0.0


class Dry(LiquidModel):
    name = "none"
    wet = False
    kernels = Kernels(volume=_volume, within_rupture=_never, force=_force)

    def bridge_volume(self, r_i, r_j, content_i, content_j):
        return np.zeros(np.broadcast(np.asarray(r_i), np.asarray(r_j)).shape)

    def rupture_distance(self, bridge_volume, theta_rad):
        return np.zeros(np.shape(bridge_volume))

    def capillary_force(self, r_i, r_j, gap, surface_tension, theta_rad, content_i,
                        content_j=None):
        out = np.zeros(np.broadcast(np.asarray(r_i), np.asarray(r_j), np.asarray(gap)).shape)
        return out if out.ndim else 0.0

    def contact_force_and_stiffness(self, radius: float, surface_tension: float,
                                    theta_rad: float, content: float) -> tuple[float, float]:
        return 0.0, 0.0


DRY = Dry()
