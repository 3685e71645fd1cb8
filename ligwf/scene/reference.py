"""The workflow file's JSON Schema and reference, generated from its models.

One source for three readers: the pydantic models of the workflow's blocks
(:data:`BLOCKS`: ``scene:`` :class:`~ligwf.scene.model.Scene`, ``sweep:``
:class:`~ligwf.scene.workflow.Sweep` plus its scene-field lists, ``analysis:``
:class:`~ligwf.scene.settings.AnalysisSettings`, ``accept:``
:class:`~ligwf.scene.accept.AcceptSettings`) give every key its description, default
and allowed range; :data:`UNITS` gives every number its unit. :func:`workflow_schema` is
the JSON Schema (draft 2020-12) a YAML editor reads (``# yaml-language-server:
$schema=...`` on a workflow's first line: completion, hover text, range checks);
:func:`reference_markdown` is ``docs/workflow_reference.md``. ``ligwf schema`` prints or
writes both; ``tests/test_schema*.py`` regenerates them against the committed files and
validates the shipped workflows with the schema.

What JSON Schema cannot say (cross-field rules: fractions summing to 1, lifters that fit,
one of ``rpm`` / ``froude``, a dump interval within the run, model-specific liquid limits)
the models still check when the workflow is loaded; the reference lists those rules.
"""

from __future__ import annotations

import json
import re
from typing import Any

from pydantic import BaseModel
from pydantic.fields import FieldInfo

from ligwf import liquids
from ligwf.scene.accept import AcceptSettings
from ligwf.scene.liquid import Liquid
from ligwf.scene.model import MAX_DUMPS, Scene
from ligwf.liquids.base import MAX_LIQUID_CONTENT
from ligwf.scene.settings import AnalysisSettings
from ligwf.scene.stability import CLOSED_MIN, SLICE_MIN, SLICE_WARN
from ligwf.scene.workflow import MAX_CASES, MAX_REPLICAS, Sweep

#: (top-level key, model, required) of the workflow file, in file order
BLOCKS: tuple[tuple[str, type[BaseModel], bool], ...] = (
    ("scene", Scene, True), ("sweep", Sweep, False), ("analysis", AnalysisSettings, False),
    ("accept", AcceptSettings, False))

#: unit of every numeric workflow field, by ``Model.field`` (``1``: dimensionless ratio or
#: fraction; ``count``: a whole number of things; ``id``: a seed, no quantity). A new
#: numeric field needs its line here (``tests/test_schema.py`` names the missing one).
UNITS: dict[str, str] = {
    "Lifters.count": "count", "Lifters.height": "m", "Lifters.width_deg": "deg",
    "Drum.diameter": "m", "Drum.length": "m", "Drum.wall_friction": "1",
    "Drum.wall_restitution": "1",
    "Particles.density": "kg/m^3", "Particles.youngs_modulus": "Pa",
    "Particles.poisson_ratio": "1", "Particles.restitution": "1", "Particles.friction": "1",
    "Particles.rolling_friction": "1",
    "FlowMatch.friction": "1",
    "FlowMatch.rolling_friction": "1",
    "SizeClass.diameter": "m", "SizeClass.diameter_range": "m", "SizeClass.bins": "count",
    "SizeClass.fraction": "1",
    "Liquid.surface_tension": "N/m", "Liquid.contact_angle_deg": "deg",
    "Liquid.viscosity": "Pa s", "Liquid.liquid_content": "1",
    "Liquid.min_separation_ratio": "1", "Liquid.max_separation_ratio": "1",
    "WetGranules.count": "count", "WetGranules.radius": "m",
    "WetGranules.liquid_content": "1",
    "Rotation.rpm": "1/min", "Rotation.froude": "1",
    "Process.fill_fraction": "1", "Process.particle_count": "count",
    "Process.settle_time": "s", "Process.run_time": "s",
    "Numerics.dt_rayleigh_fraction": "1", "Numerics.dt": "s", "Numerics.dump_interval": "s",
    "Numerics.thermo_interval": "s", "Numerics.restart_interval": "s",
    "Numerics.packing_fraction": "1", "Numerics.skin_ratio": "1", "Numerics.seed": "id",
    "Sweep.cg_levels": "1", "Sweep.replicas": "count", "Sweep.control_cg_levels": "1",
    "AnalysisSettings.steady_after": "1", "AnalysisSettings.hold_time": "s",
    "AnalysisSettings.min_bridge_force": "N", "AnalysisSettings.min_relative_force": "1",
    "AnalysisSettings.max_velocity_angle": "deg", "AnalysisSettings.flow_radius": "1",
    "AnalysisSettings.resolution": "1", "AnalysisSettings.community_seed": "id",
    "AnalysisSettings.bins_per_decade": "count", "AnalysisSettings.min_particles": "count",
    "AnalysisSettings.error_band": "1", "AnalysisSettings.bootstrap": "count",
    "AnalysisSettings.seed": "id", "AnalysisSettings.sensitivity_frames": "count",
    "AnalysisSettings.field_kernel": "1",
    "AnalysisSettings.surface_strip": "m",
    "AcceptSettings.angle_deg": "deg", "AcceptSettings.profile_error": "1",
    "AcceptSettings.rigid_share": "1", "AcceptSettings.flowing_layer": "1",
    "AcceptSettings.gsd_error": "1", "AcceptSettings.field_error": "1",
}

#: the sweep's scene-field lists (``sweep: {scene.process.rotation.rpm: [20, 30]}``)
SCENE_LIST_PATTERN = r"^scene\."
SCHEMA_ID = "https://github.com/ligwf/ligwf/docs/workflow.schema.json"

#: what the models check beyond one key's range (the reference lists it under its block)
CROSS_FIELD_RULES: dict[str, tuple[str, ...]] = {
    "scene": (
        "`drum.lifters`: `count * width_deg` < 360 deg; with lifters, `height` in "
        "[1e-6 m, drum radius).",
        "`particles.size_distribution`: each class has exactly one of `diameter` or "
        "`diameter_range` ([min, max] with 1e-6 m <= min < max <= 1 m); the number "
        "fractions sum to 1.",
        "`liquid`: `placement: granules` needs `wet_granules`, `uniform` refuses it; each "
        "liquid model (`scene.liquid.model`) checks its own limits.",
        f"`liquid.liquid_content` <= {MAX_LIQUID_CONTENT:g} (pendular bridges).",
        "`process.rotation`: exactly one of `rpm` or `froude`.",
        "`numerics.dump_interval` <= `process.run_time`; `numerics.thermo_interval` <= the "
        "run time and the free fall across the drum; at most "
        f"{MAX_DUMPS:,} dumps per run.",
        "`analysis.contact_dumps: true` needs a wet liquid model.",
    ),
    "sweep": (
        "`cg_levels` >= 1; `per_cg` and `control_cg_levels` only name levels of `cg_levels`.",
        f"`replicas` in [1, {MAX_REPLICAS}] per CG level; the sweep expands to at most "
        f"{MAX_CASES:,} cases.",
        "`scene.<path>: [values]`: any scene field as a non-empty list; the lists form a "
        "cartesian product, each combination one sweep group.",
        "`controls` needs a wet scene; one rule on a dry scene.",
    ),
    "analysis": ("`steady_after`: `auto` or a fraction in [0, 1).",),
    "accept": ("`null` leaves a criterion out of the budget; the signed criteria (angle, "
               "rigid share, flowing layer) are held to +-tolerance by two one-sided tests "
               "and the CG1 noise floor never widens a tolerance; `gsd_error` "
               "counts only where the granules beat their cohesionless control.",),
}


def _code_checked(defs: dict[str, Any]) -> None:
    """The single-key limits the workflow code checks outside the models' fields (CG
    levels >= 1, replica counts, ``steady_after`` in [0, 1)), stated in the schema too."""
    sweep = defs["Sweep"]["properties"]
    for key in ("cg_levels", "control_cg_levels"):
        sweep[key]["items"]["minimum"] = 1
    for option in sweep["replicas"]["anyOf"]:
        target = option.get("additionalProperties", option)
        target.update(minimum=1, maximum=MAX_REPLICAS)
    steady = defs["AnalysisSettings"]["properties"]["steady_after"]
    steady["anyOf"] = [{"type": "number", "minimum": 0, "exclusiveMaximum": 1},
                       {"const": "auto", "type": "string"}]


def shipped_liquid_models() -> list[str]:
    """The liquid models ligwf ships (a model registered from elsewhere, such as the
    tests' toy model, is not part of the published schema)."""
    return [n for n in liquids.names()
            if type(liquids.get(n)).__module__.startswith("ligwf.liquids.")]


def liquid_settings() -> dict[str, tuple[type[BaseModel], FieldInfo]]:
    """The shipped liquid models' own settings (keys of the ``liquid:`` block only some
    models have): key -> (the settings class that declares it first, its field)."""
    out: dict[str, tuple[type[BaseModel], FieldInfo]] = {}
    for name in shipped_liquid_models():
        own = liquids.get(name).settings_type
        for key, info in own.model_fields.items():
            out.setdefault(key, (own, info))
    return out


# each model's settings declare their unit (``json_schema_extra={"unit": ...}``)
UNITS.update({f"Liquid.{key}": (info.json_schema_extra or {}).get("unit", "")  # type: ignore
              for key, (_, info) in liquid_settings().items()})


def _model_schema(model: type[BaseModel]) -> tuple[dict[str, Any], dict[str, Any]]:
    """(the model's schema, its nested definitions) with ``$ref`` into ``#/$defs``."""
    schema = model.model_json_schema(ref_template="#/$defs/{model}", mode="validation")
    return schema, schema.pop("$defs", {})


def _annotate(name: str, schema: dict[str, Any]) -> None:
    """Add the unit of each numeric property (``unit`` and in the title) and the liquid
    model names (an enum: the registry's names)."""
    for field, prop in schema.get("properties", {}).items():
        unit = UNITS.get(f"{name}.{field}")
        if unit is not None:
            prop["unit"] = unit
            if unit not in ("1", "count", "id"):
                prop["title"] = f"{prop.get('title', field)} [{unit}]"
        if name == "Liquid" and field == "model":
            prop["enum"] = shipped_liquid_models()


def workflow_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a workflow file, from :data:`BLOCKS`."""
    defs: dict[str, Any] = {}
    props: dict[str, Any] = {
        "name": {"type": "string", "minLength": 1, "maxLength": 80, "default": "study",
                 "title": "Name", "description": "study name (also the scene's name); no "
                 "quotes, '#', '$', '&' or control characters"},
        "description": {"type": "string", "title": "Description",
                        "description": "free text, kept in the study record"}}
    for key, model, _ in BLOCKS:
        schema, nested = _model_schema(model)
        defs.update(nested)
        defs[model.__name__] = schema
        props[key] = {"$ref": f"#/$defs/{model.__name__}"}
    for key, (own, _) in liquid_settings().items():      # after the block's own keys
        defs["Liquid"]["properties"][key] = _model_schema(own)[0]["properties"][key]
    for name, schema in defs.items():
        _annotate(name, schema)
    _code_checked(defs)
    defs["Sweep"]["patternProperties"] = {SCENE_LIST_PATTERN: {
        "type": "array", "minItems": 1, "title": "Scene-field list",
        "description": "any scene field (its path after scene.) as a list of values: one "
        "sweep group per combination"}}
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "$id": SCHEMA_ID,
            "title": "ligwf workflow",
            "description": "A ligwf study: the CG1 scene, the sweep over CG levels, rules, "
                           "replicas and scene values, and the analysis settings "
                           "(docs/workflow_reference.md).",
            "type": "object", "additionalProperties": False,
            "required": [k for k, _, req in BLOCKS if req], "properties": props,
            "$defs": dict(sorted(defs.items()))}


def schema_text() -> str:
    """:func:`workflow_schema` as the committed ``docs/workflow.schema.json`` text."""
    return json.dumps(workflow_schema(), indent=2, sort_keys=False) + "\n"


# ---------------------------------------------------------------------------------------
# the markdown reference
# ---------------------------------------------------------------------------------------

def _resolve(schema: dict[str, Any], defs: dict[str, Any]) -> dict[str, Any]:
    ref = schema.get("$ref")
    return _resolve(defs[ref.rsplit("/", 1)[-1]], defs) if ref else schema


def _object_of(prop: dict[str, Any], defs: dict[str, Any]) -> dict[str, Any] | None:
    """The object schema a property holds (directly, as ``X | None`` or as list items)."""
    for option in [prop, *prop.get("anyOf", []), prop.get("items", {})]:
        target = _resolve(option, defs) if option else {}
        if target.get("type") == "object" and "properties" in target:
            return target
    return None


def _type_text(prop: dict[str, Any], defs: dict[str, Any]) -> str:
    options = prop.get("anyOf", [prop])
    out = []
    for o in options:
        o = _resolve(o, defs)
        if "enum" in o:
            out.append(" \\| ".join(f"`{v}`" for v in o["enum"]))
        elif "const" in o:
            out.append(f"`{o['const']}`")
        elif o.get("type") == "array":
            item = o.get("items") or (o.get("prefixItems") or [{}])[0]
            out.append(f"list of {_type_text(item, defs)}")
        elif o.get("type") == "object" and "properties" in o:
            out.append(o.get("title", "mapping"))
        elif o.get("type") == "object":
            out.append("mapping")
        else:
            out.append(str(o.get("type", "any")))
    return " or ".join(out)


def _num(value: float | int) -> str:
    """A range bound: whole numbers in full (seeds up to 4294967295), others as %g."""
    return str(value) if isinstance(value, int) else f"{value:g}"


def _range_text(prop: dict[str, Any], defs: dict[str, Any]) -> str:
    for o in prop.get("anyOf", [prop]):
        o = _resolve(o, defs)
        if o.get("type") == "array" and "items" in o:
            o = {**_resolve(o["items"], defs), "minItems": o.get("minItems")}
        lo = (f"[{_num(o['minimum'])}" if "minimum" in o else
              f"({_num(o['exclusiveMinimum'])}" if "exclusiveMinimum" in o else None)
        hi = (f"{_num(o['maximum'])}]" if "maximum" in o else
              f"{_num(o['exclusiveMaximum'])})" if "exclusiveMaximum" in o else None)
        if lo or hi:
            return f"{lo or '(-inf'}, {hi or 'inf)'}"
    return ""


def _default_text(prop: dict[str, Any], required: bool) -> str:
    if required:
        return "required"
    if "default" not in prop:
        return "optional"
    return f"`{json.dumps(prop['default'])}`"


def _rows(path: str, schema: dict[str, Any], defs: dict[str, Any]) -> list[str]:
    rows = []
    required = set(schema.get("required", ()))
    for field, prop in schema.get("properties", {}).items():
        key = f"{path}.{field}"
        nested = _object_of(prop, defs)
        meaning = (prop.get("description") or _first_line((nested or {}).get("description"))
                   ).replace("\n", " ").replace("|", "\\|")
        rows.append(f"| `{key}` | {_default_text(prop, field in required)} | "
                    f"{_type_text(prop, defs)} | {prop.get('unit', '')} | "
                    f"{_range_text(prop, defs)} | {meaning} |")
        if nested is not None:
            suffix = "[]" if prop.get("type") == "array" else ""
            rows += _rows(key + suffix, nested, defs)
    for pattern, prop in schema.get("patternProperties", {}).items():
        rows.append(f"| `{path}.scene.<path>` | optional | list | | at least 1 value | "
                    f"{prop['description']} |")
    return rows


def _first_line(doc: str | None) -> str:
    """The first sentence line of a docstring (a nested model's one-line summary)."""
    text = (doc or "").strip().split("\n\n")[0].replace("\n", " ")
    return re.sub(r":\w+:`", "`", text).replace("``", "`")


HEAD = ["| key | required / default | type | unit | allowed range | meaning |",
        "|---|---|---|---|---|---|"]


def reference_markdown() -> str:
    """``docs/workflow_reference.md``: every key of every block with required / default,
    type, unit, allowed range and meaning, the cross-field rules, the slice rule and what
    ``scene.analysis.contact_dumps`` switches."""
    schema = workflow_schema()
    defs = schema["$defs"]
    lines = ["# Workflow reference", "",
             "Generated from the models by `ligwf schema --reference "
             "docs/workflow_reference.md` (do not edit; `tests/test_schema.py` fails when "
             "it is out of date). The same source gives the JSON Schema "
             "[`workflow.schema.json`](workflow.schema.json) (`ligwf schema --out "
             "docs/workflow.schema.json`): put `# yaml-language-server: "
             "$schema=<path or URL of workflow.schema.json>` on a workflow's first line and "
             "a YAML editor completes keys and checks ranges. Units are SI (`1`: a ratio "
             "or fraction, `count`: a whole number, `id`: a seed); ranges are closed `[` / "
             "open `(`.", "",
             "## Top level", "", *HEAD]
    for key in ("name", "description"):
        p = schema["properties"][key]
        lines.append(f"| `{key}` | {_default_text(p, False)} | string | | | "
                     f"{p['description']} |")
    for key, model, req in BLOCKS:
        lines.append(f"| `{key}` | {'required' if req else 'optional'} | mapping | | | "
                     f"{_first_line(model.__doc__)} |")
    for key, model, _ in BLOCKS:
        lines += ["", f"## `{key}:`", "", _first_line(model.__doc__), "",
                  *HEAD, *_rows(key, defs[model.__name__], defs), "",
                  "Checked beyond one key's range:", "",
                  *[f"- {rule}" for rule in CROSS_FIELD_RULES.get(key, ())]]
    lines += ["", "## The slice rule", "",
              f"A periodic drum (`scene.drum.periodic: true`) simulates a slice of length "
              f"`scene.drum.length` along the axis. Per case, the pre-flight divides it by "
              f"the largest scaled particle diameter (CG-n particles are n times larger): "
              f"below {SLICE_MIN:g} a particle touches its own periodic image (refused), "
              f"below {SLICE_WARN:g} the slice constrains the flow (warned: 3 CG3 diameters "
              f"deviate, 6 agree); a closed drum needs {CLOSED_MIN:g} diameters between its "
              "end caps (refused below). A CG level that needs a longer slice gets its own "
              "`sweep.per_cg.<n>: {drum.length: ...}`; speedups compare per original "
              "particle, so slices of different length stay on one footing.", "",
              "## What `scene.analysis.contact_dumps` switches", "",
              "`true` adds contact dumps (`dump local/gran/vtk` of `compute pair/gran/local`) "
              "to the LIGGGHTS input, so it is part of the scene and of its hash, and needs a "
              "wet liquid model. With it, `ligwf analyse` runs the granule stage (granules, "
              "frames, GSD, pooling, kinetics, sensitivity and controls tables, the `.pvd` "
              "series with a granule id per particle); with `false` (default) the runs write "
              "no contact dumps and the study gets the flow metrics only, with a record "
              "saying why there is no granule table. How granules are defined is the "
              "study's `analysis:` block (`analysis.granules`: communities, components or "
              "held), which changes the analysis, never the runs. Its old name "
              "`scene.analysis.granules` is still read, with a warning naming the new "
              "one.", ""]
    return "\n".join(lines)


def model_fields(model: type[BaseModel] | None = None, prefix: str = ""
                 ) -> list[tuple[str, str]]:
    """(dotted key, ``Model.field``) of every field of the workflow models, nested models
    included (list items as ``key[]``): what the schema and the reference must cover."""
    import typing

    if model is None:
        return [f for key, m, _ in BLOCKS for f in model_fields(m, key)]
    out = []
    fields = dict(model.model_fields)
    if model is Liquid:     # the models' own settings, not the field that carries them
        del fields["settings"]
        fields.update({k: info for k, (_, info) in liquid_settings().items()})
    for name, info in fields.items():
        key = f"{prefix}.{name}"
        out.append((key, f"{model.__name__}.{name}"))
        stack, seen = [info.annotation], set()
        while stack:
            a = stack.pop()
            if isinstance(a, type) and issubclass(a, BaseModel) and a not in seen:
                seen.add(a)
                many = typing.get_origin(info.annotation) in (tuple, list)
                out += model_fields(a, key + ("[]" if many else ""))
            stack += list(typing.get_args(a))
    return out

