"""Checks every liquid model must pass, shared by the per-model tests in tests/liquids/."""

from __future__ import annotations

import math

import pytest

from ligwf import liquids
from ligwf.liquids.capillary import viscous_normal_force
from ligwf.scene.scaling import scale

GAP_RATIOS = [0.0, 0.01, 0.05, 0.1]  # surface gap / effective radius


def bridge_force(s, gap_ratio: float) -> float:
    """Force of the case's model between two smallest particles at a dimensionless gap."""
    r = 0.5 * s.d_min
    gap = gap_ratio * 0.5 * r
    theta = math.radians(s.liquid_values.contact_angle_deg)
    return liquids.get(s.liquid_values.model).capillary_force(r, r, gap, s.liquid_values.surface_tension, theta,
                                                       s.liquid_values.liquid_content)


def viscous_force(s, gap_ratio: float, speed: float = 0.1) -> float:
    r = 0.5 * s.d_min
    return viscous_normal_force(r, r, gap_ratio * 0.5 * r, s.liquid_values.viscosity, speed,
                                s.liquid_values.min_separation_ratio)


def assert_forces_scale_as_rule(scene, n: int, rule: str, power: int) -> None:
    """Bridge and lubrication forces of CG-n under ``rule`` are n^power those of CG1, at
    every dimensionless gap (the CG rules' promise, proved on the model's own law)."""
    s1, sn = scale(scene, 1, "none"), scale(scene, n, rule)
    for g in GAP_RATIOS:
        f1, fn = bridge_force(s1, g), bridge_force(sn, g)
        assert f1 > 0
        assert fn / f1 == pytest.approx(n**power, rel=1e-9), (scene.liquid.model, g)
        v1, vn = viscous_force(s1, g), viscous_force(sn, g)
        assert vn / v1 == pytest.approx(n**power, rel=1e-9)
