"""The easo model: its pre-flight quantities."""

from __future__ import annotations

import math

import pytest

from ligwf import liquids


def test_contact_force_and_stiffness_match_the_law():
    """F_0 is the law at contact and k_b its slope just outside it."""
    law, r, gamma, theta, content = liquids.get("easo"), 5e-4, 0.072, 0.3, 0.02
    f0, k_b = law.contact_force_and_stiffness(r, gamma, theta, content)
    assert f0 == pytest.approx(law.capillary_force(r, r, 0.0, gamma, theta, content), rel=1e-12)
    h = 1e-9 * r
    slope = (law.capillary_force(r, r, h, gamma, theta, content)
             - law.capillary_force(r, r, 2 * h, gamma, theta, content)) / h
    assert k_b == pytest.approx(slope, rel=1e-5)
    assert law.bridge_needs_contact and not math.isnan(f0)
