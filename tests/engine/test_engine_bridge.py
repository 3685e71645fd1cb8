"""The CG force ratios and the contact-angle compensation, measured on the real engine.

Two particles are held (no integrator) at a fixed surface gap with a liquid bridge; the
engine's pair force on particle 2 is read from thermo. easo forms a bridge only on contact,
so for it the pair first touches and is then pulled to the gap.
"""

from __future__ import annotations

import math
import re

import pytest

from ligwf import liquids
from ligwf.liquids.contact_angle import engine_effective_angle_rad
from ligwf.engine.render import render_bridge_probe
from ligwf.scene.scaling import scale
from ligwf.scene.workflow import load_workflow

from helpers import DRUM, run_liggghts

pytestmark = [pytest.mark.engine]

GAP_RATIO = 0.05  # surface gap / effective radius for the CG ratios
#: a wider gap for the angle test, where the force depends more on the angle (washino 18 %,
#: easo 6 % between 30 deg and the 7.9 deg the uncompensated engine would apply)
ANGLE_GAP_RATIO = 0.3


def measure(engine, tmp_path, scaled, name: str, gap_ratio: float = GAP_RATIO) -> float:
    return probe(engine, tmp_path, scaled, name, gap_ratio)[0]


def probe(engine, tmp_path, scaled, name: str, gap_ratio: float) -> tuple[float, str]:
    """(the engine's bridge force on particle 2 at ``gap_ratio``, N; the engine's output)."""
    case = tmp_path / name
    case.mkdir()
    files = render_bridge_probe(scaled, gap_ratio, model_approach=scaled.liquid.bridge_needs_contact)
    (case / "in.liggghts").write_text(files["in.liggghts"])
    out = run_liggghts(engine, case, nprocs=1, timeout=120)
    assert out.returncode == 0, out.stdout[-3000:]
    rows = [l.split() for l in out.stdout.splitlines() if re.match(r"^\s+\d+\s+2\s+\S+\s+\S+\s+\S+\s*$", l)]
    assert rows, out.stdout[-3000:]
    step, atoms, gap, fx, fy = rows[-1]
    r = 0.5 * scaled.d_min
    assert float(gap) == pytest.approx(gap_ratio * 0.5 * r, rel=1e-6)
    assert abs(float(fy)) < 1e-12 * abs(float(fx))
    return -float(fx), out.stdout  # attraction pulls particle 2 (at +x) towards -x


@pytest.fixture(scope="module")
def forces(engine, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("bridge")
    out = {}
    for model in ("washino", "easo"):
        scene = load_workflow(DRUM, [f"scene.liquid.model={model}"]).cases[0].scene
        out[(model, 1, "none")] = (scale(scene, 1, "none"),
                                   measure(engine, tmp, scale(scene, 1, "none"), f"{model}-1"))
        for n in (2, 3):
            for rule in ("weber", "bond"):
                s = scale(scene, n, rule)
                out[(model, n, rule)] = (s, measure(engine, tmp, s, f"{model}-{n}-{rule}"))
    return out


@pytest.mark.parametrize("model", ["washino", "easo"])
@pytest.mark.parametrize("n", [2, 3])
@pytest.mark.parametrize("rule,power", [("weber", 2), ("bond", 3)])
def test_engine_force_ratio(forces, model, n, rule, power):
    _, f1 = forces[(model, 1, "none")]
    _, fn = forces[(model, n, rule)]
    assert f1 > 0
    assert fn / f1 == pytest.approx(n**power, rel=0.01)


@pytest.mark.parametrize("model", ["washino", "easo"])
def test_engine_applies_the_intended_contact_angle(engine, tmp_path, model):
    """Measured force equals the published law at the scene's angle (30 deg), not at the
    angle the uncompensated engine would apply (about 7.9 deg)."""
    scene = load_workflow(DRUM, [f"scene.liquid.model={model}"]).cases[0].scene
    s = scale(scene, 1, "none")
    measured = measure(engine, tmp_path, s, model, ANGLE_GAP_RATIO)
    r = 0.5 * s.d_min
    gap = ANGLE_GAP_RATIO * 0.5 * r
    law = liquids.get(model)
    intended = law.capillary_force(r, r, gap, s.liquid_values.surface_tension,
                                   math.radians(s.liquid_values.contact_angle_deg), s.liquid_values.liquid_content)
    buggy = law.capillary_force(r, r, gap, s.liquid_values.surface_tension,
                                engine_effective_angle_rad(s.liquid_values.contact_angle_deg), s.liquid_values.liquid_content)
    assert measured == pytest.approx(intended, rel=1e-4)
    assert abs(buggy - intended) > 0.05 * intended  # the test can tell the two apart


def test_uncompensated_engine_applies_the_product_angle(engine, tmp_path):
    """Pins the engine bug itself: with compensation off, 30 deg acts as 0.5*theta^2."""
    scene = load_workflow(DRUM, ["scene.numerics.contact_angle_compensation=false"]).cases[0].scene
    s = scale(scene, 1, "none")
    measured = measure(engine, tmp_path, s, "raw", ANGLE_GAP_RATIO)
    r = 0.5 * s.d_min
    expected = liquids.get("washino").capillary_force(
        r, r, ANGLE_GAP_RATIO * 0.5 * r, s.liquid_values.surface_tension,
        engine_effective_angle_rad(s.liquid_values.contact_angle_deg), s.liquid_values.liquid_content, s.liquid_values.liquid_content)
    assert measured == pytest.approx(expected, rel=1e-4)


def test_engine_applies_the_bridge_volume_fraction_and_the_cap(engine, tmp_path):
    """liquid.bridge_volume_fraction 0.2 (lbVolumeFraction with modifyLbVolume on) and
    max_liquid_content 0.1 (maxLiquidContent with limitLiquidContent on): the engine's
    pair force equals ligwf's law at that fraction to 1e-9 (thermo prints 13 digits), is
    far from the default law's, and the maxSeparationDistanceRatio the engine sets in place
    of the written one is the one ligwf computed and wrote."""
    base = ["scene.liquid.model=washino", "scene.liquid.bridge_volume_fraction=0.2"]
    for name, extra in (("fraction", []), ("fraction-cap", ["scene.liquid.max_liquid_content=0.1"])):
        s = scale(load_workflow(DRUM, base + extra).cases[0].scene, 1, "none")
        measured, log = probe(engine, tmp_path, s, name, ANGLE_GAP_RATIO)
        r = 0.5 * s.d_min
        theta = math.radians(s.liquid_values.contact_angle_deg)
        gap = ANGLE_GAP_RATIO * 0.5 * r
        assert s.liquid.bridge_volume_fraction == 0.2
        expected = s.liquid.capillary_force(r, r, gap, s.liquid_values.surface_tension, theta, s.liquid_values.liquid_content)
        assert measured == pytest.approx(expected, rel=1e-9)
        default = liquids.get("washino").capillary_force(r, r, gap, s.liquid_values.surface_tension, theta,
                                                         s.liquid_values.liquid_content)
        assert measured > 1.5 * default           # the test tells the fractions apart
        overwritten = re.findall(r"maxSeparationDistanceRatio being overwritten by (\S+) "
                                 r"\(was (\S+)\)", log)
        if extra:
            assert overwritten, log[-3000:]
            engine_ratio, written = (float(x) for x in overwritten[-1])
            assert engine_ratio == pytest.approx(s.liquid_values.max_separation_ratio, rel=1e-6)
            assert written == pytest.approx(s.liquid_values.max_separation_ratio, rel=1e-6)
            assert s.liquid_values.max_separation_ratio > 1.3   # the law's rupture gap, not the default 1.1
        else:
            assert not overwritten
