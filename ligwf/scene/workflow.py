"""Workflows: a YAML file with ``scene:``, ``sweep:`` and ``analysis:`` blocks, expanded
into cases.

```yaml
name: demo
scene: {...}                  # a ligwf.scene.model.Scene, CG1 units
sweep:
  cg_levels: [1, 2, 3]
  rules: [weber, bond]
  replicas: {1: 1, 2: 3, 3: 3}   # or a single number for every CG level
  scene.process.rotation.rpm: [20, 30]   # any scene field as a list
  per_cg: {2: {process.run_time: 6.0}}    # scene fields for one CG level only
analysis: {steady_after: 0.25, max_velocity_angle: 30}   # ligwf.scene.settings
accept: {angle_deg: 1.0, profile_error: 0.1}   # the error budget, ligwf.scene.accept
```

CLI overrides (``--set scene.drum.lifters.count=12``) are applied to the raw mapping before
validation, so they are checked exactly like the file. Values are parsed as YAML.
A CG1 case is the same under every rule, so it is run once (rule ``none``).
"""

from __future__ import annotations

import copy
import dataclasses
import itertools
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Mapping, Sequence

from pydantic import Field, TypeAdapter, ValidationError

from ligwf.errors import ConfigError
from ligwf.yamlio import line_break_problem, parse_yaml, read_yaml_mapping
from ligwf.scene.accept import AcceptSettings, build_accept_settings
from ligwf.scene.scaled import ScaledScene
from ligwf.scene.scaling import Rule, parse_rule, scale
from ligwf.scene.messages import format_validation_error, short_repr
from ligwf.scene.controls import FlowMatch, control_scene
from ligwf.scene.model import Scene, build_scene
from ligwf.scene.values import Frozen, SafeStr
from ligwf.scene.settings import AnalysisSettings, build_analysis_settings

_TOP_KEYS = {"name", "description", "scene", "sweep", "analysis", "accept"}
#: replicas per CG level and cases per study ligwf prepares (a typo such as 300000 replicas
#: would otherwise spend minutes validating before anything is said)
MAX_REPLICAS = 1000
MAX_CASES = 5000


class Sweep(Frozen):
    """What varies between the cases of a workflow (scene-field lists are kept apart)."""

    cg_levels: tuple[float, ...] = Field((1.0,), min_length=1, description="coarse-graining "
                                         "levels n (CG particles n times the diameter; 1: the "
                                         "original, the reference of every comparison)")
    rules: tuple[Rule, ...] = Field((Rule.WEBER,), min_length=1, description="scaling rules "
                                    "of the liquid-bridge forces at CG > 1 (CG1 runs once, "
                                    "rule none)")
    replicas: int | dict[float, int] = Field(1, description="seeds per case, or per CG level")
    per_cg: dict[float, dict[str, Any]] = Field(
        default_factory=dict, description="scene fields set for one CG level only, e.g. "
        "{2: {process.run_time: 6.0}} (more revolutions where they are cheap)")
    controls: tuple[Literal["cohesionless", "flow_matched"], ...] = Field(
        (), description="null controls run beside the cases: cohesionless = a twin of each "
        "case at control_cg_levels with surface tension and viscosity / 1000 (same seeds), "
        "a bed that should hold no granules; flow_matched = that twin with the particle "
        "friction and rolling friction of sweep.flow_match (a dry bed that flows like the "
        "wet one)")
    flow_match: FlowMatch | None = Field(
        None, description="particle friction and rolling friction of the flow_matched twin "
        "(ligwf calibrate-control finds them)")
    control_cg_levels: tuple[float, ...] = Field(
        (1.0,), min_length=1, description="CG levels whose cases get the control twins")

    def replicas_for(self, cg: float) -> int:
        if isinstance(self.replicas, int):
            return self.replicas
        return self.replicas.get(cg, 1)


@dataclass(frozen=True)
class Case:
    """One run: a scene (with its sweep values applied), a CG level, a rule and a replica."""

    index: int
    case_id: str
    scene: Scene
    cg: float
    rule: Rule
    replica: int
    varied: tuple[tuple[str, Any], ...] = ()

    def scaled(self) -> ScaledScene:
        return scale(self.scene, self.cg, self.rule, self.replica)


@dataclass(frozen=True)
class Workflow:
    """A validated workflow: ``raw``, the mapping as written (what the study record
    stores), and what it expands to: its cases, from the typed ``sweep`` over the
    ``scene_lists`` (swept scene fields and their values) and the ``base_scene``."""

    name: str
    description: str
    raw: dict[str, Any]
    cases: tuple[Case, ...]
    analysis: AnalysisSettings = AnalysisSettings()
    accept: AcceptSettings = AcceptSettings()
    sweep: Sweep = Sweep()
    scene_lists: tuple[tuple[str, tuple[Any, ...]], ...] = ()
    base_scene: Mapping[str, Any] = field(default_factory=dict, repr=False)

    def with_replicas(self, replicas: Mapping[float, int]) -> "Workflow":
        """The workflow with ``replicas[cg]`` replicas at those CG levels where that is
        more than it has (levels it does not run are ignored): the same expansion with
        more seeds, so every case it had comes back with its id, scene and seed, and a
        new replica is the case a workflow written with that many would have had. ``raw``
        stays the workflow as written (a sequential study's rounds add replicas to the
        study, not to its workflow); the limits of :data:`MAX_REPLICAS` and
        :data:`MAX_CASES` hold as for a written sweep."""
        counts = {cg: max(self.sweep.replicas_for(cg), int(replicas.get(cg, 0)))
                  for cg in self.sweep.cg_levels}
        sweep = self.sweep.model_copy(update={"replicas": counts})
        _check_replicas(sweep)
        _check_count(sweep, self.scene_lists)
        return dataclasses.replace(self, sweep=sweep, cases=_cases(
            dict(self.base_scene), sweep, self.scene_lists))


# ---------------------------------------------------------------------------------------
# overrides
# ---------------------------------------------------------------------------------------

def parse_override(text: str) -> tuple[str, Any]:
    """``a.b.c=value`` -> (path, YAML-parsed value)."""
    if "=" not in text:
        raise ConfigError(f"--set {text!r}: expected KEY=VALUE, e.g. scene.drum.lifters.count=12")
    key, _, value = text.partition("=")
    key = key.strip()
    if not key:
        raise ConfigError(f"--set {text!r}: empty key")
    if (why := line_break_problem(text)) is not None:
        raise ConfigError(f"--set {text!r}: {why}")
    parsed = parse_yaml(value, f"--set {key}: value {value!r}") if value.strip() else ""
    return key, parsed


def apply_override(raw: dict[str, Any], key: str, value: Any) -> None:
    """Set ``key`` (dotted) in the raw workflow mapping; sweep scene paths stay one key."""
    parts = key.split(".")
    if parts[0] not in _TOP_KEYS:
        raise ConfigError(f"--set {key}: unknown top-level key {parts[0]!r} "
                          f"(allowed: {', '.join(sorted(_TOP_KEYS))})")
    if parts[0] == "sweep" and len(parts) > 2:
        parts = ["sweep", ".".join(parts[1:])]
    node = raw
    for p in parts[:-1]:
        child = node.get(p)
        if child is None:
            child = node[p] = {}
        if not isinstance(child, dict):
            raise ConfigError(f"--set {key}: {p!r} is not a mapping")
        node = child
    node[parts[-1]] = value


# ---------------------------------------------------------------------------------------
# loading and expansion
# ---------------------------------------------------------------------------------------

def _set_path(data: dict[str, Any], path: str, value: Any) -> None:
    node = data
    parts = path.split(".")
    for p in parts[:-1]:
        if not isinstance(node.get(p), dict):
            node[p] = {} if node.get(p) is None else node[p]
            if not isinstance(node[p], dict):
                raise ConfigError(f"sweep: scene.{path}: {p!r} is not a mapping")
        node = node[p]
    node[parts[-1]] = value


def _slug(value: Any) -> str:
    text = re.sub(r"[^A-Za-z0-9.+-]+", "-", str(value)).strip("-")
    return text or "x"


def _fmt_cg(cg: float) -> str:
    return f"{cg:g}"


def _mapping(value: Any, field: str, what: str) -> dict[str, Any]:
    """``value`` as a mapping with string keys, or ConfigError naming ``field``."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise ConfigError(f"{field} = {short_repr(value)}: must be a mapping of {what}")
    for key in value:
        if not isinstance(key, str):
            raise ConfigError(f"{field}: key {key!r} is not a name")
    return value


def _split_sweep(sweep_raw: dict[str, Any]) -> tuple[Sweep, list[tuple[str, list[Any]]]]:
    known, varied = {}, []
    for key, value in _mapping(sweep_raw, "sweep", "sweep settings").items():
        if key.startswith("scene."):
            if not isinstance(value, list) or not value:
                raise ConfigError(f"sweep.{key} = {value!r}: a scene field in the sweep must "
                                  "be a non-empty list of values")
            varied.append((key.removeprefix("scene."), value))
        else:
            known[key] = value
    if "rules" in known and isinstance(known["rules"], list):
        for k, r in enumerate(known["rules"]):
            try:
                parse_rule(r)
            except ConfigError as exc:
                raise ConfigError(f"sweep.rules[{k}] {str(exc).removeprefix('rule ')}") from None
    try:
        sweep = Sweep.model_validate(known)
    except ValidationError as exc:
        raise ConfigError("invalid sweep:\n" + format_validation_error(exc, Sweep, "sweep")) from None
    levels = [(f"sweep.cg_levels[{k}]", cg) for k, cg in enumerate(sweep.cg_levels)]
    for where, cg in levels + [(f"sweep.per_cg.{cg:g}", cg) for cg in sweep.per_cg]:
        if cg < 1:
            raise ConfigError(f"{where} = {cg:g}: CG level is < 1 (allowed range [1, inf))")
    _check_replicas(sweep)
    stray = sorted(set(sweep.per_cg) - set(sweep.cg_levels))
    if stray:
        raise ConfigError(f"sweep.per_cg: CG level {stray[0]:g} is not in sweep.cg_levels "
                          f"{[float(c) for c in sweep.cg_levels]} (its settings would never "
                          "be used)")
    _check_count(sweep, varied)
    return sweep, varied


def _check_replicas(sweep: Sweep) -> None:
    reps = ([(f"sweep.replicas.{cg:g}", n) for cg, n in sweep.replicas.items()]
            if isinstance(sweep.replicas, dict) else [("sweep.replicas", sweep.replicas)])
    for where, n in reps:
        if not 1 <= n <= MAX_REPLICAS:
            raise ConfigError(f"{where} = {n}: allowed range [1, {MAX_REPLICAS}] "
                              "replicas per CG level")


def _check_count(sweep: Sweep, varied) -> None:
    count = math.prod(len(v) for _, v in varied) * sum(
        (1 if cg == 1 else len(set(sweep.rules))) * sweep.replicas_for(cg)
        for cg in set(sweep.cg_levels))
    if count > MAX_CASES:
        raise ConfigError(f"sweep expands to {count:,} cases (replicas x rules x CG levels x "
                          f"scene lists); allowed at most {MAX_CASES:,} per study: split it")


#: longest case folder name (file systems allow 255 bytes; the study path comes on top)
MAX_CASE_ID = 200


def _check_plain(value: Any, path: str) -> None:
    """Refuse what the JSON study record cannot hold (``!!timestamp``, ``!!binary``,
    ``!!set`` values): it would fail after the case folders were written."""
    if isinstance(value, dict):
        for key, item in value.items():
            if not isinstance(key, (str, int, float, bool)) and key is not None:
                raise ConfigError(f"{path}: key {short_repr(key)} is a "
                                  f"{type(key).__name__}; a key is a name or a number")
            _check_plain(item, f"{path}.{key}" if path else str(key))
    elif isinstance(value, (list, tuple)):
        for k, item in enumerate(value):
            _check_plain(item, f"{path}[{k}]")
    elif not isinstance(value, (str, int, float, bool)) and value is not None:
        raise ConfigError(f"{path} = {short_repr(value)}: a {type(value).__name__} is not a "
                          "workflow value (text, numbers, true/false, lists and mappings "
                          "are); quote it to keep it as text")


def _unique_case_ids(cases: list[Case]) -> None:
    """Two cases in one folder would overwrite each other: sweep values that differ only
    in what the folder name drops ('a b' and 'a-b', 0.0 and -0.0) are refused, naming both."""
    first: dict[str, Case] = {}
    for case in cases:
        if len(case.case_id) > MAX_CASE_ID:
            raise ConfigError(f"case folder {case.case_id[:60]}...: {len(case.case_id)} "
                              f"characters, allowed at most {MAX_CASE_ID}; shorten the swept "
                              "values")
        other = first.setdefault(case.case_id, case)
        if other is case:
            continue
        diff = [(p, a, b) for (p, a), (_, b) in zip(other.varied, case.varied)
                if repr(a) != repr(b)]
        what = "; ".join(f"sweep.scene.{p}: {a!r} and {b!r}" for p, a, b in diff) or \
            "two cases"
        raise ConfigError(f"{what} give the same case folder {case.case_id} (folder names "
                          "keep letters, digits and . + -): make the values differ there")


def comparison_warnings(wf: Workflow) -> list[str]:
    """Documented warnings about what the study can compare (``check`` and ``study`` print
    them; nothing is refused)."""
    levels = sorted({c.cg for c in wf.cases})
    if levels and 1.0 not in levels:
        shown = "[" + ", ".join(f"{c:g}" for c in levels) + "]"
        if len(levels) < 2:
            return [f"sweep.cg_levels = {shown}: no CG1 case and one CG level, so no CG-n "
                    "result can be compared with the original size (errors, size limit and "
                    "CG-n/CG1 ratios stay empty); add 1, or a second CG level to extrapolate "
                    "CG1 from, to sweep.cg_levels"]
        check = ("two levels cannot check the line: a third one tests it" if len(levels) < 3
                 else "the line is checked for lack of fit")
        return [f"sweep.cg_levels = {shown}: no CG1 case: each level is judged against the "
                f"CG1 value extrapolated from its rule's levels ({check}); the velocity "
                "profile, the continuum fields and the GSD are judged only against a real "
                "CG1 and stay not assessed"]
    cg1 = [c.replica for c in wf.cases
           if c.cg == 1.0 and CONTROL_KEY not in dict(c.varied)]   # twins are not replicas
    reps = 1 + max(cg1) if cg1 else 0
    if len(levels) > 1 and reps < 2:
        return [f"sweep.replicas = {reps} at CG1: the CG1 noise floor comes from one run's own "
                "scatter (indicative), and CG errors near it stay undecided; 2 or more CG1 "
                "replicas per group measure it (sweep.replicas: {1: 2, ...})"]
    return []


def expand(raw: dict[str, Any]) -> Workflow:
    """Validate a raw workflow mapping and expand it into its cases (pure)."""
    if not isinstance(raw, dict):
        raise ConfigError("a workflow file must be a YAML mapping with scene: and sweep:")
    _check_plain(raw, "")
    unknown = set(raw) - _TOP_KEYS
    if unknown:
        raise ConfigError(f"workflow: unknown key(s) {', '.join(sorted(map(str, unknown)))} "
                          f"(allowed: {', '.join(sorted(_TOP_KEYS))})")
    if raw.get("scene") is None:
        raise ConfigError(f"scene = {raw.get('scene')!r}: the workflow's scene: block is "
                          "missing or empty")
    name = raw.get("name", "study")
    try:
        TypeAdapter(SafeStr).validate_python(name)
    except ValidationError as exc:
        raise ConfigError(f"name = {name!r}: {exc.errors()[0]['msg']}") from None
    sweep, varied = _split_sweep(raw.get("sweep"))
    analysis = build_analysis_settings(raw.get("analysis") or {})
    accept = build_accept_settings(raw.get("accept"))

    base_scene = copy.deepcopy(_mapping(raw["scene"], "scene", "scene fields (drum:, "
                                        "particles:, liquid:, process:, ...)"))
    base_scene.setdefault("name", name)
    first = build_scene(base_scene)  # report errors of the base scene once, plainly
    if not first.liquid.wet and len(set(sweep.rules)) > 1 and any(c != 1 for c in sweep.cg_levels):
        raise ConfigError(f"sweep.rules = {[r.value for r in sweep.rules]}: on a dry scene "
                          f"(liquid.model {first.liquid.model}) every rule gives the same case; "
                          "sweep one rule")

    if sweep.controls and not first.liquid.wet:
        raise ConfigError(f"sweep.controls = {list(sweep.controls)}: the scene is dry (liquid.model "
                          f"{first.liquid.model}): it is its own cohesionless control")
    if "flow_matched" in sweep.controls and sweep.flow_match is None:
        raise ConfigError("sweep.controls = [..., flow_matched]: sweep.flow_match is missing "
                          "({friction: F, rolling_friction: R}; 'ligwf calibrate-control "
                          "WORKFLOW --out DIR' measures candidates and prints them)")
    if sweep.flow_match is not None and "flow_matched" not in sweep.controls:
        raise ConfigError(f"sweep.flow_match = {sweep.flow_match.model_dump()}: set, but "
                          f"sweep.controls = {list(sweep.controls)} has no flow_matched twin "
                          "to use it")
    stray = sorted(set(sweep.control_cg_levels) - set(sweep.cg_levels)) if sweep.controls else []
    if stray:
        raise ConfigError(f"sweep.control_cg_levels: CG level {stray[0]:g} is not in "
                          f"sweep.cg_levels {[float(c) for c in sweep.cg_levels]}")

    return Workflow(name=name, description=str(raw.get("description", "")), raw=raw,
                    cases=_cases(base_scene, sweep, varied), analysis=analysis,
                    accept=accept, sweep=sweep, scene_lists=tuple(
                        (path, tuple(values)) for path, values in varied),
                    base_scene=base_scene)


def _cases(base_scene: dict[str, Any], sweep: Sweep,
           varied: Sequence[tuple[str, Sequence[Any]]]) -> tuple[Case, ...]:
    """The cases of a validated sweep over the (validated) base scene, in the study's
    order: per combination of the swept scene values, per CG level, rule and replica,
    each followed by its control twins."""
    cases: list[Case] = []
    combos = itertools.product(*[vals for _, vals in varied]) if varied else [()]
    seen: set[tuple] = set()
    for combo in combos:
        data = copy.deepcopy(base_scene)
        for (path, _), value in zip(varied, combo):
            _set_path(data, path, value)
        base = build_scene(data)
        tag = "".join(f"_{path.split('.')[-1]}-{_slug(v)}" for (path, _), v in zip(varied, combo))
        for cg in sweep.cg_levels:
            if cg in sweep.per_cg:
                cg_data = copy.deepcopy(data)
                for path, value in sweep.per_cg[cg].items():
                    _set_path(cg_data, path.removeprefix("scene."), value)
                scene = build_scene(cg_data, prefix=f"sweep.per_cg.{cg:g} -> scene")
            else:
                scene = base
            rules = [Rule.NONE] if cg == 1 else list(sweep.rules)
            for rule in rules:
                for rep in range(sweep.replicas_for(cg)):
                    key = (tuple(map(str, combo)), cg, rule, rep)
                    if key in seen:
                        continue
                    seen.add(key)
                    case_id = f"cg{_fmt_cg(cg)}-{rule.value}-r{rep}{tag}"
                    values = tuple((p, v) for (p, _), v in zip(varied, combo))
                    cases.append(Case(len(cases), case_id, scene, float(cg), rule, rep, values))
                    if cg in sweep.control_cg_levels:
                        for control in sweep.controls:
                            cases.append(Case(len(cases), f"{case_id}_{control}",
                                              control_scene(scene, control, sweep.flow_match),
                                              float(cg), rule,
                                              rep, values + ((CONTROL_KEY, control),)))
    _unique_case_ids(cases)
    return tuple(cases)


#: the ``varied`` entry that marks a control twin (its own comparison group)
CONTROL_KEY = "control"
def load_workflow(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> Workflow:
    """Read a workflow YAML, apply ``--set`` overrides, validate and expand it."""
    raw = read_yaml_mapping(path, "workflow file")
    for text in overrides:
        apply_override(raw, *parse_override(text))
    return expand(raw)
