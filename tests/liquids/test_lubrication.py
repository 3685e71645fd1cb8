"""The engine's viscous force as ligwf mirrors it, and ``liquid.min_separation_ratio``.

LIGGGHTS' capillary models (washino, easo) apply 6 pi mu R* v_n / max(s_min, gap / R*)
normally and (8/15 ln(1 / max(s_min, gap / R*)) + 0.9588) 6 pi mu R* v_t tangentially,
s_min = ``minSeparationDistanceRatio`` (``liquid.min_separation_ratio``). Here: the
mirror's two branches by hand, the viscous path integral against a quadrature, the scene
field's range (> 0) and its rendering. The engine's side:
tests/engine/test_engine_bridge_dynamics.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ligwf.engine.render import render
from ligwf.errors import ConfigError
from ligwf.liquids.capillary import (lubrication_gap, viscous_normal_force,
                                     viscous_path_integral, viscous_tangential_force)
from ligwf.scene.scaling import scale
from ligwf.scene.workflow import load_workflow

from helpers import DRUM

R = 5e-4            # m, both particles: R* = 2.5e-4 m
MU, SPEED = 1e-3, 0.1


def test_normal_force_grows_as_one_over_the_gap_down_to_s_min_then_stops():
    r_eff = 0.5 * R
    stokes = 6 * math.pi * MU * r_eff * SPEED
    for s_min in (0.02, 0.05, 0.3):
        for x in (0.01, 0.03, 0.1, 0.3):
            expected = stokes / max(s_min, x)
            assert viscous_normal_force(R, R, x * r_eff, MU, SPEED, s_min) == pytest.approx(
                expected, rel=1e-12)
        # touching (negative gap) and at s_min: the same capped force
        assert viscous_normal_force(R, R, -0.01 * r_eff, MU, SPEED, s_min) == pytest.approx(
            stokes / s_min, rel=1e-12)
    # ligwf's default 1.01: Stokes drag / 1.01 at every gap a bridge can have (<= 0.6 R*)
    forces = viscous_normal_force(R, R, np.array([0.0, 0.1, 0.4, 0.6]) * r_eff, MU, SPEED, 1.01)
    assert np.allclose(forces, stokes / 1.01, rtol=1e-12)
    # lubrication at s_min 0.02 is 50x the default's force at 0.01 R*, and equal at R*
    assert viscous_normal_force(R, R, 0.01 * r_eff, MU, SPEED, 0.02) == pytest.approx(
        1.01 / 0.02 * viscous_normal_force(R, R, 0.01 * r_eff, MU, SPEED, 1.01))


def test_tangential_force_by_hand_and_unequal_radii():
    r_i, r_j = 4e-4, 6e-4
    r_eff = r_i * r_j / (r_i + r_j)
    gap = 0.1 * r_eff
    assert lubrication_gap(r_i, r_j, gap, 0.02) == pytest.approx(0.1, rel=1e-12)
    assert lubrication_gap(r_i, r_j, gap, 0.3) == 0.3
    expected = (0.5333333 * math.log(10.0) + 0.9588) * 6 * math.pi * MU * r_eff * SPEED
    assert viscous_tangential_force(r_i, r_j, gap, MU, SPEED, 0.02) == pytest.approx(
        expected, rel=1e-12)


@pytest.mark.parametrize("s_min", [0.02, 0.05, 0.3, 0.4, 1.01, 3.0])
@pytest.mark.parametrize("x_end", [0.4, 0.6])
def test_viscous_path_integral_is_the_quadrature_of_the_law(s_min, x_end):
    """J = int_0^x_end dx / max(s_min, x), checked on a fine grid (both branches)."""
    x = np.linspace(0.0, x_end, 400_001)
    numeric = np.trapezoid(1.0 / np.maximum(s_min, x), x)
    assert viscous_path_integral(x_end, s_min) == pytest.approx(numeric, rel=1e-6)


def test_viscous_path_integral_refuses_zero():
    with pytest.raises(ValueError, match=r"min_separation_ratio = 0: .*allowed > 0"):
        viscous_path_integral(0.4, 0.0)


def scene(*overrides: str):
    return load_workflow(DRUM, ["scene.liquid.model=washino", *overrides]).cases[0].scene


@pytest.mark.parametrize("value", [0.02, 0.05, 0.3])
def test_lubrication_values_are_accepted_and_written_unchanged_at_every_cg(value):
    sc = scene(f"scene.liquid.min_separation_ratio={value}")
    for n, rule in ((1, "none"), (2, "weber"), (3, "bond")):
        text = render(scale(sc, n, rule))["in.liggghts"]
        assert f"fix lq_smin all property/global minSeparationDistanceRatio scalar {value:g}\n" in text


@pytest.mark.parametrize("value", ["0", "-0.02", "20"])
def test_out_of_range_refused_in_one_line(value):
    with pytest.raises(ConfigError) as info:
        scene(f"scene.liquid.min_separation_ratio={value}")
    line = next(l for l in str(info.value).splitlines() if "min_separation_ratio" in l)
    assert f"scene.liquid.min_separation_ratio = {value}:" in line
    assert "(allowed range (0, 10])" in line and "divides" in line


def test_no_order_between_the_two_ratios():
    """min_separation_ratio is a gap over R*, max_separation_ratio a centre distance over
    r_i + r_j: different quantities, so neither bounds the other (the engine has no such
    rule); Stokes drag / 2 with bridges cut at 1.05 is a legal scene."""
    sc = scene("scene.liquid.min_separation_ratio=2", "scene.liquid.max_separation_ratio=1.05")
    assert (sc.liquid.min_separation_ratio, sc.liquid.max_separation_ratio) == (2.0, 1.05)


def test_default_unchanged():
    """The default stays 1.01 (lubrication off) until a measurement says otherwise: the
    golden inputs and scene hashes of existing studies do not move."""
    sc = load_workflow(DRUM, []).cases[0].scene
    assert sc.liquid.min_separation_ratio == 1.01
    assert "minSeparationDistanceRatio scalar 1.01\n" in render(scale(sc, 1, "none"))["in.liggghts"]
