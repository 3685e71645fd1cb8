"""ligwf.scene.reference and ``ligwf schema``: the workflow's JSON Schema and reference are
generated from the models, committed in docs/ and kept in step with them; the schema
accepts every shipped workflow and refuses what the models refuse where JSON Schema can
say it."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import jsonschema
import pytest

from helpers import ROOT
from ligwf.cli.main import main
from ligwf.errors import ConfigError
from ligwf.scene.reference import (UNITS, model_fields, reference_markdown, schema_text,
                                   workflow_schema)
from ligwf.scene.workflow import expand
from ligwf.yamlio import read_yaml_mapping

DOCS = ROOT / "docs"
SCHEMA_FILE = DOCS / "workflow.schema.json"
REFERENCE_FILE = DOCS / "workflow_reference.md"
#: workflow files of the repository (stability.yaml is a stress-suite file, not a workflow)
WORKFLOWS = sorted(p for p in [*(ROOT / "workflows").glob("*.yaml"),
                               *(ROOT / "tests" / "workflows").glob("*.yaml")]
                   if p.name != "stability.yaml")
REGENERATE = ("ligwf schema --out docs/workflow.schema.json --reference "
              "docs/workflow_reference.md --dictionary docs/data_dictionary.md")


@pytest.fixture(scope="module")
def validator():
    schema = workflow_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def test_committed_schema_and_reference_are_the_generated_ones():
    assert SCHEMA_FILE.read_text() == schema_text(), f"regenerate: {REGENERATE}"
    assert REFERENCE_FILE.read_text() == reference_markdown(), f"regenerate: {REGENERATE}"


def _schema_properties(schema: dict, path: str, out: set[str]) -> None:
    defs = schema.get("$defs", {})

    def walk(node: dict, where: str) -> None:
        node = defs[node["$ref"].rsplit("/", 1)[-1]] if "$ref" in node else node
        for key, prop in node.get("properties", {}).items():
            out.add(f"{where}.{key}")
            for option in [prop, *prop.get("anyOf", [])]:
                if "$ref" in option or "properties" in option:
                    walk(option, f"{where}.{key}")
                if "items" in option and ("$ref" in option["items"]
                                          or "properties" in option["items"]):
                    walk(option["items"], f"{where}.{key}[]")

    walk(schema, path)


def test_every_model_field_is_in_the_schema_and_the_reference():
    fields = model_fields()
    assert len(fields) > 60
    in_schema: set[str] = set()
    _schema_properties(workflow_schema(), "", in_schema)
    text = reference_markdown()
    for key, _ in fields:
        assert f".{key}" in in_schema, key
        assert f"| `{key}` |" in text, key


def test_every_numeric_field_has_a_unit_and_a_meaning():
    """A new number without a unit (or any field without a description) fails here, naming
    it: add its unit to ligwf.scene.reference.UNITS, its description to the model."""
    schema = workflow_schema()
    for name, node in schema["$defs"].items():
        if "properties" not in node:
            continue
        for field, prop in node["properties"].items():
            kinds = {o.get("type") for o in [prop, *prop.get("anyOf", [])]}
            kinds |= {o.get("items", {}).get("type") for o in [prop, *prop.get("anyOf", [])]}
            if kinds & {"number", "integer"}:
                assert f"{name}.{field}" in UNITS, f"{name}.{field}: no unit in UNITS"
                assert prop.get("unit") == UNITS[f"{name}.{field}"]
            nested = "$ref" in prop or any("$ref" in o for o in prop.get("anyOf", []))
            assert prop.get("description") or nested, f"{name}.{field}: no description"
    assert not set(UNITS) - {f"{m}" for _, m in model_fields()}, "a unit of no field"


@pytest.mark.parametrize("path", WORKFLOWS, ids=lambda p: p.name)
def test_shipped_workflows_validate_against_the_schema(path, validator):
    raw = read_yaml_mapping(path, "workflow")
    expand(copy.deepcopy(raw))                       # the models accept it ...
    errors = [f"{'.'.join(map(str, e.path))}: {e.message}" for e in validator.iter_errors(raw)]
    assert not errors                                # ... and so does the schema


def _set(raw: dict, dotted: str, value) -> dict:
    raw = copy.deepcopy(raw)
    node = raw
    *parents, last = dotted.split(".")
    for p in parents:
        node = node.setdefault(p, {})
    node[last] = value
    return raw


@pytest.mark.parametrize("key,value", [
    ("scene.process.fill_fraction", 0.9),
    ("scene.particles.density", "2500"),
    ("scene.particles.poisson_ratio", 0.5),
    ("scene.drum.axis", "w"),
    ("scene.drum.lifters.count", 361),
    ("scene.liquid.model", "water"),
    ("scene.liquid.liquid_content", 0.3),
    ("scene.numerics.typo", 1),
    ("sweep.cg_levels", [0.5, 2]),
    ("sweep.rules", ["weber", "froude"]),
    ("sweep.replicas", 0),
    ("sweep.controls", ["dry"]),
    ("analysis.steady_after", 1.5),
    ("analysis.granules", "clusters"),
    ("analysis.bins_per_decade", 0),
    ("accept.angle_deg", -1.0),
    ("accept.gsd_level", 0.2),
    ("extra", 1),
])
def test_a_bad_value_is_refused_by_the_models_and_the_schema(key, value, validator):
    raw = _set(read_yaml_mapping(ROOT / "workflows" / "demo.yaml", "workflow"), key, value)
    with pytest.raises(ConfigError):
        expand(copy.deepcopy(raw))
    assert list(validator.iter_errors(raw)), f"{key} = {value!r} passes the schema"


def test_reference_states_units_ranges_defaults_the_slice_rule_and_the_granule_switch():
    text = reference_markdown()
    assert "| `scene.drum.diameter` | required | number | m | [0.001, 10] |" in text
    assert "| `scene.process.fill_fraction` | required | number | 1 | [0.01, 0.7] |" in text
    assert "| `analysis.resolution` | `0.002` |" in text
    assert "## The slice rule" in text and "below 6" in text
    assert "## What `scene.analysis.contact_dumps` switches" in text
    assert "contact dumps" in text


def test_cli_prints_and_writes_the_schema(tmp_path, capsys):
    assert main(["schema"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed == workflow_schema()
    out, ref, dic = tmp_path / "w.json", tmp_path / "ref.md", tmp_path / "dict.md"
    assert main(["schema", "--out", str(out), "--reference", str(ref),
                 "--dictionary", str(dic)]) == 0
    assert out.read_text() == schema_text() and ref.read_text() == reference_markdown()
    assert dic.read_text().startswith("# Data dictionary")


def test_cli_refuses_a_file_in_a_missing_folder_before_writing(tmp_path, capsys):
    ok = tmp_path / "ok.json"
    assert main(["schema", "--out", str(ok), "--reference",
                 str(tmp_path / "no" / "ref.md")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "does not exist" in err[-1] and "Traceback" not in "".join(err)
    assert not ok.exists()
