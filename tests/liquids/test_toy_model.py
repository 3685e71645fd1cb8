"""Extensibility: a fourth liquid model defined in tests/toy_constant.py (one new
file, registered there with one line) goes through every stage without touching ligwf:
validation, CG scaling, rendering, pre-flight and granule identification. So does its own
setting (``liquid.force_factor``, declared in that file only): refused in one line, kept by
the scaled record, applied by the input, the analysis and the foreign-dump reader."""

from __future__ import annotations

import argparse

import numpy as np
import pytest
from pathlib import Path

from ligwf import liquids

from ligwf.analysis.frames.dumps import ContactFrame, ParticleFrame
from ligwf.analysis.granules.bonds import BondCriterion, identify_fast, identify_reference
from ligwf.analysis.foreign import ForeignRun
from ligwf.analysis.granules.bridge_law import Liquid
from ligwf.cli import analyse_dumps
from ligwf.engine.render import render
from ligwf.errors import ConfigError
from ligwf.scene.scaled import ScaledScene
from ligwf.scene.scaling import Rule
from ligwf.scene.stability import preflight
from ligwf.scene.workflow import load_workflow

from toy_constant import ToySettings  # importing it registers the model
from helpers import DRUM
from liquid_checks import assert_forces_scale_as_rule

TOY = ["scene.liquid.model=toy_constant"]


def toy_case(extra=(), case_id="cg2-weber-r0"):
    wf = load_workflow(DRUM, TOY + list(extra))
    return next(c for c in wf.cases if c.case_id == case_id)


def test_scene_validates_with_the_model_and_its_own_limits():
    assert toy_case().scene.liquid.model == "toy_constant"
    with pytest.raises(ConfigError, match="toy law needs < 90 deg"):
        load_workflow(DRUM, TOY + ["scene.liquid.contact_angle_deg=120"])


@pytest.mark.parametrize("rule,power", [(Rule.WEBER, 2), (Rule.BOND, 3), (Rule.NONE, 1)])
def test_cg_rules_scale_its_force(rule, power):
    assert_forces_scale_as_rule(toy_case().scene, 3, rule, power)


def test_renders_its_lines():
    s = toy_case().scaled()
    text = render(s)["in.liggghts"]
    assert "cohesion sjkr" in text
    assert "fix lq_ced all property/global cohesionEnergyDensity peratomtypepair 2 " in text
    assert "surfaceTension" not in text and "f_surfaceLiquidContent" not in text


def test_preflight_runs_on_it():
    rep = preflight(toy_case().scaled(), "toy")
    assert rep.scales.capillary_overlap is not None and rep.scales.rupture_distance > 0
    assert "capillary_overlap" in {f.check for f in rep.findings}


@pytest.mark.parametrize("need_force", [False, True])
def test_granules_reference_and_compiled_agree(need_force):
    rng = np.random.default_rng(3)
    n, r = 60, 5e-4
    ids = np.arange(1, n + 1)
    vel = np.tile([0.1, 0.0, 0.0], (n, 1)) + rng.normal(0, 0.03, (n, 3))
    p = ParticleFrame(Path("toy"), 0, 0.0, ids, np.ones(n, np.int32),
                      rng.uniform(0, 0.01, (n, 3)), vel, np.full(n, r), np.full(n, 0.02))
    a = rng.integers(0, n, 150)
    b = (a + rng.integers(1, n, 150)) % n
    delta = rng.uniform(-2.5e-4, 2e-5, 150)          # rupture is ~1.6e-4 m here
    c = ContactFrame(Path("toy"), 0, ids[np.minimum(a, b)], ids[np.maximum(a, b)], delta)
    liquid = Liquid.from_scaled(toy_case().scaled())
    crit = BondCriterion(1e-9 if need_force else 0.0, 30.0)
    ref = identify_reference(p, c, liquid, crit, 1, 0.01)
    fast = identify_fast(p, c, liquid, crit, 1, 0.01, need_force=need_force)
    assert 0 < len(fast.i) < len(c)
    np.testing.assert_array_equal(ref.i, fast.i)
    np.testing.assert_array_equal(ref.labels, fast.labels)
    np.testing.assert_array_equal(ref.percolating, fast.percolating)
    if need_force:
        np.testing.assert_allclose(ref.force, fast.force, rtol=1e-12)


def test_its_own_setting_is_validated_per_model_in_one_line():
    assert toy_case(["scene.liquid.force_factor=2"]).scene.liquid.settings == ToySettings(
        force_factor=2.0)
    with pytest.raises(ConfigError) as info:
        load_workflow(DRUM, TOY + ["scene.liquid.force_factor=20"])
    assert str(info.value).splitlines()[-1] == (
        "scene.liquid.force_factor = 20: Input should be less than or equal to 10 "
        "(allowed range (0, 10])")
    with pytest.raises(ConfigError, match=r"scene.liquid.force_factor = 2: liquid model "
                       r"'washino' has no such setting \(only toy_constant has it\)"):
        load_workflow(DRUM, ["scene.liquid.model=washino", "scene.liquid.force_factor=2"])


def test_its_own_setting_reaches_the_record_the_input_and_the_analysis():
    base, strong = toy_case().scaled(), toy_case(["scene.liquid.force_factor=2"]).scaled()
    assert strong.to_dict()["force_factor"] == 2.0
    assert ScaledScene.from_dict(strong.to_dict()) == strong
    assert base.liquid is liquids.get("toy_constant")
    energy = {}
    for s in (base, strong):
        line = next(ln for ln in render(s)["in.liggghts"].splitlines() if "lq_ced" in ln)
        energy[s is strong] = float(line.split()[-1])
    assert energy[True] == pytest.approx(2 * energy[False], rel=1e-9)
    r, gap = 0.5 * base.d_min, 1e-6
    forces = [Liquid.from_scaled(s).law.capillary_force(
        r, r, gap, s.liquid_values.surface_tension, 0.3, 0.02) for s in (base, strong)]
    assert forces[1] == pytest.approx(2 * forces[0], rel=1e-12)
    law = Liquid.from_scaled(strong).law
    assert law.kernels.force.py_func(r, r, gap, 0.02, 0.3, np.cos(0.3), np.sin(0.3), 1.0) == \
        pytest.approx(law.capillary_force(r, r, gap, 0.02, 0.3, 0.02), rel=1e-12)


def test_the_foreign_dump_reader_takes_its_setting():
    run = ForeignRun("toy_constant", 0.02, 30.0, "scene", "y", 0.01, 1e-5, 0.02, 1.0,
                     {"force_factor": 3.0})
    assert run.facts("r").liquid.law.settings == ToySettings(force_factor=3.0)
    bad = ForeignRun("toy_constant", 0.02, 30.0, "scene", "y", 0.01, 1e-5, 0.02, 1.0,
                     {"force_factor": 0.0})
    with pytest.raises(ConfigError, match=r"--force-factor 0.0: .*allowed range \(0, 10\]"):
        bad.facts("r")

    parser = argparse.ArgumentParser()
    analyse_dumps.register(parser.add_subparsers())
    args = parser.parse_args(["analyse-dumps", "dumps", "--liquid", "toy_constant",
                              "--angle-convention", "scene", "--periodic-axis", "none",
                              "--dt", "1e-5", "--force-factor", "3"])
    assert 3.0 in vars(args).values()       # an option made from the toy's settings class
