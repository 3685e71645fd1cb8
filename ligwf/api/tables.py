"""The tables of a study as the API reads them: where each comes from, and their dtypes.

:data:`TABLES` says for every table its file (a name from :mod:`ligwf.study.layout`), the
command that writes it and whether only a study with granule data has it;
:func:`read_table` reads one with the API's dtypes (:func:`typed`, the rules in
:mod:`ligwf.api`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from ligwf.analysis.records.renamed import current_names
from ligwf.errors import LigwfError
from ligwf.report import dictionary
from ligwf.study import layout

ANALYSE, REPORT = "ligwf analyse", "ligwf report"


class MissingOutput(LigwfError):
    """A table or record the study does not (yet) have; the message names the command
    that writes it (or why the study has none by design)."""


@dataclass(frozen=True)
class TableSpec:
    """Where one table of :class:`StudyResults` comes from."""

    attribute: str      # the StudyResults property
    folder: str         # layout.ANALYSIS_DIR or layout.REPORT_DIR
    file: str           # its name in that folder (from ligwf.study.layout)
    command: str        # the command that writes it
    granules: bool      # only a study with granule data has it
    what: str           # one line: one row per ...


#: Every table of a study, in the order a reader meets them.
TABLES: tuple[TableSpec, ...] = (
    TableSpec("cases", layout.REPORT_DIR, layout.CASES_REPORT, REPORT, False,
              "one row per usable case: run facts, costs, metrics, errors against CG1"),
    TableSpec("conditions", layout.REPORT_DIR, layout.CONDITIONS_REPORT, REPORT, False,
              "one row per (sweep group, CG level, rule): m, m_lo, m_hi, m_se per metric, "
              "errors also m_floor, m_floor_source, m_vs_floor"),
    TableSpec("verdict", layout.REPORT_DIR, layout.VERDICT_TABLE, REPORT, False,
              "one row per (sweep group, CG level, rule, criterion): pass / fail / undecided "
              "with the value, its interval (its level: the verdict record's statistics) and "
              "the budget, the speedup"),
    TableSpec("extrapolation", layout.REPORT_DIR, layout.EXTRAPOLATION_REPORT, REPORT, False,
              "one row per (sweep group, rule, signed criterion) with two or more CG-n "
              "levels: the CG1 value extrapolated from them (95 % interval, model term, "
              "lack-of-fit check, observed order) beside the measured CG1 mean"),
    TableSpec("spreading", layout.REPORT_DIR, layout.SPREADING_REPORT, REPORT, False,
              "one row per (sweep group, rule, CG-n level) of a study with placed liquid: how "
              "many times faster the liquid spreads than at CG1 (interval, exponent against "
              "n^2, the CG1 seeds' own spread)"),
    TableSpec("noise_floor", layout.REPORT_DIR, layout.NOISE_FLOOR_REPORT, REPORT, False,
              "one row per (sweep group, metric): the CG1 value and CG1-vs-CG1 scatter"),
    TableSpec("field_null_check", layout.REPORT_DIR, layout.FIELD_NULL_REPORT, REPORT, False,
              "one row per cohesionless twin: its field error against the wet CG1 case "
              "beside the CG1 floor (the null check of the field error)"),
    TableSpec("flow", layout.ANALYSIS_DIR, layout.FLOW_TABLE, ANALYSE, False,
              "one row per case: its steady window and flow metrics"),
    TableSpec("frames", layout.ANALYSIS_DIR, layout.FRAMES_TABLE, ANALYSE, True,
              "one row per case and frame: status, particles, contacts, bonds, granules"),
    TableSpec("granules", layout.ANALYSIS_DIR, layout.GRANULES_TABLE, ANALYSE, True,
              "one row per granule and frame: members, volume, centre of mass"),
    TableSpec("gsd", layout.ANALYSIS_DIR, layout.GSD_TABLE, ANALYSE, True,
              "one row per condition and volume bin: the steady-window GSD with bands"),
    TableSpec("gsd_summary", layout.ANALYSIS_DIR, layout.GSD_SUMMARY_TABLE, ANALYSE, True,
              "one row per condition: GSD size limits and errors against CG1"),
    TableSpec("gsd_pooling", layout.ANALYSIS_DIR, layout.GSD_POOLING_TABLE, ANALYSE, True,
              "one row per condition, pool size and pool: the GSD size limit of pooled replicas"),
    TableSpec("gsd_pooling_summary", layout.ANALYSIS_DIR, layout.GSD_POOLING_SUMMARY_TABLE,
              ANALYSE, True, "one row per condition and pool size: the pooled size limit "
              "and errors, mean [min, max] over pools"),
    TableSpec("kinetics", layout.ANALYSIS_DIR, layout.KINETICS_TABLE, ANALYSE, True,
              "one row per case and frame: granule count, d10/d50/d90, largest granule"),
    TableSpec("kinetics_summary", layout.ANALYSIS_DIR, layout.KINETICS_SUMMARY_TABLE, ANALYSE,
              True, "one row per condition and time: the kinetics with bands over replicas"),
    TableSpec("sensitivity", layout.ANALYSIS_DIR, layout.SENSITIVITY_TABLE, ANALYSE, True,
              "one row per variant of the granule definition"),
    TableSpec("controls", layout.ANALYSIS_DIR, layout.CONTROLS_TABLE, ANALYSE, True,
              "one row per wet case and definition beside its cohesionless twin"),
)

#: text columns by name (also when every value is missing, where a CSV reader sees nan)
TEXT_COLUMNS = frozenset({
    "case_id", "condition", "group", "rule", "status", "reason", "metric", "source",
    "variant", "definition", "control", "twin_id", "twin_case_id", "verdict", "method",
    "velocity_frame", "pool", "reference", "comparison", "split",
    # the verdict table (ligwf.inference.verdict)
    "criterion", "label", "unit", "state", "condition_state", "budget_source", "note",
    # describe(): the data dictionary's columns
    "column", "dtype", "meaning"})
TEXT_SUFFIXES = ("_floor_source", "_vs_floor", "_reason", "_verdict", "_label")


def is_text_column(name: str) -> bool:
    """Whether a column of a study table holds text by its name (see the module docstring)."""
    return name in TEXT_COLUMNS or name.endswith(TEXT_SUFFIXES)


def typed(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` with the API's dtypes: text columns ``string``, yes/no columns
    ``boolean``, numbers left numeric; no ``object`` column survives (a column of mixed
    values that is neither becomes ``string``)."""
    out = {}
    for col in table.columns:
        s = table[col]
        if is_text_column(str(col)):
            out[col] = s.astype("string")
        elif pd.api.types.is_bool_dtype(s) or _is_flags(s):
            out[col] = s.astype("boolean")
        elif pd.api.types.is_numeric_dtype(s):
            out[col] = s
        else:
            numbers = pd.to_numeric(s, errors="coerce")
            numeric = numbers.notna().sum() == s.notna().sum()
            out[col] = numbers if numeric else s.astype("string")
    return pd.DataFrame(out, index=table.index)


def _is_flags(s: pd.Series) -> bool:
    """An object/text column holding only True/False (and missing values)."""
    if pd.api.types.is_numeric_dtype(s):
        return False
    values = set(s.dropna().astype(str).unique())
    return bool(values) and values <= {"True", "False"}


#: columns that name a row: a table whose dictionary entry lists one always writes it
KEY_COLUMNS = frozenset({"case_id", "condition", "group", "cg", "rule", "replica",
                         "criterion", "variant", "definition", "twin_id", "metric", "column",
                         "comparison", "control", "step", "time", "k", "pool"})


def column_problem(table: pd.DataFrame, spec: TableSpec) -> str | None:
    """Why ``table`` (read from ``spec``'s file) is not the table ligwf writes, naming the
    table and the column (None: it is, or it is empty): a column that names its rows is
    missing, or a column is none the data dictionary documents for it (renamed or added
    by hand). The CLI's stages never read such a table either: one rule for both."""
    if not len(table.columns):
        return None
    documented = dictionary.TABLES.get(spec.file)
    if documented is None:
        return None
    for name in documented.columns:
        if name in KEY_COLUMNS and name not in table.columns:
            return (f"the {spec.attribute} table has no column {name!r} (each of its rows "
                    "is named by it: renamed or removed since ligwf wrote it?)")
    for name in table.columns:
        if not dictionary.documented(spec.file, str(name)):
            return (f"column {str(name)!r} is none of the {spec.attribute} table's (see "
                    "describe(); renamed or added by hand?)")
    return None


def read_checked(path: Path, spec: TableSpec, study: Path) -> pd.DataFrame:
    """:func:`read_table` of ``spec``'s file at ``path`` in the study folder ``study``;
    MissingOutput naming the command that writes it when the file cannot be read or is not
    the table ligwf writes (:func:`column_problem`)."""
    try:
        table = read_table(path)
    except (OSError, ValueError) as exc:
        raise MissingOutput(f"{path}: unreadable ({type(exc).__name__}: {exc}); run "
                            f"`{spec.command} {study}` again") from None
    if (why := column_problem(table, spec)) is not None:
        raise MissingOutput(f"{path}: {why}; run `{spec.command} {study}` again")
    return table


def read_table(path: Path) -> pd.DataFrame:
    """A study table (``.csv`` or ``.parquet``) with the API's dtypes; an empty file is an
    empty table. An analysis table written by the previous release has its renamed
    columns under their current names (:func:`~ligwf.analysis.records.renamed.current_names`,
    with a FutureWarning)."""
    if path.suffix == ".parquet":
        return typed(current_names(pd.read_parquet(path), path.name, str(path)))
    try:
        return typed(current_names(pd.read_csv(path), path.name, str(path)))
    except pd.errors.EmptyDataError:
        return pd.DataFrame()


