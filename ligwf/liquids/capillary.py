"""What LIGGGHTS' two capillary cohesion models (washino, easo) share.

Both ``cohesion washino/capillary/viscous`` and ``cohesion easo/capillary/viscous`` read the
same six ``fix property/global`` entries, break a bridge at Lian et al.'s rupture distance
(1 + theta/2) V^(1/3) in their force law, cut it at ``maxSeparationDistanceRatio`` x
(r_i + r_j), enlarge the contact distance factor of the neighbour lists to 1.1 x that
ratio, add the same viscous force, and create the per-atom ``surfaceLiquidContent``.
The models differ in their force law, bridge volume and when a bridge forms
(:mod:`ligwf.liquids.washino`: on approach, at the rupture gap; :mod:`ligwf.liquids.easo`:
only once the pair has touched) -- measured on the engine in
tests/engine/test_engine_bridge_dynamics.py.

The viscous force (Nase et al. as cited by Shi and McCarthy, Powder Technol. 184 (2008)
eqs. 40-41) is regularised by ``minSeparationDistanceRatio`` s_min: a GAP OVER R* =
r_i r_j / (r_i + r_j) below which the force stops growing (in contact it is the value at
s_min). Bridges end at a gap of at most ~0.4-0.6 R*, so s_min >= 1 turns lubrication off
(Stokes drag / s_min at every bridged gap); s_min of a few 1e-2 gives lubrication that
grows as R*/h down to h = s_min R*; s_min = 0 makes the engine divide by zero (nan).
"""

from __future__ import annotations

import numpy as np

from ligwf.liquids.base import InputAngle, Line, LiquidModel, ScaledLiquid, \
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


def lubrication_gap(r_i, r_j, gap, min_separation_ratio):
    """max(s_min, gap / R*): the dimensionless gap the engine's viscous force is evaluated
    at (``MathExtraLiggghts::max(minSeparationDistanceRatio, dist/rEff)``; a touching pair,
    gap <= 0, gets s_min)."""
    r_i, r_j, gap = (np.asarray(a, float) for a in (r_i, r_j, gap))
    return np.maximum(min_separation_ratio, gap * (r_i + r_j) / (r_i * r_j))


def viscous_normal_force(r_i, r_j, gap, viscosity, normal_speed, min_separation_ratio):
    """Normal viscous force magnitude, N: 6 pi mu R* v_n / max(s_min, gap / R*)
    (Nase et al. as cited by Shi and McCarthy, Powder Technol. 184 (2008) eq. 40), opposing
    the normal relative velocity v_n (m/s): lubrication ~ 1/gap above s_min R*, constant
    below; with s_min >= 1, Stokes drag / s_min at every bridged gap."""
    r_i, r_j = np.asarray(r_i, float), np.asarray(r_j, float)
    r_eff = r_i * r_j / (r_i + r_j)
    out = 6 * np.pi * viscosity * r_eff * np.abs(normal_speed) / lubrication_gap(
        r_i, r_j, gap, min_separation_ratio)
    return out if out.ndim else float(out)


def viscous_tangential_force(r_i, r_j, gap, viscosity, tangential_speed,
                             min_separation_ratio):
    """Tangential viscous force magnitude, N: (8/15 ln(1 / max(s_min, gap / R*)) + 0.9588)
    6 pi mu R* v_t (Shi and McCarthy eq. 41 as coded in LIGGGHTS, 8/15 written 0.5333333),
    opposing the tangential relative velocity v_t (m/s) of the surfaces."""
    r_i, r_j = np.asarray(r_i, float), np.asarray(r_j, float)
    r_eff = r_i * r_j / (r_i + r_j)
    factor = 0.5333333 * np.log(1.0 / lubrication_gap(r_i, r_j, gap, min_separation_ratio)) \
        + 0.9588
    out = factor * 6 * np.pi * viscosity * r_eff * np.abs(tangential_speed)
    return out if out.ndim else float(out)


def viscous_path_integral(bridge_gap_ratio, min_separation_ratio):
    """J = integral of dx / max(s_min, x) over x = gap / R* from contact (0) to the bridge's
    end ``bridge_gap_ratio``: the normal viscous impulse of one traverse of the bridge at
    relative speed v is 6 pi mu R*^2 v J (N s) while the speed changes little. With
    s_min < x_end: 1 + ln(x_end / s_min) (Ennis's ln(h_0 / h_a), the engine's s_min in the
    place of the asperity height); with s_min >= x_end: x_end / s_min (Stokes drag)."""
    x_end = np.asarray(bridge_gap_ratio, float)
    s = float(min_separation_ratio)
    if s <= 0:
        raise ValueError(f"min_separation_ratio = {s:g}: the engine divides by it (allowed > 0)")
    out = np.where(x_end > s, 1.0 + np.log(np.maximum(x_end, s) / s), np.maximum(x_end, 0.0) / s)
    return out if out.ndim else float(out)


class CapillaryModel(LiquidModel):
    """Base of the LIGGGHTS capillary models: their lines, checks, rupture and cutoffs."""

    properties = CAPILLARY_PROPERTIES
    dump_columns = ("f_surfaceLiquidContent",)

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
