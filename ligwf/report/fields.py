"""The report's flow-field part: field errors in the case and condition tables, the
cohesionless null check, and the "Flow fields" section.

Reads the field archive of the analysis (:func:`ligwf.analysis.records.fields.read_fields`)
and computes only statistics of it (:mod:`ligwf.analysis.records.field_errors`): per
condition each field error against the CG1 cases of its sweep group with its 95 %
interval, the group's CG1 floor and the mark against it (:func:`ligwf.report.uncertainty.mark`),
in the columns every error of the condition table has (``field_error``, ``_lo``, ``_hi``,
``_se``, ``_floor``, ``_floor_source``, ``_vs_floor``), so the verdict reads it by name.

Null check: the cohesionless twin of the wet CG1 case (``sweep.controls: [cohesionless]``)
against the wet CG1 cases, held to the wet group's CG1 floor. Where the cohesion changes
the flow, that difference should be beyond the floor; the report shows the measured mark
beside the CG errors and asserts nothing it did not measure.
"""

from __future__ import annotations

import json
import math
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.records.conditions import Conditions
from ligwf.analysis.records.field_errors import (ERRORS, FIELD_ERRORS, MATERIAL_SOLID,
                                                 condition_mean, field_floor, field_intervals,
                                                 same_grid)
from ligwf.analysis.records.fields import CaseFields, read_fields
from ligwf.analysis.records.provenance import StaleAnalysis
from ligwf.fsio import atomic_write_text
from ligwf.report.field_figures import group_figures, rotation_sense
from ligwf.report.uncertainty import mark
from ligwf.scene.workflow import CONTROL_KEY
from ligwf.study import layout
from ligwf.study.case import group_label
from ligwf.study.study import Study

#: what each field error is called in the report
LABELS = {"field_error": "velocity field err (L2)",
          "field_solid_error": "solid fraction field err (L1)"}
#: the control whose fields the null check compares with the wet CG1 fields
COHESIONLESS = "cohesionless"


def case_fields(analysis_dir: Path) -> dict[str, CaseFields]:
    """The fields of every case the analysis recorded ({} when its record lists no field
    archive: an analysis from before the fields, or without a measured case; a stale
    archive an older analysis left is never read). StaleAnalysis (one line) when the
    listed archive cannot be read."""
    path = Path(analysis_dir) / layout.FIELDS_DATA
    try:
        record = json.loads((Path(analysis_dir) / layout.ANALYSIS_RECORD).read_text())
    except (OSError, ValueError):
        return {}
    if layout.FIELDS_DATA not in (record.get("outputs") or {}) or not path.is_file():
        return {}
    try:
        return read_fields(path)
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        raise StaleAnalysis(f"{path}: not a field archive ligwf wrote ({exc}); run `ligwf "
                            "analyse` again") from None


def _members(ids, fields: dict[str, CaseFields]) -> list[CaseFields]:
    return [fields[c] for c in ids if c in fields]


def add_field_errors(cases: pd.DataFrame, conditions: pd.DataFrame,
                     fields: dict[str, CaseFields], draws: int, seed: int
                     ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The case table with each case's field errors against its group's CG1 cases, and
    the condition table with every field error's interval, floor and mark (nan and
    ``–`` without fields)."""
    cases, conditions = cases.copy(), conditions.copy()
    for name in FIELD_ERRORS:
        cases[name] = math.nan
        for sfx in ("", "_lo", "_hi", "_se", "_floor"):
            conditions[f"{name}{sfx}"] = math.nan
        conditions[f"{name}_floor_source"] = "none"
        conditions[f"{name}_vs_floor"] = "–"
    if cases.empty or conditions.empty or not fields:
        return cases, conditions
    groups = Conditions.of(cases.itertuples())
    for i, row in cases.iterrows():
        refs = _members(groups.reference_cases(row["group"]), fields)
        own = _members([row["case_id"]], fields)
        if refs and own and same_grid(refs + own):
            for name in FIELD_ERRORS:
                cases.at[i, name] = float(ERRORS[name](condition_mean(refs), own[0].mean()))
    for i, row in conditions.iterrows():
        sub = cases[(cases["group"] == row["group"]) & (cases["cg"] == row["cg"])
                    & (cases["rule"] == row["rule"])]
        ids = list(sub["case_id"])
        ref_ids = groups.reference_cases(row["group"])
        members, refs = _members(ids, fields), _members(ref_ids, fields)
        reference = bool(ids) and groups.condition(ids[0]).is_reference
        intervals = field_intervals(members, refs, draws, seed)
        for name in FIELD_ERRORS:
            iv = intervals[name]
            fl = field_floor(refs, name)
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
    try:
        varied = json.loads(group)
    except (TypeError, ValueError):
        return None
    if not isinstance(varied, dict) or varied.get(CONTROL_KEY) != COHESIONLESS:
        return None
    varied.pop(CONTROL_KEY)
    return json.dumps(varied, sort_keys=True) if varied else "{}"


def twin_cases(cases: pd.DataFrame) -> dict[str, list[str]]:
    """Per wet sweep group the ids of its cohesionless CG1 twins."""
    out: dict[str, list[str]] = {}
    for r in cases.itertuples():
        wet = _wet_group(r.group)
        if wet is not None and r.cg == 1.0:
            out.setdefault(wet, []).append(r.case_id)
    return out


def null_check(cases: pd.DataFrame, fields: dict[str, CaseFields], draws: int, seed: int
               ) -> pd.DataFrame:
    """Per cohesionless twin condition at CG1: each field error of the twins against the
    wet CG1 cases of their group, its interval, the wet CG1 floor and the mark."""
    rows = []
    if cases.empty or not fields:
        return pd.DataFrame(rows)
    groups = Conditions.of(cases.itertuples())
    for cond, ids in groups.cases.items():
        wet = _wet_group(cond.group)
        if wet is None or not cond.is_reference:
            continue
        twins = _members(ids, fields)
        refs = _members(groups.reference_cases(wet), fields) if wet in groups.groups() else []
        if not twins or not refs:
            continue
        row = {"control": cond.group, "wet_group": wet, "cg": cond.cg,
               "twins": len(twins), "wet_cg1": len(refs)}
        intervals = field_intervals(twins, refs, draws, seed)
        for name in FIELD_ERRORS:
            iv = intervals[name]
            fl = field_floor(refs, name)
            marked = mark(iv.value, fl.value, iv.lo, iv.hi, len(refs))
            row.update({name: iv.value, f"{name}_lo": iv.lo, f"{name}_hi": iv.hi,
                        f"{name}_floor": fl.value, f"{name}_floor_source": fl.source,
                        f"{name}_vs_floor": marked.replace("CG-n replicas", "twin replicas")})
        rows.append(row)
    return pd.DataFrame(rows)


def _num(v) -> str:
    return "–" if v is None or not np.isfinite(v) else f"{v:.3g}"


def _cell(r, name) -> str:
    lo, hi = r.get(f"{name}_lo", math.nan), r.get(f"{name}_hi", math.nan)
    band = f" [{_num(lo)}, {_num(hi)}]" if np.isfinite(lo) and np.isfinite(hi) else ""
    return f"{_num(r[name])}{band}"




def fields_section(conditions: pd.DataFrame, null: pd.DataFrame, fields: dict[str, CaseFields],
                   figures: list[tuple[str, str]], kernel: float | None = None) -> str:
    """The "Flow fields" section (markdown): what the fields are, the field errors of
    every CG-n condition against CG1 with interval, floor and mark, the cohesionless null
    check, the maps (``figures``: (title, path relative to the report)) and the ParaView
    images (``kernel``: the study's ``analysis.field_kernel``, CG1 diameters)."""
    lines = ["## Flow fields", ""]
    if not fields:
        return "\n".join(lines + ["No cross-section fields in the analysis (analysed before "
                                  "ligwf had them: run `ligwf analyse` again).", ""])
    g = next(iter(fields.values())).grid
    lines += [
        "Coarse-grained fields on the drum cross-section (averaged along the periodic axis "
        "and over the steady window, ligwf.analysis.flow.fields): solid fraction, in-plane "
        "velocity and granular temperature T = <|c'|^2>/3 (fluctuation about the local mean "
        f"velocity). Gaussian kernel of standard deviation {1e3 * g.width:.3g} mm at every CG "
        f"level ({'' if kernel is None else f'analysis.field_kernel = {kernel:g} '}CG1 "
        f"diameters), nodes every {1e3 * g.spacing:.3g} mm; the maps show velocity and "
        f"temperature where phi >= {MATERIAL_SOLID:g}.",
        "",
        "Errors against the CG1 cases of the sweep group: **velocity field err** = "
        "sqrt(sum phi_1 |U - U_1|^2 / sum phi_1 |U_1|^2) over the nodes where CG1 has "
        f"material (phi_1 >= {MATERIAL_SOLID:g}); **solid fraction field err** = "
        "sum |phi - phi_1| / sum phi_1. 95 % intervals: block bootstrap over frames and "
        "replicas, jointly with CG1; floor: CG1 against CG1 (replicas, or the split-half of "
        "one run / sqrt 2, indicative); marked beyond / within only where the interval "
        "decides it.", ""]
    cg = conditions[conditions["cg"] != 1.0] if "cg" in conditions else conditions
    cg = cg[[_wet_group(gr) is None for gr in cg["group"]]] if not cg.empty else cg
    if not cg.empty:
        head = "| group | CG | rule | replicas |"
        rule = "|---|---|---|---|"
        for name in FIELD_ERRORS:
            head += f" {LABELS[name]} [95 % CI] | floor | vs floor |"
            rule += "---|---|---|"
        lines += [head, rule]
        for _, r in cg.iterrows():
            cells = [group_label(r["group"]), f"{r['cg']:g}", r["rule"], str(r["replicas"])]
            for name in FIELD_ERRORS:
                cells += [_cell(r, name), f"{_num(r[f'{name}_floor'])} "
                          f"({r[f'{name}_floor_source']})", r[f"{name}_vs_floor"]]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    if not null.empty:
        lines += ["Null check: the cohesionless twin against the wet CG1 cases (the same "
                  "errors, held to the wet CG1 floor). Where cohesion changes the flow this "
                  "difference should be beyond the floor; a CG error far below it is then "
                  "a measured agreement, not an insensitive measure.", "",
                  "| wet group | twins | " + " | ".join(
                      f"{LABELS[n]} [95 % CI] | vs floor" for n in FIELD_ERRORS) + " |",
                  "|---|---|" + "---|---|" * len(FIELD_ERRORS)]
        for _, r in null.iterrows():
            cells = [group_label(r["wet_group"]), str(r["twins"])]
            for name in FIELD_ERRORS:
                cells += [_cell(r, name), f"{r[f'{name}_vs_floor']} (floor "
                          f"{_num(r[f'{name}_floor'])})"]
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
    null = null_check(cases, fields, settings.bootstrap, settings.seed)
    atomic_write_text(out / layout.FIELD_NULL_REPORT, null.to_csv(index=False))
    usable = study.usable_cases()[0]
    sense = rotation_sense(usable[0].scaled.axis, usable[0].scaled.omega) if usable else "?"
    figures = group_figures(cases, fields, out / layout.FIGURES_DIR, sense, twin_cases(cases))
    md = fields_section(conditions, null, fields,
                        [(t, f"{layout.FIGURES_DIR}/{p.name}") for t, p in figures],
                        settings.field_kernel)
    return md, figures
