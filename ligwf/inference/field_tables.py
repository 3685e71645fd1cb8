"""The field columns of a study's case and condition tables, and the field null checks.

From the cases' fields (the archive the analysis recorded,
:func:`ligwf.analysis.records.fields.recorded_fields`) it computes statistics
(:mod:`ligwf.inference.field_errors`): per condition the field criterion (drum-frame
velocity in the flowing layer, noise-corrected, with bounds; at every width of
``CRITERION_KERNELS`` as ``field_error_k<w>``, and at the study's ``analysis.field_kernel``
as ``field_error``, the column the verdict reads) and the solid-fraction error with its
bootstrap interval, each with the columns every error of the condition table has (``_lo``,
``_hi``, ``_se``, ``_floor``, ``_floor_source``, ``_vs_floor``). The field criterion's floor
is its CG1-vs-CG1 value (:func:`~ligwf.inference.field_errors.null_split`).

Null checks (one table, :func:`null_check`): per sweep group, CG1 against CG1 (the
criterion should find no difference); and the cohesionless twin of the wet CG1 case
(``sweep.controls: [cohesionless]``) against the wet CG1 cases: where cohesion changes the
flow, that difference should be found. The report shows them (:mod:`ligwf.report.fields`).
"""

from __future__ import annotations

import math

import pandas as pd

from ligwf.analysis.records.conditions import Conditions
from ligwf.analysis.records.fields import CaseFields
from ligwf.inference.equivalence import ALPHA, NormEstimate
from ligwf.inference.field_errors import (ERRORS, FIELD_NOISE_COLUMNS, KERNEL_COLUMNS,
                                          condition_mean, field_floor, field_intervals,
                                          layer_components, layer_error, null_split,
                                          same_grid, whole_windows)
from ligwf.inference.uncertainty import mark
from ligwf.study.condition import Condition
from ligwf.study.group import SweepGroup

#: the control whose fields the null check compares with the wet CG1 fields
COHESIONLESS = "cohesionless"


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


def wet_group(group: str) -> str | None:
    """The sweep group of the wet cases a cohesionless twin's group controls (None for a
    group that is not a cohesionless control)."""
    parsed = SweepGroup.parse(group)
    return parsed.wet.text if parsed.control == COHESIONLESS else None


def twin_cases(cases: pd.DataFrame) -> dict[str, list[str]]:
    """Per wet sweep group the ids of its cohesionless CG1 twins."""
    out: dict[str, list[str]] = {}
    for r in cases.itertuples():
        wet = wet_group(r.group)
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
        if wet_group(group) is not None:
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
        wet = wet_group(cond.group)
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
