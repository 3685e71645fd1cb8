"""CG scaling rules: dimensionless numbers, kept quantities, sizes, counts and time steps.

The force laws themselves scaling as the rules say is proved per model in tests/liquids/."""

from __future__ import annotations

import math

import pytest

from ligwf.scene.scaled import rayleigh_time
from ligwf.scene.scaling import bond_number, scale, weber_number
from ligwf.scene.seeds import is_prime, replica_seeds
from ligwf.scene.workflow import load_workflow

from helpers import DRUM, WET_POLY


def base_scene(model: str = "washino"):
    return load_workflow(DRUM, [f"scene.liquid.model={model}"]).cases[0].scene


@pytest.mark.parametrize("n", [2, 3, 4])
def test_weber_conserved_under_weber_rule(n):
    scene = base_scene()
    s1, sn = scale(scene, 1, "none"), scale(scene, n, "weber")
    v = scene.drum.radius * s1.drum.omega  # same drum, same speed
    we1 = weber_number(s1.particles.density, 0.5 * s1.d_min, v, s1.liquid_values.surface_tension, s1.liquid_values.contact_angle_deg)
    wen = weber_number(sn.particles.density, 0.5 * sn.d_min, v, sn.liquid_values.surface_tension, sn.liquid_values.contact_angle_deg)
    assert wen == pytest.approx(we1, rel=1e-12)
    bo1 = bond_number(s1.particles.density, 0.5 * s1.d_min, s1.liquid_values.surface_tension, s1.liquid_values.contact_angle_deg)
    bon = bond_number(sn.particles.density, 0.5 * sn.d_min, sn.liquid_values.surface_tension, sn.liquid_values.contact_angle_deg)
    assert bon == pytest.approx(bo1 / n, rel=1e-12)  # and Bo is NOT kept


@pytest.mark.parametrize("n", [2, 3, 4])
def test_bond_conserved_under_bond_rule(n):
    scene = base_scene()
    s1, sn = scale(scene, 1, "none"), scale(scene, n, "bond")
    bo1 = bond_number(s1.particles.density, 0.5 * s1.d_min, s1.liquid_values.surface_tension, s1.liquid_values.contact_angle_deg)
    bon = bond_number(sn.particles.density, 0.5 * sn.d_min, sn.liquid_values.surface_tension, sn.liquid_values.contact_angle_deg)
    assert bon == pytest.approx(bo1, rel=1e-12)


def test_unchanged_quantities():
    scene = base_scene()
    s1, s3 = scale(scene, 1, "none"), scale(scene, 3, "bond")
    for group, name in (("liquid_values", "contact_angle_deg"),
                        ("liquid_values", "liquid_content"),
                        ("liquid_values", "min_separation_ratio"),
                        ("liquid_values", "max_separation_ratio"),
                        ("particles", "restitution"), ("particles", "friction"),
                        ("particles", "density"), ("particles", "youngs_modulus"),
                        ("particles", "poisson_ratio"), ("drum", "omega"), ("drum", "diameter")):
        assert getattr(getattr(s3, group), name) == getattr(getattr(s1, group), name), name
    assert s3.liquid_values.surface_tension == pytest.approx(9 * s1.liquid_values.surface_tension)
    assert s3.liquid_values.viscosity == pytest.approx(9 * s1.liquid_values.viscosity)


def test_ssw_size_distribution_keeps_shape():
    scene = load_workflow(WET_POLY).cases[0].scene
    s1, s3 = scale(scene, 1, "none"), scale(scene, 3, "weber")
    assert [d * 3 for d in s1.particles.diameters] == pytest.approx(list(s3.particles.diameters))
    assert s3.particles.number_fractions == s1.particles.number_fractions
    assert sum(s1.particles.number_fractions) == pytest.approx(1.0)
    # 80 % at 1 mm, 20 % spread over 1..4 mm in three bins, largest first
    assert s1.particles.diameters == pytest.approx((0.0035, 0.0025, 0.0015, 0.001))
    assert s1.particles.number_fractions == pytest.approx((0.2 / 3, 0.2 / 3, 0.2 / 3, 0.8))


@pytest.mark.parametrize("n", [2, 3, 4])
def test_count_and_time_step_scale(n):
    scene = base_scene()
    s1, sn = scale(scene, 1, "none"), scale(scene, n, "weber")
    assert sn.particles.count == round(s1.particles.count / n**3)
    assert sn.numerics.dt == pytest.approx(n * s1.numerics.dt)
    assert sn.numerics.run_steps == pytest.approx(s1.numerics.run_steps / n, abs=1)


def test_particle_count_from_fill_fraction():
    scene = base_scene()
    s = scale(scene, 1, "none")
    r, lif = scene.drum.radius, scene.drum.lifters
    free = (math.pi * r**2 - lif.count * math.radians(lif.width_deg) * 0.5
            * (r**2 - (r - lif.height) ** 2)) * scene.drum.length
    expected = scene.process.fill_fraction * scene.numerics.packing_fraction * free / (
        math.pi * 1e-9 / 6)
    assert s.particles.count == round(expected)


def test_rayleigh_time_hand_value():
    # 1 mm glass-like bead: R = 0.5 mm, rho 2500, E 5e6, nu 0.3 -> G = 1.923e6 Pa
    t = rayleigh_time(5e-4, 2500.0, 5e6, 0.3)
    assert t == pytest.approx(math.pi * 5e-4 * math.sqrt(2500 / 1.923076923e6) / 0.92553, rel=1e-6)


def test_cg1_is_rule_independent():
    scene = base_scene()
    assert scale(scene, 1, "bond") == scale(scene, 1, "weber") == scale(scene, 1, "none")


def test_seeds_are_distinct_primes_above_10000():
    seeds = replica_seeds(10007, 0, 6) + replica_seeds(10007, 1, 6)
    assert len(set(seeds)) == 12
    assert all(s > 10000 and is_prime(s) for s in seeds)
