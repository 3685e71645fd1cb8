"""The report's "Flow fields" section: the field criterion and the solid-fraction error of
the condition table (computed with the tables, :mod:`ligwf.inference.field_tables`), the
null checks' table and the map figures. It renders; the statistics are the inference
layer's."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.records.fields import CaseFields
from ligwf.inference.field_errors import KERNEL_COLUMNS, LAYER_SPEED, MATERIAL_SOLID
from ligwf.inference.field_tables import twin_cases, wet_group
from ligwf.report.field_figures import group_figures, rotation_sense
from ligwf.study import layout
from ligwf.study.case import group_label
from ligwf.study.study import Study

#: what each field error is called in the report
LABELS = {"field_error": "layer velocity err (drum frame)",
          "field_solid_error": "solid fraction field err (L1)"}
#: the field criterion's columns: the verdict's width, then each reported width
CRITERION_COLUMNS = ("field_error", *KERNEL_COLUMNS.values())


def _num(v) -> str:
    return "–" if v is None or not np.isfinite(v) else f"{v:.3g}"


def _cell(r, name) -> str:
    lo, hi = r.get(f"{name}_lo", math.nan), r.get(f"{name}_hi", math.nan)
    band = f" [{_num(lo)}, {_num(hi)}]" if np.isfinite(lo) and np.isfinite(hi) else ""
    return f"{_num(r[name])}{band}"




def _extra_width(kernel: float | None) -> bool:
    """Whether the verdict's width is not one of the reported widths (its own column)."""
    return kernel is not None and not any(np.isclose(kernel, k) for k in KERNEL_COLUMNS)


def _criterion_cells(r, kernel: float | None) -> list[str]:
    """The field criterion's cells of a row: each reported width, then the verdict's if
    it is another."""
    cells = [_cell(r, col) for col in KERNEL_COLUMNS.values()]
    return cells + [_cell(r, "field_error")] if _extra_width(kernel) else cells


def _criterion_count(kernel: float | None) -> int:
    return len(KERNEL_COLUMNS) + int(_extra_width(kernel))


def _criterion_head(kernel: float | None) -> str:
    """The field criterion's column heads (the verdict's width marked)."""
    heads = [f"layer velocity err, kernel {k:g} d [bounds]" + (
        " (verdict)" if kernel is not None and np.isclose(k, kernel) else "")
             for k in KERNEL_COLUMNS]
    if _extra_width(kernel):
        heads.append(f"layer velocity err, kernel {kernel:g} d [bounds] (verdict)")
    return " | ".join(heads)


def fields_section(conditions: pd.DataFrame, null: pd.DataFrame, fields: dict[str, CaseFields],
                   figures: list[tuple[str, str]], kernel: float | None = None) -> str:
    """The "Flow fields" section (markdown): what the fields are, the field criterion of
    every CG-n condition against CG1 at each kernel width (the verdict's named) with its
    bounds and CG1-vs-CG1 value, the solid-fraction error, the null checks, the maps
    (``figures``: (title, path relative to the report)) and the ParaView images
    (``kernel``: the study's ``analysis.field_kernel``, CG1 diameters: the maps' width
    and the verdict's)."""
    lines = ["## Flow fields", ""]
    if not fields:
        return "\n".join(lines + ["No cross-section fields in the analysis (analysed before "
                                  "ligwf had them: run `ligwf analyse` again).", ""])
    g = next(iter(fields.values())).grid
    widths = ", ".join(f"{k:g}" for k in KERNEL_COLUMNS)
    lines += [
        "Coarse-grained fields on the drum cross-section (averaged along the periodic axis "
        "and over the steady window, ligwf.analysis.flow.fields): solid fraction, in-plane "
        "velocity and granular temperature T = <|c'|^2>/3 (fluctuation about the local mean "
        f"velocity). The maps: Gaussian kernel of standard deviation {1e3 * g.width:.3g} mm at "
        f"every CG level ({'' if kernel is None else f'analysis.field_kernel = {kernel:g} '}"
        f"CG1 diameters), nodes every {1e3 * g.spacing:.3g} mm; velocity and temperature "
        f"shown where phi >= {MATERIAL_SOLID:g}.",
        "",
        "**Layer velocity err** (the field criterion): the in-plane velocity in the drum "
        "frame, W = U - omega x r, compared where CG can change it: the flowing layer, the "
        f"nodes where CG1 has material (phi_1 >= {MATERIAL_SOLID:g}) and moves relative to "
        f"the drum (|W_1| >= {LAYER_SPEED:g} omega R; the co-rotating plug agrees by "
        "construction). The phi_1-weighted RMS of the difference of the arms' mean fields, "
        "in units of the wall speed omega R, less the noise of both arms' run scatter (as "
        "the velocity profile); bounds [lo, hi] from the triangle inequality with a "
        "Student t bound on the noise, each holding with >= 95 %. The unit is the run. "
        f"At kernel widths {widths} CG1 diameters; the verdict reads the width "
        f"{'analysis.field_kernel' if kernel is None else f'{kernel:g} d (analysis.field_kernel)'}. "
        "CG1 vs CG1: the same criterion between two halves of the CG1 runs. "
        "**Solid fraction field err** = sum |phi - phi_1| / sum phi_1 over the cross-section, "
        "95 % interval from a block bootstrap over frames and replicas; floor: CG1 against "
        "CG1.", ""]
    levels = conditions[conditions["cg"] != 1.0] if "cg" in conditions else conditions
    levels = (levels[[wet_group(gr) is None for gr in levels["group"]]] if not levels.empty
              else levels)
    if not levels.empty:
        name = "field_solid_error"
        lines += [f"| group | CG | rule | replicas | {_criterion_head(kernel)} | CG1 vs CG1 | "
                  f"{LABELS[name]} [95 % CI] | floor | vs floor |",
                  "|---|---|---|---|" + "---|" * _criterion_count(kernel) + "---|---|---|---|"]
        for _, r in levels.iterrows():
            cells = [group_label(r["group"]), f"{r['cg']:g}", r["rule"], str(r["replicas"]),
                     *_criterion_cells(r, kernel), _num(r["field_error_floor"]),
                     _cell(r, name), f"{_num(r[f'{name}_floor'])} ({r[f'{name}_floor_source']})",
                     r[f"{name}_vs_floor"]]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    if not null.empty:
        lines += ["Null checks: CG1 against CG1 should show no difference (upper bound near "
                  "the noise); the cohesionless twin against the wet CG1 cases shows what a "
                  "change of the physics does to the same criterion.", "",
                  f"| comparison | group | split | runs | {_criterion_head(kernel)} | "
                  f"{LABELS['field_solid_error']} [95 % CI] |",
                  "|---|---|---|---|" + "---|" * _criterion_count(kernel) + "---|"]
        for _, r in null.iterrows():
            solid = (_cell(r, "field_solid_error") if "field_solid_error" in r
                     and np.isfinite(r.get("field_solid_error", math.nan)) else "–")
            cells = [r["comparison"], group_label(r["group"]), r["split"],
                     f"{r['runs']} vs {r['ref_runs']}", *_criterion_cells(r, kernel), solid]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    for t, p in figures:    # one paragraph each: the page renders each as a figure
        lines += [f"![{t}]({p})", ""]
    lines += ["", f"ParaView: `{layout.ANALYSIS_DIR}/{layout.field_image('<case>')}` (ImageData: "
              "solid_fraction, velocity, speed, temperature of the window mean).", ""]
    return "\n".join(lines)


def fields_report(study: Study, cases: pd.DataFrame, conditions: pd.DataFrame,
                  null: pd.DataFrame, fields: dict[str, CaseFields], out: Path
                  ) -> tuple[str, list[tuple[str, Path]]]:
    """The report's flow-field part of a study whose tables are built (``conditions``
    with the field errors, ``null`` the null checks, from the cases' ``fields``: all of
    :func:`ligwf.inference.decide.decide_study`): the map figures (in the report folder
    ``out``'s figures folder) and the section's markdown; returns (markdown, figures)."""
    settings = study.analysis
    usable = study.usable_cases()[0]
    drum = usable[0].scaled.drum if usable else None
    sense = rotation_sense(drum.axis, drum.omega) if drum else "?"
    figures = group_figures(cases, fields, out / layout.FIGURES_DIR, sense, twin_cases(cases))
    md = fields_section(conditions, null, fields,
                        [(t, f"{layout.FIGURES_DIR}/{p.name}") for t, p in figures],
                        settings.field_kernel)
    return md, figures
