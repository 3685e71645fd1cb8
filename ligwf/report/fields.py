"""The report's flow-field part: the field criterion and the solid-fraction error in the
case and condition tables, the null checks, and the "Flow fields" section.

Reads the field archive of the analysis (:func:`ligwf.analysis.records.fields.read_fields`)
and computes only statistics of it (:mod:`ligwf.inference.field_errors`): per
condition the field criterion (drum-frame velocity in the flowing layer, noise-corrected,
with bounds; at every width of ``CRITERION_KERNELS`` as ``field_error_k<w>``, and at the
study's ``analysis.field_kernel`` as ``field_error``, the column the verdict reads) and the
solid-fraction error with its bootstrap interval, each with the columns every error of the
condition table has (``_lo``, ``_hi``, ``_se``, ``_floor``, ``_floor_source``,
``_vs_floor``). The field criterion's floor is its CG1-vs-CG1 value
(:func:`~ligwf.inference.field_errors.null_split`).

Null checks (one table): per sweep group, CG1 against CG1 (the criterion should find no
difference); and the cohesionless twin of the wet CG1 case (``sweep.controls:
[cohesionless]``) against the wet CG1 cases: where cohesion changes the flow, that
difference should be found. The report shows what it measured and asserts nothing more.
"""

from __future__ import annotations

import math
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.records.analysis_record import AnalysisRecord
from ligwf.analysis.records.conditions import Conditions
from ligwf.inference.equivalence import ALPHA, NormEstimate
from ligwf.inference.field_errors import (ERRORS, FIELD_NOISE_COLUMNS, KERNEL_COLUMNS,
                                                 LAYER_SPEED, MATERIAL_SOLID, condition_mean,
                                                 field_floor, field_intervals,
                                                 layer_components, layer_error, null_split,
                                                 same_grid, whole_windows)
from ligwf.analysis.records.fields import CaseFields, read_fields
from ligwf.analysis.records.provenance import StaleAnalysis
from ligwf.fsio import atomic_write_text
from ligwf.report.field_figures import group_figures, rotation_sense
from ligwf.inference.uncertainty import mark
from ligwf.study import layout
from ligwf.study.case import group_label
from ligwf.study.condition import Condition
from ligwf.study.group import SweepGroup
from ligwf.study.study import Study

#: what each field error is called in the report
LABELS = {"field_error": "layer velocity err (drum frame)",
          "field_solid_error": "solid fraction field err (L1)"}
#: the field criterion's columns: the verdict's width, then each reported width
CRITERION_COLUMNS = ("field_error", *KERNEL_COLUMNS.values())
#: the control whose fields the null check compares with the wet CG1 fields
COHESIONLESS = "cohesionless"


def case_fields(analysis_dir: Path) -> dict[str, CaseFields]:
    """The fields of every case the analysis recorded ({} when its record lists no field
    archive: an analysis from before the fields, or without a measured case; a stale
    archive an older analysis left is never read). StaleAnalysis (one line) when the
    listed archive cannot be read."""
    path = Path(analysis_dir) / layout.FIELDS_DATA
    record = AnalysisRecord.read(analysis_dir)
    if record is None or not record.wrote(layout.FIELDS_DATA) or not path.is_file():
        return {}
    try:
        return read_fields(path)
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        raise StaleAnalysis(f"{path}: not a field archive ligwf wrote ({exc}); run `ligwf "
                            "analyse` again") from None


def _fields_of(ids, fields: dict[str, CaseFields]) -> list[CaseFields]:
    return [fields[c] for c in ids if c in fields]


def _criterion_row(row: dict, est: dict[str, NormEstimate]) -> None:
    """The field criterion's columns of a table row from its estimates by column."""
    for col, e in est.items():
        row[col], row[f"{col}_lo"], row[f"{col}_hi"] = e.value, e.lo, e.hi


def _criterion(cases: list, refs: list, kernel: float, alpha: float = ALPHA
               ) -> dict[str, NormEstimate]:
    """The field criterion at the verdict's width ``kernel`` and at every reported width,
    by column (runs: (case, part of its window)), bounds at ``alpha``."""
    out = {"field_error": layer_error(cases, refs, kernel, alpha)}
    out.update({col: layer_error(cases, refs, k, alpha) for k, col in KERNEL_COLUMNS.items()})
    return out


def _noise_row(row: dict, noise) -> None:
    """The pieces of the field criterion's bounds (:class:`LayerNoise`) as columns: what
    the verdict plans more replicas from."""
    values = ((math.nan,) * 3 + (0, 0)) if noise is None else (
        noise.distance, noise.run_variance, noise.reference_variance, noise.runs,
        noise.reference_runs)
    row.update(zip(FIELD_NOISE_COLUMNS, values))


def add_field_errors(cases: pd.DataFrame, conditions: pd.DataFrame,
                     fields: dict[str, CaseFields], draws: int, seed: int, kernel: float,
                     alpha: float = ALPHA) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The case table with each case's field errors against its group's CG1 cases (the
    criterion raw: one run has no noise estimate), and the condition table with the field
    criterion at the verdict's width ``kernel`` (CG1 diameters) and at each reported width,
    and the solid-fraction error, each with bounds, floor and mark (nan and ``–`` without
    fields). The field criterion's bounds are at ``alpha`` (a sequential study's looks:
    its level per look) and its noise pieces (``FIELD_NOISE_COLUMNS``) are kept for the
    verdict's planning."""
    cases, conditions = cases.copy(), conditions.copy()
    for name in ("field_error", "field_solid_error"):
        cases[name] = math.nan
        for sfx in ("", "_lo", "_hi", "_se", "_floor"):
            conditions[f"{name}{sfx}"] = math.nan
        conditions[f"{name}_floor_source"] = "none"
        conditions[f"{name}_vs_floor"] = "–"
    conditions["field_error_kernel"] = kernel
    for col in KERNEL_COLUMNS.values():
        for sfx in ("", "_lo", "_hi"):
            conditions[f"{col}{sfx}"] = math.nan
    for col in FIELD_NOISE_COLUMNS:
        conditions[col] = math.nan
    if cases.empty or conditions.empty or not fields:
        return cases, conditions
    groups = Conditions.of(cases.itertuples())
    for i, row in cases.iterrows():
        refs = _fields_of(groups.reference_cases(row["group"]), fields)
        own = _fields_of([row["case_id"]], fields)
        if refs and own:
            cases.at[i, "field_error"] = layer_error(whole_windows(own), whole_windows(refs),
                                                     kernel).raw
            if same_grid(refs + own):
                cases.at[i, "field_solid_error"] = float(
                    ERRORS["field_solid_error"](condition_mean(refs), own[0].mean()))
    for i, row in conditions.iterrows():
        cond = Condition(row["group"], row["cg"], row["rule"])
        ids = list(groups.cases.get(cond, ()))
        ref_ids = groups.reference_cases(cond.group)
        runs, refs = _fields_of(ids, fields), _fields_of(ref_ids, fields)
        reference = bool(ids) and cond.is_reference
        est = _criterion(whole_windows(runs), whole_windows(refs), kernel, alpha)
        null = layer_error(*null_split(refs)[:2], kernel, alpha)
        values: dict = {}
        _criterion_row(values, est)
        _noise_row(values, layer_components(whole_windows(runs), whole_windows(refs),
                                            kernel))
        for col, v in values.items():
            conditions.at[i, col] = v
        e = est["field_error"]
        conditions.at[i, "field_error_floor"] = null.value
        conditions.at[i, "field_error_floor_source"] = (
            "none" if not math.isfinite(null.value) else f"CG1 vs CG1: {null_split(refs)[2]}")
        conditions.at[i, "field_error_vs_floor"] = (
            "reference" if reference else mark(e.value, null.value, e.lo, e.hi, len(refs)))
        iv = field_intervals(runs, refs, draws, seed)["field_solid_error"]
        fl = field_floor(refs, "field_solid_error")
        name = "field_solid_error"
        conditions.at[i, name], conditions.at[i, f"{name}_lo"] = iv.value, iv.lo
        conditions.at[i, f"{name}_hi"], conditions.at[i, f"{name}_se"] = iv.hi, iv.se_within
        conditions.at[i, f"{name}_floor"] = fl.value
        conditions.at[i, f"{name}_floor_source"] = fl.source
        conditions.at[i, f"{name}_vs_floor"] = (
            "reference" if reference else mark(iv.value, fl.value, iv.lo, iv.hi, len(refs)))
    return cases, conditions


def _wet_group(group: str) -> str | None:
    """The sweep group of the wet cases a cohesionless twin's group controls (None for a
    group that is not a cohesionless control)."""
    parsed = SweepGroup.parse(group)
    return parsed.wet.text if parsed.control == COHESIONLESS else None


def twin_cases(cases: pd.DataFrame) -> dict[str, list[str]]:
    """Per wet sweep group the ids of its cohesionless CG1 twins."""
    out: dict[str, list[str]] = {}
    for r in cases.itertuples():
        wet = _wet_group(r.group)
        if wet is not None and r.cg == 1.0:
            out.setdefault(wet, []).append(r.case_id)
    return out


#: the two kinds of null check
CG1_VS_CG1, TWIN_VS_WET = "CG1 vs CG1", "cohesionless twin vs wet CG1"


def null_check(cases: pd.DataFrame, fields: dict[str, CaseFields], draws: int, seed: int,
               kernel: float) -> pd.DataFrame:
    """The null checks: per sweep group with CG1 cases, the field criterion of CG1 against
    CG1 (:func:`~ligwf.inference.field_errors.null_split`); per cohesionless twin
    condition at CG1, the field criterion and the solid-fraction error of the twins
    against the wet CG1 cases (with the wet CG1 floor and mark)."""
    rows = []
    if cases.empty or not fields:
        return pd.DataFrame(rows)
    groups = Conditions.of(cases.itertuples())
    for group in groups.groups():
        if _wet_group(group) is not None:
            continue
        refs = _fields_of(groups.reference_cases(group), fields)
        if not refs:
            continue
        a, b, how = null_split(refs)
        row = {"comparison": CG1_VS_CG1, "control": group, "group": group, "cg": 1.0,
               "split": how, "runs": len(a), "ref_runs": len(b)}
        _criterion_row(row, _criterion(a, b, kernel))
        rows.append(row)
    for cond, ids in groups.cases.items():
        wet = _wet_group(cond.group)
        if wet is None or not cond.is_reference:
            continue
        twins = _fields_of(ids, fields)
        refs = _fields_of(groups.reference_cases(wet), fields) if wet in groups.groups() else []
        if not twins or not refs:
            continue
        row = {"comparison": TWIN_VS_WET, "control": cond.group, "group": wet, "cg": cond.cg,
               "split": "every twin against every wet CG1 run", "runs": len(twins),
               "ref_runs": len(refs)}
        _criterion_row(row, _criterion(whole_windows(twins), whole_windows(refs), kernel))
        name = "field_solid_error"
        iv = field_intervals(twins, refs, draws, seed)[name]
        fl = field_floor(refs, name)
        row.update({name: iv.value, f"{name}_lo": iv.lo, f"{name}_hi": iv.hi,
                    f"{name}_floor": fl.value, f"{name}_floor_source": fl.source,
                    f"{name}_vs_floor": mark(iv.value, fl.value, iv.lo, iv.hi, len(refs))
                    .replace("CG-n replicas", "twin replicas")})
        rows.append(row)
    return pd.DataFrame(rows)


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
    levels = (levels[[_wet_group(gr) is None for gr in levels["group"]]] if not levels.empty
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


def fields_report(study: Study, cases: pd.DataFrame, conditions: pd.DataFrame, out: Path
                  ) -> tuple[str, list[tuple[str, Path]]]:
    """The report's flow-field part of a study whose tables are built (``conditions``
    with the field errors of :func:`add_field_errors`): the null-check table
    (``layout.FIELD_NULL_REPORT`` in the report folder ``out``), the map figures (in its
    figures folder) and the section's markdown; returns (markdown, figures)."""
    fields = case_fields(study.analysis_dir)
    settings = study.analysis
    null = null_check(cases, fields, settings.bootstrap, settings.seed, settings.field_kernel)
    atomic_write_text(out / layout.FIELD_NULL_REPORT, null.to_csv(index=False))
    usable = study.usable_cases()[0]
    drum = usable[0].scaled.drum if usable else None
    sense = rotation_sense(drum.axis, drum.omega) if drum else "?"
    figures = group_figures(cases, fields, out / layout.FIGURES_DIR, sense, twin_cases(cases))
    md = fields_section(conditions, null, fields,
                        [(t, f"{layout.FIGURES_DIR}/{p.name}") for t, p in figures],
                        settings.field_kernel)
    return md, figures
