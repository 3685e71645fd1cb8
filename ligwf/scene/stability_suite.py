"""The stress suite file: one base scene and named variants, each an ordinary workflow.

A workflow sweep is a cartesian product, so sweeping six axes of one tiny scene at once
would be thousands of cases. ``workflows/stability.yaml`` instead holds::

    name: stability
    base: {...}                       # a Scene (CG1), shared by every variant
    variants:
      stiffness:
        scene: {numerics: {dt: 1.0e-5}}         # deep-merged into the base scene
        sweep: {scene.particles.youngs_modulus: [1e6, 1e9, 1e12]}

Each variant becomes a workflow named ``<suite>-<variant>`` through
:func:`ligwf.scene.workflow.expand`, so it is validated, rendered and run exactly like any other
workflow; its cases live under ``<study>/<variant>/<case_id>``.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any


from ligwf.errors import ConfigError
from ligwf.yamlio import read_yaml_mapping
from ligwf.scene.workflow import Workflow, expand


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = copy.deepcopy(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def expand_suite(raw: dict[str, Any]) -> dict[str, Workflow]:
    """Variant name -> workflow, in file order (pure)."""
    if not isinstance(raw, dict) or "base" not in raw or "variants" not in raw:
        raise ConfigError("a stability suite is a mapping with base: (a scene) and variants:")
    unknown = set(raw) - {"name", "description", "base", "variants"}
    if unknown:
        raise ConfigError(f"stability suite: unknown key(s) {', '.join(sorted(unknown))}")
    name = str(raw.get("name", "stability"))
    out: dict[str, Workflow] = {}
    for variant, spec in (raw["variants"] or {}).items():
        spec = spec or {}
        bad = set(spec) - {"scene", "sweep"}
        if bad:
            raise ConfigError(f"variants.{variant}: unknown key(s) {', '.join(sorted(bad))} "
                              "(allowed: scene, sweep)")
        wf_raw = {"name": f"{name}-{variant}",
                  "description": f"{raw.get('description', '')} Variant {variant}.".strip(),
                  "scene": _merge(raw["base"], spec.get("scene") or {}),
                  "sweep": spec.get("sweep") or {}}
        try:
            out[variant] = expand(wf_raw)
        except ConfigError as exc:
            raise ConfigError(f"variants.{variant}: {exc}") from None
    return out


def load_suite(path: str | Path) -> dict[str, Workflow]:
    return expand_suite(read_yaml_mapping(path, "stability suite"))
