"""washino's optional engine settings as scene settings: ``liquid.bridge_volume_fraction``
(LIGGGHTS ``lbVolumeFraction`` with ``modifyLbVolume on``) and ``liquid.max_liquid_content``
(``maxLiquidContent`` with ``limitLiquidContent on``): refusals, rendering (nothing at the
defaults), CG scaling (unchanged fractions) and the law ligwf's analysis applies (numpy and
numba alike). The engine's side: tests/engine/test_engine_bridge.py."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ligwf import liquids
from ligwf.analysis import granules_numba as gn
from ligwf.analysis.frames.dumps import ParticleFrame
from ligwf.analysis.granules.bridge_law import Liquid, content_of
from ligwf.engine.render import render
from ligwf.errors import ConfigError
from ligwf.liquids.washino import BRIDGE_VOLUME_FRACTION, WashinoSettings, bridge_volume
from ligwf.scene.scaling import scale
from ligwf.scene.workflow import load_workflow

from helpers import DRUM

WASHINO = ["scene.liquid.model=washino"]


def scene(*overrides: str):
    return load_workflow(DRUM, [*WASHINO, *overrides]).cases[0].scene


def refusal(*overrides: str) -> str:
    with pytest.raises(ConfigError) as info:
        load_workflow(DRUM, list(overrides))
    return str(info.value)


def test_default_written_out_is_the_default_case():
    """0.05 written out is the engine default: the same scaled record, input and law
    object as leaving it unset (scene hashes and outputs of existing studies unchanged)."""
    unset, explicit = scale(scene(), 2, "weber"), scale(
        scene(f"scene.liquid.bridge_volume_fraction={BRIDGE_VOLUME_FRACTION}"), 2, "weber")
    assert unset.to_dict() == explicit.to_dict()
    assert "bridge_volume_fraction" not in unset.to_dict()
    assert "max_liquid_content" not in unset.to_dict()
    assert render(unset) == render(explicit)
    text = render(unset)["in.liggghts"]
    assert "modifyLbVolume" not in text and "lbVolumeFraction" not in text
    assert "limitLiquidContent" not in text and "maxLiquidContent" not in text
    assert unset.liquid is liquids.get("washino") is explicit.liquid


def test_non_default_settings_are_rendered_with_their_switches():
    s = scale(scene("scene.liquid.bridge_volume_fraction=0.2",
                    "scene.liquid.max_liquid_content=0.1"), 1, "none")
    text = render(s)["in.liggghts"]
    pair = next(l for l in text.splitlines() if l.startswith("pair_style"))
    assert pair.endswith("cohesion washino/capillary/viscous modifyLbVolume on "
                         "limitLiquidContent on")
    assert "fix lq_lbvol all property/global lbVolumeFraction scalar 0.2\n" in text
    assert "fix lq_maxlc all property/global maxLiquidContent peratomtype 0.1 0.1\n" in text
    # the engine replaces maxSeparationDistanceRatio when capping: ligwf writes its value
    assert f"maxSeparationDistanceRatio scalar {s.liquid_values.max_separation_ratio:.12g}\n" in text


@pytest.mark.parametrize("overrides,field,value,allowed", [
    (["scene.liquid.bridge_volume_fraction=0"], "bridge_volume_fraction", "= 0:", "(allowed range (0, 1])"),
    (["scene.liquid.bridge_volume_fraction=1.5"], "bridge_volume_fraction", "= 1.5:", "(allowed range (0, 1])"),
    (["scene.liquid.max_liquid_content=0.5"], "max_liquid_content", "= 0.5:", "(allowed range (0, 0.2])"),
    (["scene.liquid.max_liquid_content=0.01"], "max_liquid_content", "= 0.01:", "(allowed range [0.02, 0.2])"),
])
def test_out_of_range_refused_in_one_line(overrides, field, value, allowed):
    msg = refusal(*WASHINO, *overrides)
    line = next(l for l in msg.splitlines() if field in l)
    assert "scene.liquid" in line and value in line and allowed in line, msg


def test_settings_of_other_models_refused():
    msg = refusal("scene.liquid.model=easo", "scene.liquid.bridge_volume_fraction=0.1")
    assert "scene.liquid.bridge_volume_fraction = 0.1" in msg and "'easo'" in msg
    assert "only washino" in msg
    msg = refusal("scene.liquid.model=easo", "scene.liquid.max_liquid_content=0.1")
    assert "scene.liquid.max_liquid_content = 0.1" in msg and "'easo'" in msg
    # a scene record of an older ligwf writes them as null for every model: still read
    easo = load_workflow(DRUM, ["scene.liquid.model=easo"]).cases[0].scene
    old = easo.model_dump(mode="json")
    old["liquid"].update(bridge_volume_fraction=None, max_liquid_content=None)
    assert type(easo).model_validate(old) == easo


def test_settings_are_one_value_written_as_keys_of_the_block():
    """The scene carries washino's settings as one value and writes them back as keys of
    ``liquid:`` (a scene record reads back to the same scene)."""
    sc = scene("scene.liquid.bridge_volume_fraction=0.2")
    assert sc.liquid.settings == WashinoSettings(bridge_volume_fraction=0.2)
    dumped = sc.model_dump(mode="json")["liquid"]
    assert dumped["bridge_volume_fraction"] == 0.2 and "settings" not in dumped
    assert type(sc).model_validate(sc.model_dump(mode="json")) == sc
    assert "scene.liquid.settings: unknown key" in refusal(*WASHINO,
                                                          "scene.liquid.settings={a: 1}")


def test_cap_refuses_a_separation_ratio_the_engine_would_overwrite():
    msg = refusal(*WASHINO, "scene.liquid.max_liquid_content=0.1",
                  "scene.liquid.max_separation_ratio=1.2")
    assert "max_separation_ratio = 1.2" in msg and "max_liquid_content = 0.1" in msg
    # a case's scene record writes every key, the ratio at its default too: it reads back
    capped = scene("scene.liquid.max_liquid_content=0.1")
    assert type(capped).model_validate(capped.model_dump(mode="json")) == capped


@pytest.mark.parametrize("n,rule,power", [(2, "weber", 2), (3, "bond", 3)])
def test_fractions_unchanged_by_cg_and_forces_scale_as_the_rule(n, rule, power):
    sc = scene("scene.liquid.bridge_volume_fraction=0.2", "scene.liquid.max_liquid_content=0.1")
    s1, sn = scale(sc, 1, "none"), scale(sc, n, rule)
    assert sn.liquid_values.settings == WashinoSettings(bridge_volume_fraction=0.2,
                                                        max_liquid_content=0.1)
    assert sn.liquid_values.max_separation_ratio == pytest.approx(s1.liquid_values.max_separation_ratio, rel=1e-12)
    theta = math.radians(sc.liquid.contact_angle_deg)
    for g in (0.0, 0.05, 0.1):
        f1, fn = (s.liquid.capillary_force(0.5 * s.d_min, 0.5 * s.d_min, g * 0.25 * s.d_min,
                                           s.liquid_values.surface_tension, theta, s.liquid_values.liquid_content)
                  for s in (s1, sn))
        assert fn / f1 == pytest.approx(n**power, rel=1e-9)


def test_law_follows_the_fraction_in_numpy_and_numba():
    r, gamma, theta, c = 5e-4, 0.024, math.radians(30), 0.02
    law = liquids.get("washino").configured(WashinoSettings(bridge_volume_fraction=0.2))
    assert law is liquids.get("washino").configured(           # one object per settings
        WashinoSettings(bridge_volume_fraction=0.2))
    assert law.bridge_volume(r, r, c, c) == pytest.approx(4 * bridge_volume(r, r, c, c))
    # the force at 0.2 is the default law's expression at the 0.2 bridge volume ...
    vol = float(bridge_volume(r, r, c, c, 0.2))
    expected = float(law.kernels.force.py_func(r, r, 7.5e-5, gamma, theta, math.cos(theta),
                                                math.sin(theta), vol))
    assert law.capillary_force(r, r, 7.5e-5, gamma, theta, c) == pytest.approx(expected,
                                                                                 rel=1e-12)
    assert expected > 1.5 * liquids.get("washino").capillary_force(r, r, 7.5e-5, gamma,
                                                                  theta, c)
    # ... and the compiled bond kernel gives the numpy force at either fraction
    v, radii, content = np.ones((2, 3)), np.full(2, r), np.full(2, c)
    for model in (liquids.get("washino"), law):
        _, _, _, force, _ = gn.bond_kernel(np.array([1]), np.array([2]), 1, v, radii, content,
                                           np.array([-7.5e-5]), *gn.law(model), gamma, theta,
                                           0.5, 0.0)
        assert force[0] == model.capillary_force(r, r, 7.5e-5, gamma, theta, c)


def test_analysis_applies_the_cases_fraction_and_cap():
    s = scale(scene("scene.liquid.bridge_volume_fraction=0.2",
                    "scene.liquid.max_liquid_content=0.1"), 1, "none")
    liquid = Liquid.from_scaled(s)
    own = WashinoSettings(bridge_volume_fraction=0.2, max_liquid_content=0.1)
    assert liquid.settings == own
    assert liquid.law is liquids.get("washino").configured(own)
    assert liquid.law.bridge_volume_fraction == 0.2
    assert Liquid.from_scaled(scale(scene(), 1, "none")).law is liquids.get("washino")

    frame = ParticleFrame(Path("particles_0.vtu"), 0, 0.0, np.arange(1, 4), np.ones(3, np.int32),
                          np.zeros((3, 3)), np.zeros((3, 3)), np.full(3, 5e-4),
                          np.array([0.02, 0.15, 0.1]))
    # the engine clips a content above the cap before it evaluates a pair: so does ligwf
    assert content_of(frame, liquid).tolist() == [0.02, 0.1, 0.1]
    assert content_of(frame, Liquid.from_scaled(scale(scene(), 1, "none"))).tolist() == [
        0.02, 0.15, 0.1]


def test_foreign_runs_are_analysed_at_their_fraction():
    """``ligwf analyse-dumps --bridge-volume-fraction``: dumps of a run with another
    lbVolumeFraction are analysed with it; refused for a model without one."""
    from ligwf.analysis.foreign import ForeignRun

    def run(liquid, fraction):
        own = {} if fraction is None else {"bridge_volume_fraction": fraction}
        return ForeignRun(liquid, 0.02, 30.0, "scene", "y", 0.01, 1e-5, None, 1.0, own)

    assert run("washino", 0.2).facts("r").liquid.law is liquids.get("washino").configured(
        WashinoSettings(bridge_volume_fraction=0.2))
    assert run("washino", None).facts("r").liquid.law is liquids.get("washino")
    with pytest.raises(ConfigError, match=r"--bridge-volume-fraction 0.2: liquid model 'easo'"):
        run("easo", 0.2).facts("r")
    with pytest.raises(ConfigError, match=r"--bridge-volume-fraction 1.5: .*allowed range \(0, 1\]"):
        run("washino", 1.5).facts("r")


def test_a_cap_at_the_content_cuts_bridges_at_the_laws_own_rupture_gap():
    """With max_liquid_content = liquid_content the engine's cut (the ratio it computes) is
    the law's own rupture gap of the pair: the pre-flight's bridge_cut ratio is 1; a short
    written ratio warns and names the cap as the other way out."""
    from ligwf.scene.stability import preflight

    def bridge_cut(*overrides):
        s = scale(scene(*overrides), 1, "none")
        return next(f for f in preflight(s).findings if f.check == "bridge_cut")

    capped = bridge_cut("scene.liquid.max_liquid_content=0.02")
    assert capped.value == pytest.approx(1.0, rel=1e-12) and capped.verdict == "ok"
    short = bridge_cut("scene.liquid.max_separation_ratio=1.02")
    assert short.verdict != "ok" and "or set max_liquid_content" in short.message
