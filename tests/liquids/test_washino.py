"""The washino model: its pre-flight quantities and its positivity proof."""

from __future__ import annotations

import pytest

from ligwf import liquids


def test_contact_force_and_stiffness_hand_value():
    # 1 mm spheres, 2 % liquid, theta = 0: V = 0.05 * 2 * 4.18879e-9 * 0.02 = 8.3776e-12 m^3,
    # F0 = 2 pi 5e-4 0.072 = 2.2619e-4 N, k_b = F0 sqrt(pi 5e-4 / (2 V)) = 2.1901 N/m
    f0, k_b = liquids.get("washino").contact_force_and_stiffness(1e-3, 0.072, 0.0, 0.02)
    assert f0 == pytest.approx(2.2619e-4, rel=2e-4)
    assert k_b == pytest.approx(2.1901, rel=2e-4)


def test_law_is_positive_where_it_claims():
    law = liquids.get("washino")
    assert law.force_positive(0.024, 0.5, 5e-4, 5e-4, 0.02, 0.02)
    assert not law.force_positive(0.024, 1.6, 5e-4, 5e-4, 0.02, 0.02)   # theta > 90 deg
    assert not law.force_positive(0.024, 0.5, 5e-4, 5e-4, 0.0, 0.02)    # a dry partner
