"""ligwf.report.dictionary: every column of every table ligwf writes has a unit, a label
and a meaning; the report headers come from it; docs/data_dictionary.md is generated from
it. The completeness check runs on the tables' declared columns, on report tables built
from hand-made inputs, and (engine) on every table of a real tiny study with CG1 replicas,
CG2 and a cohesionless twin."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from apistudy import api_study
from helpers import ROOT
from ligwf.analysis.flow.registry import METRICS
from ligwf.analysis.gsd.kinetics import QUANTITIES
from ligwf.analysis.gsd.pooling import POOLING_COLUMNS
from ligwf.analysis.gsd.tables import GSD_COLUMNS, SUMMARY_COLUMNS
from ligwf.analysis.records.metrics import GRANULE_METRICS
from ligwf.report import dictionary as dic
from ligwf.inference.study_tables import compare_to_cg1, condition_table, noise_floor_table
from ligwf.study import layout
from ligwf.study.case import group_label

from report.test_tables import METRICS as TEST_METRICS, case_table, stats


def undocumented(table: str, columns) -> list[str]:
    return [c for c in columns if not dic.documented(table, c)]


def test_committed_dictionary_is_the_generated_one():
    text = (ROOT / "docs" / "data_dictionary.md").read_text()
    assert text == dic.dictionary_markdown(), (
        "regenerate: ligwf schema --dictionary docs/data_dictionary.md")


def test_declared_columns_of_the_analysis_tables_are_documented():
    assert not undocumented(layout.GSD_TABLE, GSD_COLUMNS)
    assert not undocumented(layout.GSD_SUMMARY_TABLE, SUMMARY_COLUMNS)
    assert not undocumented(layout.GSD_POOLING_TABLE, POOLING_COLUMNS)
    assert not undocumented(layout.KINETICS_TABLE, QUANTITIES)


def test_every_registered_metric_is_in_the_dictionary_and_the_report_tables():
    names = [*METRICS, *(m.name for m in GRANULE_METRICS)]
    assert set(names) == {*dic.FLOW_METRICS, *dic.GRANULE_METRICS}, (
        "a metric without a dictionary entry: give its MetricSpec a unit and a meaning, "
        "then `ligwf schema --dictionary docs/data_dictionary.md`")
    for name in names:
        assert dic.documented(layout.CONDITIONS_REPORT, name), name
        assert dic.documented(layout.CASES_REPORT, name), name


def test_report_tables_from_hand_made_inputs_are_documented():
    s = stats()
    df = compare_to_cg1(case_table(), s, [TEST_METRICS["angle_error"]])
    conditions = condition_table(df, s, ["core_seconds", "speedup_core",
                                         "gsd_error_below_lower"])
    assert "group_label" in conditions and "gsd_error_below_lower_lo" in conditions
    floors = noise_floor_table(df, s)
    report_columns = {layout.CONDITIONS_REPORT: conditions, layout.NOISE_FLOOR_REPORT: floors}
    for table, frame in report_columns.items():
        known = [c for c in frame.columns if not c.startswith("angle")]   # test metrics
        assert not undocumented(table, known), table


def test_field_error_columns_are_documented():
    from ligwf.inference.field_errors import FIELD_ERRORS

    assert set(FIELD_ERRORS) == set(dic.FIELD_ERRORS)
    for name in FIELD_ERRORS:
        for sfx in ("", "_lo", "_hi", "_se", "_floor", "_floor_source", "_vs_floor"):
            assert dic.documented(layout.CONDITIONS_REPORT, name + sfx)
        assert dic.documented(layout.FIELD_NULL_REPORT, name + "_vs_floor")


def test_verdict_table_columns_are_documented():
    from ligwf.inference.registry import CriterionResult
    from ligwf.inference.verdict import ConditionVerdict, GroupVerdict, Verdict
    from ligwf.inference.verdict_records import verdict_rows

    crit = CriterionResult("angle_deg", "angle of repose", "deg", "pass", 0.5, 0.1, 0.9, 1.0,
                           "tolerance")
    cond = ConditionVerdict("{}", 2.0, "weber", 2, 9.4, 8.8, 10.0, (crit,))
    rows = verdict_rows(Verdict((GroupVerdict("{}", (cond,), "CG2 weber meets it", cond.name),)))
    assert len(rows) == 1
    assert not undocumented(layout.VERDICT_TABLE, rows.columns)


def test_headers_carry_units_and_the_shown_unit_scales_values():
    assert dic.header("angle_of_repose") == "angle [deg]"
    assert dic.header("core_seconds") == "cores x wall [core-s]"
    assert dic.header("wall_seconds") == "wall [s]"
    assert dic.header("d50") == "d50 [mm]"
    assert dic.header("speedup_core") == "speedup"
    assert dic.header("gsd_error_below_lower") == "GSD err below lower limit"
    assert dic.header("gsd_lower_limit_diameter") == "GSD lower limit d [mm]"
    assert dic.header("my_plugin_metric", fallback="plug-in") == "plug-in"
    assert dic.shown_value("d50", 0.0023) == pytest.approx(2.3)
    assert dic.shown_value("angle_of_repose", 31.0) == 31.0
    assert dic.shown_value("d50", "–") == "–"


def test_shown_frame_scales_renames_and_drops_the_raw_group():
    df = pd.DataFrame({"group": ["{}"], "group_label": ["all cases"], "d50": [0.002],
                       "angle_of_repose": [31.0], "plugin": [1.0]})
    shown = dic.shown_frame(df)
    assert list(shown.columns) == ["group", "d50 [mm]", "angle [deg]", "plugin"]
    assert shown["d50 [mm]"].iloc[0] == pytest.approx(2.0)
    assert shown["group"].iloc[0] == "all cases"


def test_derived_columns_name_their_base():
    c = dic.column("angle_error_vs_floor", layout.CONDITIONS_REPORT)
    assert c.unit == "text" and "angle_error" in c.meaning and "undecided" in c.meaning
    assert dic.column("d50_lo").unit == "m" and dic.column("d50_lo").shown == "mm"
    assert dic.column("twin_share_10", layout.CONTROLS_TABLE).meaning.startswith("share_10")
    assert dic.column("upper_limit_nan_pools").unit == "count"
    assert dic.column("no_such_column") is None
    assert not dic.documented(layout.FLOW_TABLE, "no_such_column")
    # a suffix documents a column only in a table that has that family
    assert dic.documented(layout.CONDITIONS_REPORT, "angle_error_floor")
    assert not dic.documented(layout.FLOW_TABLE, "angle_of_repose_mean_floor")


@pytest.mark.parametrize("group,label", [
    ("{}", "all cases"),
    ('{"control": "cohesionless"}', "cohesionless control"),
    ('{"process.rotation.rpm": 20}', "process.rotation.rpm=20"),
    ('{"control": "cohesionless", "process.rotation.rpm": 20.5}',
     "cohesionless control, process.rotation.rpm=20.5"),
    ("g", "g"),
])
def test_groups_have_readable_names(group, label):
    assert group_label(group) == label


def test_no_lower_limit_is_said_in_the_gsd_cells():
    compared = {"gsd_lower_limit": math.nan, "gsd_error_all": 1.6}
    assert dic.gsd_note(compared, "gsd_lower_limit_diameter") == "none located"
    assert dic.gsd_note(compared, "gsd_error_below_lower") == "(all bins: no lower limit)"
    assert dic.gsd_note(compared, "gsd_error_above_lower") == "(no lower limit)"
    located = {"gsd_lower_limit": 2e-7, "gsd_error_all": 1.6}
    assert dic.gsd_note(located, "gsd_error_below_lower") is None
    cg1 = {"gsd_lower_limit": math.nan, "gsd_error_all": math.nan}    # nothing compared
    assert dic.gsd_note(cg1, "gsd_lower_limit_diameter") is None
    assert dic.gsd_note(compared, "angle_error") is None


@pytest.fixture(scope="module")
def real_study(engine, tmp_path_factory):
    """A tiny real study: 2 CG1 replicas with their cohesionless twins and 2 We-CG2, the
    session's one (tests/apistudy.py, shared with the API tests; only read here)."""
    return api_study(engine, tmp_path_factory)


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.slow
def test_every_column_of_every_real_table_is_documented(real_study):
    seen = {}
    for folder in (layout.ANALYSIS_DIR, layout.REPORT_DIR):
        for path in sorted((real_study / folder).glob("*.csv")) + sorted(
                (real_study / folder).glob("*.parquet")):
            frame = (pd.read_parquet(path) if path.suffix == ".parquet"
                     else pd.read_csv(path))
            assert path.name in dic.TABLES, f"{path.name}: a table the dictionary lacks"
            seen[path.name] = undocumented(path.name, frame.columns)
    assert {layout.CONDITIONS_REPORT, layout.CONTROLS_TABLE, layout.GSD_SUMMARY_TABLE,
            layout.KINETICS_SUMMARY_TABLE} <= set(seen)
    assert not {t: cols for t, cols in seen.items() if cols}, (
        "columns without a dictionary entry: add them to ligwf/report/dictionary_entries.py "
        "and the table's columns in ligwf/report/dictionary.TABLES")
    summary = (real_study / layout.REPORT_DIR / layout.SUMMARY_REPORT).read_text()
    assert "cohesionless control" in summary and "| {} |" not in summary
    assert "GSD err below lower limit" in summary and "angle [deg]" in summary


def test_the_field_columns_of_the_dictionary_are_the_ones_the_report_writes():
    """The field criterion's columns (kernel widths, noise pieces) are listed once in
    analysis/records/field_errors and once in the dictionary: kept in step here, in the
    fast lane (the real-study test above found the noise pieces missing only in CI)."""
    from ligwf.inference import field_errors

    assert dic.FIELD_NOISE == field_errors.FIELD_NOISE_COLUMNS
    assert dic.FIELD_KERNEL_ERRORS == tuple(field_errors.KERNEL_COLUMNS.values())
    for column in (*dic.FIELD_NOISE, *dic.FIELD_KERNEL_ERRORS):
        assert not undocumented(layout.CONDITIONS_REPORT, [column]), column


def test_a_metric_is_documented_by_its_own_declaration():
    """Issue 48 item 4: a flow metric registered with a unit and a meaning is in the
    dictionary's flow, case and condition tables with its header, and in the generated page,
    with nothing else edited; one registered without a meaning is not documented (the
    real-table check then names it); unregistered, it is gone again."""
    from ligwf.analysis.flow import registry
    from ligwf.analysis.records.metrics import POSITIVE, MetricSpec
    from ligwf.analysis.records.statistics import MEAN

    def top(frame, geo, flow):
        return float(frame.positions[:, 2].max())

    spec = MetricSpec("bed_top_doc", "bed top [m]", "bed_top_doc", MEAN, POSITIVE, unit="m",
                      shown="mm", meaning="height of the highest particle centre")
    registry.register(spec, top)
    try:
        for table in (layout.FLOW_TABLE, layout.CASES_REPORT, layout.CONDITIONS_REPORT):
            assert dic.documented(table, "bed_top_doc"), table
        assert dic.documented(layout.CONDITIONS_REPORT, "bed_top_doc_lo")
        assert dic.header("bed_top_doc") == "bed top [mm]"
        assert dic.shown_value("bed_top_doc", 0.002) == 2.0
        page = dic.dictionary_markdown()
        assert "| `bed_top_doc` | m | mm | bed top | height of the highest particle centre |" in page
        assert not dic.documented(layout.GSD_TABLE, "bed_top_doc")
    finally:
        registry.unregister(spec.name)
    assert not dic.documented(layout.CASES_REPORT, "bed_top_doc")
    assert "bed_top_doc" not in dic.dictionary_markdown()
    bare = MetricSpec("bed_top_bare", "bed top [m]", "bed_top_bare", MEAN, POSITIVE)
    registry.register(bare, top)
    try:
        assert not dic.documented(layout.CASES_REPORT, "bed_top_bare")
    finally:
        registry.unregister(bare.name)


def test_metric_documentation_is_not_stored_in_the_flow_record():
    from ligwf.analysis.flow.registry import METRICS
    from ligwf.analysis.records.metrics import MetricSpec

    spec = METRICS["flowing_layer_thickness_mean"]
    stored = spec.to_json()
    assert not {"unit", "meaning", "shown"} & set(stored)
    back = MetricSpec.from_json(stored)
    assert back.meaning == "" and back.statistic == spec.statistic and back.label == spec.label
