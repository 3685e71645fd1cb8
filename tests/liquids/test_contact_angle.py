"""ligwf.liquids.contact_angle: the LIGGGHTS 3.8.0 contact-angle law and its compensation."""

from __future__ import annotations

import math

import pytest

from ligwf.liquids.contact_angle import engine_contact_angle_deg, engine_effective_angle_rad


def test_contact_angle_compensation():
    # the engine applies 0.5*a*a (rad) for input a: compensation must invert that
    for theta in (0.0, 10.0, 30.0, 90.0, 180.0):
        a = engine_contact_angle_deg(theta)
        assert 0.0 <= a <= 180.0
        assert math.degrees(engine_effective_angle_rad(a)) == pytest.approx(theta, abs=1e-9)
    assert engine_contact_angle_deg(30.0, compensate=False) == 30.0
    # uncompensated, 30 deg becomes about 7.9 deg in the engine
    assert math.degrees(engine_effective_angle_rad(30.0)) == pytest.approx(7.85, abs=0.01)
