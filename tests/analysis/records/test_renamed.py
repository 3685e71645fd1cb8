"""Analysis tables of the previous release read under today's column names
(ligwf.analysis.records.renamed): the flow table's angle once, the controls' share of
percolating frames as ``percolating_frames``."""

import io
import warnings

import pandas as pd
import pytest

from helpers import ROOT
from ligwf.analysis.records.flow import CaseFlow
from ligwf.analysis.records.renamed import RENAMED, current_names
from ligwf.api.tables import read_table
from ligwf.report import dictionary
from ligwf.analysis.records.controls import read_controls
from ligwf.report.controls import controls_markdown
from ligwf.study import layout

RESULTS = ROOT / "docs" / "results"


def _old(path, new_to_old: dict) -> str:
    """A committed table's text with its header as the previous release wrote it."""
    text = path.read_text()
    head, rest = text.split("\n", 1)
    return ",".join(new_to_old.get(c, c) for c in head.split(",")) + "\n" + rest


def test_old_flow_table_with_both_angles_keeps_one():
    old = pd.DataFrame({"case_id": ["a"], "angle_of_repose_mean": [40.5],
                        "angle_of_repose_std": [1.0], "angle_of_repose": [40.5]})
    with pytest.warns(FutureWarning, match="angle_of_repose_mean -> angle_of_repose"):
        t = current_names(old, layout.FLOW_TABLE)
    assert list(t.columns) == ["case_id", "angle_of_repose_std", "angle_of_repose"]
    assert t["angle_of_repose"].tolist() == [40.5]


def test_old_flow_table_with_the_mean_only_is_renamed():
    old = pd.DataFrame({"case_id": ["a"], "angle_of_repose_mean": [40.5]})
    with pytest.warns(FutureWarning):
        t = current_names(old, layout.FLOW_TABLE)
    assert list(t.columns) == ["case_id", "angle_of_repose"]


def test_current_tables_pass_unchanged_without_a_warning():
    for file in (layout.FLOW_TABLE, layout.CONTROLS_TABLE):
        t = pd.read_csv(RESULTS / "gsd_cg" / "analysis" / file)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            assert current_names(t, file) is t


def test_every_new_name_is_documented_and_no_old_one():
    for file, renames in RENAMED.items():
        for old, new in renames.items():
            assert dictionary.documented(file, new), (file, new)
            assert not dictionary.documented(file, old), (file, old)


def test_an_old_controls_table_reads_in_the_report_and_the_api(tmp_path):
    """The committed controls of the granules study, with the previous header: the report's
    controls section and verdict reader and the API get percolating_frames."""
    committed = RESULTS / "granules" / "controls.csv"
    analysis = tmp_path / layout.ANALYSIS_DIR
    analysis.mkdir()
    back = {new: old for old, new in RENAMED[layout.CONTROLS_TABLE].items()}
    (analysis / layout.CONTROLS_TABLE).write_text(_old(committed, back))
    with pytest.warns(FutureWarning, match="percolating -> percolating_frames"):
        table = read_controls(analysis)
    now = pd.read_csv(committed)
    pd.testing.assert_frame_equal(table, now)
    with pytest.warns(FutureWarning):
        lines = controls_markdown(analysis)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        assert lines == controls_markdown(committed.parent)   # the same section as today's
        api = read_table(analysis / layout.CONTROLS_TABLE)
    assert "percolating_frames" in api and "percolating" not in api


def test_an_old_flow_table_reads_in_the_api(tmp_path):
    committed = RESULTS / "we_vs_bo" / "analysis" / layout.FLOW_TABLE
    path = tmp_path / layout.FLOW_TABLE
    path.write_text(_old(committed, {"angle_of_repose": "angle_of_repose_mean"}))
    with pytest.warns(FutureWarning, match=str(path)):
        old = read_table(path)
    pd.testing.assert_frame_equal(old, read_table(committed))


def test_an_old_flow_record_summary_has_the_current_key():
    case = CaseFlow.from_json({"case_id": "a", "cg": 1.0, "rule": "none", "replica": 0,
                               "group": "{}", "steady_fraction": 0.5, "steady_from_step": 10,
                               "summary": {"angle_of_repose_mean": 40.5,
                                           "angle_of_repose_std": None}})
    assert case.summary["angle_of_repose"] == 40.5 and "angle_of_repose_mean" not in case.summary


def test_no_table_keeps_a_name_in_two_meanings():
    """percolating: a granule's flag only; the share of frames is percolating_frames."""
    flags = {t for t, spec in dictionary.TABLES.items() if "percolating" in spec.columns}
    assert flags == {layout.GRANULES_TABLE}
    assert dictionary.column("percolating", layout.GRANULES_TABLE).unit == "flag"
    for table in (layout.GSD_SUMMARY_TABLE, layout.CONTROLS_TABLE):
        assert dictionary.column("percolating_frames", table).unit == "1"


def test_csv_round_trip_of_the_committed_flow_table_keeps_one_angle():
    text = (RESULTS / "gsd_cg" / "analysis" / layout.FLOW_TABLE).read_text()
    t = pd.read_csv(io.StringIO(text))
    assert list(t.columns).count("angle_of_repose") == 1
    assert not any(c.startswith("angle_of_repose_mean") for c in t.columns)
