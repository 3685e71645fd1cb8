"""The report's "Resolution and grains" section: the one physical resolution every flow
metric of the study was measured at, and the drum counted in grains of each CG level with
the measured flowing layer beside it (:mod:`ligwf.scene.grains`)."""

from __future__ import annotations

import json
import math

import pandas as pd

from ligwf.errors import ConfigError
from ligwf.report.sections import Section
from ligwf.scene.grains import grains, scaled_mean_diameter, study_strip
from ligwf.scene.model import Scene
from ligwf.study import layout
from ligwf.study.study import Study


def scale_section(study: Study, conditions: pd.DataFrame) -> list[Section]:
    """The section (none for a study without a usable case)."""
    cases = study.usable_cases()[0]
    if not cases:
        return []
    try:
        scene = Scene.model_validate(
            json.loads((cases[0].path / layout.SCENE_FILE).read_text())["scene"])
    except (OSError, ValueError, KeyError, ConfigError):
        return []
    strip = study_strip([scaled_mean_diameter(c.scaled) for c in cases],
                        study.analysis.surface_strip)
    where = (f"strips {strip * 1e3:.3g} mm wide at every CG level" if strip else
             "strips twice each case's own diameter (analysis.surface_strip = 0: the "
             "resolution moves with the CG level)")
    lines = [f"Every level is measured at one physical resolution: the angle of repose on "
             f"{where} (analysis.surface_strip); the velocity profile and the flowing layer "
             f"on bins of depth over the bed's depth (the same at every level); the continuum fields "
             f"with a kernel of analysis.field_kernel = {study.analysis.field_kernel:g} CG1 "
             f"diameters. The drum in grains of each level (the flowing layer: its measured "
             f"mean thickness over the level's diameter):", "",
             "| CG | diameter (mm) | lifter height | slice length | bed depth | flowing layer |",
             "|---|---|---|---|---|---|"]
    warnings = []
    layer = {}
    if not conditions.empty and "flowing_layer_thickness_mean" in conditions:
        for cg, sub in conditions.groupby("cg"):
            v = pd.to_numeric(sub["flowing_layer_thickness_mean"], errors="coerce").mean()
            layer[float(cg)] = float(v)
    for cg in sorted({float(c.cg) for c in cases}):
        g = grains(scene, cg)
        thick = layer.get(cg, math.nan)
        shown = f"{thick / g.diameter:.3g}" if math.isfinite(thick) else "–"
        lines.append(f"| {cg:g} | {g.diameter * 1e3:.3g} | {g.lifter:.2g} | {g.slice:.3g} | "
                     f"{g.bed_depth:.3g} | {shown} |")
        if g.warning:
            warnings.append(f"- {g.warning}")
    return [Section("Resolution and grains", "resolution-and-grains",
                    "\n".join(lines + ([""] + warnings if warnings else [])))]
