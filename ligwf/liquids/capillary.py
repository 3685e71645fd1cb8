"""What LIGGGHTS' two capillary cohesion models (washino, easo) share.

Both ``cohesion washino/capillary/viscous`` and ``cohesion easo/capillary/viscous`` read the
same six ``fix property/global`` entries, break a bridge at Lian et al.'s rupture distance
(1 + theta/2) V^(1/3) in their force law, cut it at ``maxSeparationDistanceRatio`` x
(r_i + r_j), enlarge the contact distance factor of the neighbour lists to 1.1 x that
ratio, add the same lubrication force, and create the per-atom ``surfaceLiquidContent``.
The models differ in their force law and bridge volume only (:mod:`ligwf.liquids.washino`,
:mod:`ligwf.liquids.easo`).
"""

from __future__ import annotations

import numpy as np

from ligwf.liquids.base import InputAngle, Line, LiquidBlock, LiquidModel, ScaledLiquid, \
    comment
from ligwf.numba_cache import cached_jit

#: the properties both capillary cohesion models read (LIGGGHTS 3.8.0 source)
CAPILLARY_PROPERTIES = ("surfaceLiquidContentInitial", "surfaceTension", "fluidViscosity",
                        "contactAngle", "minSeparationDistanceRatio",
                        "maxSeparationDistanceRatio")


def rupture_distance(bridge_volume, theta_rad):
    """Gap at which a bridge breaks, m: (1 + theta/2) V^(1/3) (Lian et al., both models)."""
    return (1.0 + 0.5 * theta_rad) * np.cbrt(bridge_volume)


@cached_jit(inline="always", error_model="numpy")
def within_rupture(gap, vol, theta):
    """``gap < (1 + theta/2) vol^(1/3)`` (:func:`rupture_distance`) decided without the cube
    root where the cubes differ by more than any rounding could (1e-10 relative); the few
    pairs closer than that get the exact comparison. Written with non-short-circuit
    ``&``/``|`` so the compiler can avoid branches on random gaps."""
    separated = gap > 0.0
    g3, r3 = gap * gap * gap, (1.0 + 0.5 * theta) ** 3 * vol
    sure_in = (gap < 0.0) | (separated & (g3 < r3 * (1.0 - 1e-10)))
    sure_out = separated & (g3 > r3 * (1.0 + 1e-10))
    if sure_in | sure_out:
        return sure_in
    return gap < (1.0 + 0.5 * theta) * np.cbrt(vol)


def viscous_normal_force(r_i, r_j, gap, viscosity, normal_speed, min_separation_ratio):
    """Normal lubrication force magnitude, N: 6 pi mu R* v_n / max(s_min, gap / R*)
    (Nase et al. as cited by Shi and McCarthy, Powder Technol. 184 (2008) eq. 40)."""
    r_i, r_j, gap = (np.asarray(a, float) for a in (r_i, r_j, gap))
    r_eff = r_i * r_j / (r_i + r_j)
    out = 6 * np.pi * viscosity * r_eff * np.abs(normal_speed) / np.maximum(
        min_separation_ratio, gap / r_eff)
    return out if out.ndim else float(out)


class CapillaryModel(LiquidModel):
    """Base of the LIGGGHTS capillary models: their lines, checks, rupture and cutoffs."""

    properties = CAPILLARY_PROPERTIES
    dump_columns = ("f_surfaceLiquidContent",)

    def validate(self, liquid: LiquidBlock) -> list[str]:
        problems = super().validate(liquid)
        if liquid.max_separation_ratio < liquid.min_separation_ratio:
            problems.append(f"max_separation_ratio = {liquid.max_separation_ratio:g} must "
                            f"be >= min_separation_ratio = {liquid.min_separation_ratio:g}")
        return problems

    def liggghts_lines(self, s: ScaledLiquid, angle: InputAngle) -> tuple[Line, ...]:
        # LIGGGHTS reads surfaceLiquidContentInitial as a FRACTION of the particle volume
        # (its docs say %) and contactAngle in degrees, per atom type (particles, wall)
        note = (f"({angle.note})",) if angle.note else ()
        return self.checked_lines((
            comment("contact angle: scene", s.contact_angle_deg, "deg; engine input",
                    angle.degrees, "deg", *note),
            self.property_line("lq_content", "surfaceLiquidContentInitial", "scalar",
                               s.liquid_content),
            self.property_line("lq_gamma", "surfaceTension", "scalar", s.surface_tension),
            self.property_line("lq_mu", "fluidViscosity", "scalar", s.viscosity),
            self.property_line("lq_theta", "contactAngle", "peratomtype", angle.degrees,
                               angle.degrees),
            self.property_line("lq_smin", "minSeparationDistanceRatio", "scalar",
                               s.min_separation_ratio),
            self.property_line("lq_smax", "maxSeparationDistanceRatio", "scalar",
                               s.max_separation_ratio),
        ))

    def rupture_distance(self, bridge_volume, theta_rad):
        return rupture_distance(bridge_volume, theta_rad)

    def engine_cutoff_gaps(self, radius: float,
                           max_separation_ratio: float) -> tuple[float, float]:
        # the engine cuts the bridge at max_separation_ratio x (r_i + r_j) and registers a
        # contact distance factor 1.1 x max_separation_ratio for the neighbour lists
        return ((max_separation_ratio - 1.0) * 2.0 * radius,
                (1.1 * max_separation_ratio - 1.0) * 2.0 * radius)
