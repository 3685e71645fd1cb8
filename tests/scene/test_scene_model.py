"""Scene validation: bad input is refused with field, value and allowed range."""

from __future__ import annotations

import copy
import json

import pytest
import yaml

from ligwf.errors import ConfigError
from ligwf.scene.model import build_scene
from ligwf.scene.workflow import expand, load_workflow

from helpers import DRUM


def demo_raw() -> dict:
    return yaml.safe_load(DRUM.read_text())


def expect_error(raw: dict, *fragments: str) -> str:
    with pytest.raises(ConfigError) as info:
        expand(raw)
    msg = str(info.value)
    for frag in fragments:
        assert frag in msg, f"{frag!r} not in error message:\n{msg}"
    return msg


def with_value(path: str, value):
    raw = demo_raw()
    node = raw
    keys = path.split(".")
    for k in keys[:-1]:
        node = node[k]
    node[keys[-1]] = value
    return raw


def test_demo_is_valid():
    wf = load_workflow(DRUM)
    assert [c.case_id for c in wf.cases] == [
        "cg1-none-r0", "cg2-weber-r0", "cg2-bond-r0", "cg3-weber-r0", "cg3-bond-r0"]


@pytest.mark.parametrize("value", [0.0, -0.001])
def test_non_positive_size_refused(value):
    raw = with_value("scene.particles.size_distribution", [{"diameter": value, "fraction": 1.0}])
    expect_error(raw, "scene.particles.size_distribution[0].diameter", repr(value), "[1e-06, 1]")


def test_negative_drum_diameter_refused():
    expect_error(with_value("scene.drum.diameter", -0.05), "scene.drum.diameter", "-0.05", "[0.001, 10]")


def test_fractions_must_sum_to_one():
    raw = with_value("scene.particles.size_distribution",
                     [{"diameter": 1e-3, "fraction": 0.8}, {"diameter": 2e-3, "fraction": 0.3}])
    msg = expect_error(raw, "scene.particles.size_distribution: ", "sum to 1.1", "must sum to 1")
    assert "{" not in msg   # the field, not the whole particles block


@pytest.mark.parametrize("value", [0.0, 0.75, -0.1])
def test_fill_fraction_range(value):
    expect_error(with_value("scene.process.fill_fraction", value),
                 "scene.process.fill_fraction", repr(value), "[0.01, 0.7]")


def test_fill_fraction_upper_bound_accepted():
    expand(with_value("scene.process.fill_fraction", 0.7))


def test_lifter_height_must_be_below_radius():
    msg = expect_error(with_value("scene.drum.lifters.height", 0.025),
                       "scene.drum.lifters.height = 0.025", "< the drum radius 0.025",
                       "allowed range [1e-06, 0.025) m")
    assert "{" not in msg


@pytest.mark.parametrize("value", [-1, 181, 400])
def test_contact_angle_range(value):
    expect_error(with_value("scene.liquid.contact_angle_deg", value),
                 "scene.liquid.contact_angle_deg", repr(value), "[0, 180]")


@pytest.mark.parametrize("value", [0.5, 0, -2])
def test_cg_level_below_one_refused(value):
    expect_error(with_value("sweep.cg_levels", [1, value]), "sweep.cg_levels", "[1, inf)")


def test_unknown_rule_refused():
    expect_error(with_value("sweep.rules", ["weber", "reynolds"]), "reynolds", "weber", "bond")


def test_unknown_liquid_model_refused():
    expect_error(with_value("scene.liquid.model", "glue"), "scene.liquid.model", "glue",
                 "washino", "easo", "none")


@pytest.mark.parametrize("path", ["scene.drum.diamter", "scene.particles.densty",
                                  "scene.liquid.surface_tensoin", "scene.procss"])
def test_unknown_keys_are_typos(path):
    expect_error(with_value(path, 1.0), path, "unknown key")


def test_unknown_top_level_and_sweep_keys():
    raw = demo_raw()
    raw["scnee"] = {}
    expect_error(raw, "scnee")
    expect_error(with_value("sweep.cg_level", [1]), "sweep.cg_level", "unknown key")


@pytest.mark.parametrize("bad", ["demo\nshell rm -rf /", "a & b", "x$y", "name#c", "it's", 'say "hi"'])
def test_injection_refused_in_every_string(bad):
    expect_error(with_value("name", bad), "name")
    expect_error(with_value("scene.name", bad), "scene.name", "newline")


def test_rotation_needs_exactly_one_speed():
    expect_error(with_value("scene.process.rotation", {"rpm": 30, "froude": 0.1}),
                 "scene.process.rotation", "exactly one of rpm or froude")


def test_sweep_scene_field_must_be_list():
    raw = demo_raw()
    raw["sweep"]["scene.process.rotation.rpm"] = 20
    expect_error(raw, "sweep.scene.process.rotation.rpm", "list")


def test_sweep_over_scene_field_expands_cases():
    raw = demo_raw()
    raw["sweep"] = {"cg_levels": [1, 2], "rules": ["weber"], "replicas": {2: 2},
                    "scene.process.rotation.rpm": [20, 40]}
    wf = expand(raw)
    ids = [c.case_id for c in wf.cases]
    assert ids == ["cg1-none-r0_rpm-20", "cg2-weber-r0_rpm-20", "cg2-weber-r1_rpm-20",
                   "cg1-none-r0_rpm-40", "cg2-weber-r0_rpm-40", "cg2-weber-r1_rpm-40"]
    assert wf.cases[3].scene.process.rotation.rpm == 40
    # replicas differ by their insertion seeds only
    s0, s1 = wf.cases[1].scaled(), wf.cases[2].scaled()
    assert s0.fill.seeds != s1.fill.seeds and s0.numerics.dt == s1.numerics.dt


def test_set_override_applies_and_validates():
    wf = load_workflow(DRUM, ["scene.drum.lifters.count=6", "sweep.cg_levels=[2]"])
    assert wf.cases[0].scene.drum.lifters.count == 6
    with pytest.raises(ConfigError, match="scene.drum.lifters.count"):
        load_workflow(DRUM, ["scene.drum.lifters.count=-3"])
    with pytest.raises(ConfigError, match="unknown top-level key"):
        load_workflow(DRUM, ["scen.drum.length=1"])


def test_scene_is_frozen():
    scene = build_scene(copy.deepcopy(demo_raw()["scene"]))
    with pytest.raises(Exception):
        scene.drum.diameter = 1.0  # type: ignore[misc]


# --- issue 21: YAML 1.1 surprises, merge keys, dates, strict numbers ---

def _load_text(tmp_path, text: str, overrides=()):
    path = tmp_path / "wf.yaml"
    path.write_text(text)
    return load_workflow(path, overrides)


def test_yaml_merge_keys_are_accepted(tmp_path):
    text = DRUM.read_text() + (
        "  per_cg:\n"
        "    2: &slow {process.run_time: 0.6, numerics.dump_interval: 0.1}\n"
        "    3: {<<: *slow, numerics.dump_interval: 0.2}\n")
    wf = _load_text(tmp_path, text)
    by_cg = {c.cg: c.scene for c in wf.cases}
    assert by_cg[2.0].process.run_time == by_cg[3.0].process.run_time == 0.6
    # the mapping's own key overrides the merged one
    assert (by_cg[2.0].numerics.dump_interval, by_cg[3.0].numerics.dump_interval) == (0.1, 0.2)
    with pytest.raises(ConfigError, match="duplicate key"):
        _load_text(tmp_path, text.replace("numerics.dump_interval: 0.2}",
                                          "numerics.dump_interval: 0.2, "
                                          "numerics.dump_interval: 0.3}"))


def test_yaml_dates_stay_text(tmp_path):
    wf = _load_text(tmp_path, DRUM.read_text().replace(
        "description: Small wet drum with lifters, CG1 and We/Bo-scaled CG2 and CG3.",
        "description: 2024-01-01", 1))
    assert wf.description == "2024-01-01"
    json.dumps(wf.raw)   # the study record can hold it


@pytest.mark.parametrize("word, value", [("yes", True), ("no", False), ("on", True),
                                         ("off", False), ("true", True)])
def test_yaml_yes_no_words_only_fit_yes_no_fields(word, value):
    wf = load_workflow(DRUM, [f"scene.drum.periodic={word}"])
    assert wf.cases[0].scene.drum.periodic is value
    with pytest.raises(ConfigError, match="scene.particles.friction = "):
        load_workflow(DRUM, [f"scene.particles.friction={word}"])


def test_yaml_1_2_numbers():
    wf = load_workflow(DRUM, ["scene.particles.youngs_modulus=5e6", "scene.drum.lifters.count=6",
                              "scene.numerics.seed=10_007", "sweep.cg_levels=[1, 2]"])
    scene = wf.cases[0].scene
    assert scene.particles.youngs_modulus == 5e6 and scene.drum.lifters.count == 6
    assert scene.numerics.seed == 10007
    with pytest.raises(ConfigError, match="base-60 number 5400"):
        load_workflow(DRUM, ["scene.process.rotation.rpm=1:30:00"])


def test_whole_numbers_stand_for_floats():
    # strict about text and yes/no, not about 2500 vs 2500.0
    wf = load_workflow(DRUM, ["scene.particles.density=2500", "sweep.cg_levels=[1, 2]",
                              "scene.liquid.liquid_content=0.2"])
    assert wf.cases[0].scene.particles.density == 2500.0


def test_signed_zero_sweep_is_refused_not_collapsed():
    raw = demo_raw()
    raw["sweep"]["scene.particles.rolling_friction"] = [0.0, -0.0]
    expect_error(raw, "0.0 and -0.0", "same case folder")
    raw["sweep"]["scene.particles.rolling_friction"] = [0.0, 0.1]
    assert len({c.case_id for c in expand(raw).cases}) == len(expand(raw).cases) == 10


def test_model_level_errors_name_the_field_not_the_block():
    msg = expect_error(with_value("scene.liquid.max_liquid_content", 0.01),
                       "scene.liquid.max_liquid_content = 0.01", "liquid content")
    assert "{" not in msg
    msg = expect_error(with_value("scene.process.rotation", {"rpm": 30, "froude": 0.1}),
                       "scene.process.rotation: give exactly one")
    assert "{" not in msg
