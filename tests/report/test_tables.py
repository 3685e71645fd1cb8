"""ligwf.inference.study_tables on hand-made case tables: speedups and errors against the CG1 cases
of the sweep group, the condition table (intervals, floors, marks, GSD bands, costs), the
noise-floor table, and the granule columns restricted to the steady window.

Runs are constant over their frames wherever an exact answer is wanted, so every expected
number below is arithmetic on the table written in the test.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from ligwf.analysis.records import statistics as st
from ligwf.analysis.records.flow import CaseFlow, FlowRecord
from ligwf.analysis.records.metrics import POSITIVE, MetricSpec
from ligwf.inference.study_tables import compare_to_cg1, condition_table, merge_analysis, \
    noise_floor_table
from ligwf.inference.uncertainty import ConditionStats
from ligwf.study import layout

T1 = 12.706204736174704      # Student t, 97.5 %, 1 degree of freedom

ANGLE = MetricSpec("angle", "angle of repose", "angle", st.MEAN, POSITIVE)
ANGLE_ERROR = MetricSpec("angle_error", "angle error", "angle", st.RELATIVE_ERROR, POSITIVE)
METRICS = {m.name: m for m in (ANGLE, ANGLE_ERROR)}

#: case id, group, cg, rule, angle (constant over 40 frames), production core-s per s,
#: original particles, core-s
CASES = [
    ("cg1-r0", "g", 1.0, "none", 30.0, 200.0, 2000, 2.0),
    ("cg1-r1", "g", 1.0, "none", 33.0, 180.0, 2000, 8.0),
    ("cg1-r2", "g", 1.0, "none", 27.0, 220.0, 2000, 4.0),
    ("cg2-w-r0", "g", 2.0, "weber", 34.0, 5.0, 1000, 2.0),
    ("cg2-w-r1", "g", 2.0, "weber", 36.0, 5.0, 1000, 8.0),
    ("cg2-b-r0", "g", 2.0, "bond", 31.0, 10.0, 1000, 3.0),
    ("cg3-r0", "h", 3.0, "weber", 40.0, 1.0, 1000, 1.0),      # a group without CG1
]


def case_table() -> pd.DataFrame:
    rows = []
    for cid, group, cg, rule, _angle, rate, original, core in CASES:
        rows.append({"case_id": cid, "group": group, "cg": cg, "rule": rule,
                     "particles": int(original / cg**3), "original_particles": original,
                     "dt": 1e-5 * cg, "steps": 1000, "core_seconds": core,
                     "production_core_rate": rate, "production_wall_rate": rate / 2,
                     "fill_core_seconds": 1.0, "settle_core_seconds": 2.0,
                     "production_core_seconds": core,
                     "gsd_error_below_lower": 0.3 if cg == 2 else math.nan,
                     "gsd_error_below_lower_lo": 0.2 if cg == 2 else math.nan,
                     "gsd_error_below_lower_hi": 0.5 if cg == 2 else math.nan})
    return pd.DataFrame(rows)


def stats() -> ConditionStats:
    series = {cid: {"angle": np.full(40, angle)} for cid, _g, _c, _r, angle, *_ in CASES}
    return ConditionStats(series, 2000, 1, METRICS)


def test_speedup_is_per_original_particle_against_the_groups_cg1_mean():
    """CG1: 200 / 180 / 220 core-s per s on a 2000-particle slice = 0.1 per particle (mean);
    CG2 weber 5 per s on a 1000-particle slice = 0.005 -> speedup 20; bond 10 -> 10; CG1
    cases against their own mean (1 for the middle one). A group without CG1 gets none."""
    df = compare_to_cg1(case_table(), stats(), [ANGLE_ERROR]).set_index("case_id")
    cg1_per_particle = (200.0 + 180.0 + 220.0) / 3 / 2000
    assert df.at["cg2-w-r0", "speedup_core"] == pytest.approx(cg1_per_particle / (5 / 1000))
    assert df.at["cg2-w-r0", "speedup_core"] == pytest.approx(20.0)
    assert df.at["cg2-b-r0", "speedup_core"] == pytest.approx(10.0)
    assert df.at["cg1-r0", "speedup_core"] == pytest.approx(1.0)
    assert df.at["cg1-r2", "speedup_core"] == pytest.approx(200.0 / 220.0)
    assert df.at["cg2-w-r0", "speedup_wall"] == pytest.approx(20.0)     # wall = core / 2
    assert "speedup_core" not in df or math.isnan(df.at["cg3-r0", "speedup_core"])


def test_case_errors_are_against_the_mean_of_the_groups_cg1_runs():
    """CG1 mean angle 30: 34 -> 4/30, 36 -> 6/30, 31 -> 1/30, the CG1 runs themselves
    0 / 3/30 / 3/30; no error without a CG1 in the group."""
    df = compare_to_cg1(case_table(), stats(), [ANGLE_ERROR]).set_index("case_id")
    expected = {"cg1-r0": 0.0, "cg1-r1": 3 / 30, "cg1-r2": 3 / 30, "cg2-w-r0": 4 / 30,
                "cg2-w-r1": 6 / 30, "cg2-b-r0": 1 / 30}
    for cid, err in expected.items():
        assert df.at[cid, "angle_error"] == pytest.approx(err, rel=1e-13, abs=1e-15), cid
    assert "angle_error" not in df or math.isnan(df.at["cg3-r0", "angle_error"])


def condition_rows() -> pd.DataFrame:
    df = compare_to_cg1(case_table(), stats(), [ANGLE_ERROR])
    table = condition_table(df, stats(), ["core_seconds", "angle", "angle_error",
                                          "gsd_error_below_lower"])
    return table.set_index(["group", "cg", "rule"])


def test_condition_rows_one_per_group_level_and_rule():
    table = condition_rows()
    assert list(table.index) == [("g", 1.0, "none"), ("g", 2.0, "bond"), ("g", 2.0, "weber"),
                                 ("h", 3.0, "weber")]
    assert list(table["replicas"]) == [3, 1, 2, 1]
    assert table.loc[("g", 2.0, "weber"), "particles"] == 125
    assert table.loc[("g", 1.0, "none"), "fill_core_seconds"] == 1.0


def test_condition_value_interval_floor_and_mark():
    """CG2 weber: angle 35 with the two replicas' spread widened by sqrt(2): 35 -+ sqrt(2);
    its error |35 - 30| / 30 = 1/6 is above the CG1 floor (each CG1 replica against the
    mean of the other two, the largest: 33 vs 28.5 -> 4.5 / 28.5 = 0.158) but its interval
    (replicas at 4/30 and 6/30) holds the floor: undecided, and too close to it for a
    replica count; bond's 1/30 is below it, from one replica without an interval: undecided
    too. The CG1 row is the reference."""
    table = condition_rows()
    weber, bond, cg1 = (table.loc[k] for k in [("g", 2.0, "weber"), ("g", 2.0, "bond"),
                                               ("g", 1.0, "none")])
    assert weber["angle"] == pytest.approx(35.0)
    assert weber["angle_lo"] == pytest.approx(35.0 - math.sqrt(2), rel=1e-12)
    assert weber["angle_hi"] == pytest.approx(35.0 + math.sqrt(2), rel=1e-12)
    assert weber["angle_error"] == pytest.approx(5.0 / 30.0, rel=1e-13)
    floor = 4.5 / 28.5
    for row in (weber, bond, cg1):
        assert row["angle_error_floor"] == pytest.approx(floor, rel=1e-13)
        assert row["angle_error_floor_source"] == "measured over 3 CG1 replicas"
    assert weber["angle_error_lo"] < floor < weber["angle_error_hi"]
    assert weber["angle_error_vs_floor"].startswith("undecided: the error is close to the floor")
    assert bond["angle_error"] == pytest.approx(1.0 / 30.0, rel=1e-13)
    assert bond["angle_error_vs_floor"] == "undecided: 1 replica, no interval (add CG-n replicas)"
    assert math.isnan(bond["angle_lo"])                  # one replica: no interval
    assert cg1["angle_error_vs_floor"] == "reference"
    assert cg1["angle_error"] == pytest.approx(0.0, abs=1e-15)


def test_a_group_without_cg1_has_no_error_floor_or_mark():
    h = condition_rows().loc[("h", 3.0, "weber")]
    assert h["angle"] == pytest.approx(40.0)
    assert math.isnan(h["angle_error"]) and math.isnan(h["angle_error_floor"])
    assert h["angle_error_floor_source"] == "none"
    assert h["angle_error_vs_floor"] == "–"


def test_costs_get_a_t_interval_on_the_log_and_gsd_errors_their_own_band():
    """core-s 2 and 8 (CG2 weber): mean 5, geometric mean 4, log half-width
    t(0.975, 1) ln(4) / 2; the GSD error comes pooled from the analysis with its band."""
    weber = condition_rows().loc[("g", 2.0, "weber")]
    half = T1 * math.log(4.0) / 2.0
    assert weber["core_seconds"] == 5.0
    assert weber["core_seconds_lo"] == pytest.approx(4.0 * math.exp(-half), rel=1e-12)
    assert weber["core_seconds_hi"] == pytest.approx(4.0 * math.exp(half), rel=1e-12)
    assert (weber["gsd_error_below_lower"], weber["gsd_error_below_lower_lo"],
            weber["gsd_error_below_lower_hi"]) == (0.3, 0.2, 0.5)


def test_noise_floor_table_cg1_value_and_scatter():
    """CG1 angles 30 / 33 / 27: value 30, sample std 3; a group without CG1 has no row."""
    nf = noise_floor_table(case_table(), stats())
    assert list(nf["group"]) == ["g"] and list(nf["metric"]) == ["angle"]
    row = nf.iloc[0]
    assert row["cg1_value"] == pytest.approx(30.0)
    assert row["cg1_scatter"] == pytest.approx(3.0, rel=1e-13)
    assert row["source"] == "std over 3 CG1 replicas"


def _flow_record(steady_from: dict[str, int]) -> FlowRecord:
    cases = {}
    for cid, group, cg, rule, angle, *_ in CASES:
        cases[cid] = CaseFlow(case_id=cid, cg=cg, rule=rule, replica=0, group=group,
                              steady_fraction=0.25, steady_from_step=steady_from.get(cid, 0),
                              values={"angle": angle}, series={"angle": [angle] * 4},
                              times=[0.1, 0.2, 0.3, 0.4])
    return FlowRecord("auto", (ANGLE, ANGLE_ERROR), cases)


def test_granule_columns_come_from_the_steady_window_frames_only(tmp_path):
    """Largest granule per frame: frames before the case's steady window and frames not
    'ok' are left out: cg1-r0 keeps steps 100 (0.2) and 200 (1.0): mean 0.6, one-granule
    share (above 0.99) 1/2. The GSD summary's errors join by group, level and rule."""
    frames = pd.DataFrame({
        "case_id": ["cg1-r0"] * 4 + ["cg2-w-r0"] * 2,
        "step": [0, 100, 200, 300, 100, 200],
        "status": ["ok", "ok", "ok", "unreadable", "ok", "ok"],
        "largest_fraction": [0.9, 0.2, 1.0, 0.7, 0.3, 0.5]})
    frames.to_csv(tmp_path / layout.FRAMES_TABLE, index=False)
    pd.DataFrame({"group": ["g"], "cg": [2.0], "rule": ["weber"], "error_below_lower": [0.25],
                  "error_below_lower_lo": [0.1], "error_below_lower_hi": [0.4]}).to_csv(
        tmp_path / layout.GSD_SUMMARY_TABLE, index=False)
    cases = case_table().drop(columns=["gsd_error_below_lower", "gsd_error_below_lower_lo",
                                       "gsd_error_below_lower_hi"])
    df = merge_analysis(cases, tmp_path, _flow_record({"cg1-r0": 100, "cg2-w-r0": 150}))
    df = df.set_index("case_id")
    assert df.at["cg1-r0", "largest_cluster_fraction"] == pytest.approx(0.6)
    assert df.at["cg1-r0", "one_granule_frame_share"] == pytest.approx(0.5)
    assert df.at["cg2-w-r0", "largest_cluster_fraction"] == pytest.approx(0.5)
    assert df.at["cg1-r0", "angle"] == 30.0 and df.at["cg1-r0", "steady_from_step"] == 100
    assert df.at["cg2-w-r0", "gsd_error_below_lower"] == 0.25
    assert df.at["cg2-w-r1", "gsd_error_below_lower_hi"] == 0.4
    assert math.isnan(df.at["cg2-b-r0", "gsd_error_below_lower"])
    assert math.isnan(df.at["cg3-r0", "largest_cluster_fraction"])
