"""Extensibility: a flow metric defined here (one function, one registration line) reaches
the flow table and the report's case and condition tables with its interval, without
touching ligwf: on synthetic beds through the analysis record into the report's tables
(no engine), and on a real study (the shared wet study: two CG3 replicas) end to end."""

from __future__ import annotations

import dataclasses
import json
import math
import shutil

import numpy as np
import pandas as pd
import pytest

from ligwf.analysis.flow import registry as flow_metrics
from ligwf.analysis.flow.frame import frame_flow
from ligwf.analysis.flow.stage import flow_record, flow_table, measured_flow
from ligwf.analysis.records.flow import FlowRecord
from ligwf.analysis.records.metrics import POSITIVE, MetricSpec
from ligwf.analysis.records.statistics import MEAN
from ligwf.cli.main import main
from ligwf.study import layout
from ligwf.inference.study_tables import compare_to_cg1, condition_table, merge_analysis, metric_columns
from ligwf.inference.uncertainty import ConditionStats, case_series, report_metrics
from ligwf.report.table_sections import markdown_tables
from test_flow import bed
from wetdump import wet_study


def bed_top(frame, geo, flow) -> float:
    """Toy metric: the height of the highest particle centre above the drum axis (m)."""
    return float(frame.positions[:, 2].max() + geo.radius)


@pytest.fixture
def toy_metric():
    spec = flow_metrics.register(MetricSpec("bed_top", "bed top [m]", "bed_top", MEAN, POSITIVE), bed_top)
    yield spec
    flow_metrics.unregister(spec.name)


def synthetic_case(case_id: str, cg: float, replica: int, angles) -> object:
    """The flow record entry of a case whose steady frames are plane beds at ``angles``."""
    frames, flows, series = [], [], []
    for k, angle in enumerate(angles):
        frame, geo = bed(angle, seed=100 * replica + k, offset=0.002 * math.sin(k))
        frame = dataclasses.replace(frame, step=1000 * k, time=0.05 * k)
        flow = frame_flow(frame, geo)
        frames.append(frame)
        flows.append(flow)
        series.append(flow_metrics.frame_series(frame, geo, flow))
    head = dict(case_id=case_id, cg=cg, rule="none" if cg == 1 else "weber", replica=replica,
                group="{}", steady_fraction=0.0, steady_from_step=0.0)
    return measured_flow(head, frames, flows, series, list(range(len(frames))), geo)


def synthetic_cases(flow: FlowRecord) -> pd.DataFrame:
    """The report's case table columns a finished run gives (run costs invented)."""
    rows = []
    for k, c in enumerate(flow.cases.values()):
        cost = 100.0 + 10 * k
        rows.append({"case_id": c.case_id, "group": c.group, "cg": c.cg, "rule": c.rule,
                     "replica": c.replica, "particles": 1000, "original_particles": 1000,
                     "dt": 1e-5, "steps": 1000, "wall_seconds": cost, "core_seconds": cost,
                     "fill_core_seconds": 1.0, "settle_core_seconds": 1.0,
                     "production_core_seconds": cost, "production_core_rate": cost,
                     "production_core_rate_k": cost, "production_wall_rate": cost})
    return pd.DataFrame(rows)


def test_a_registered_flow_metric_reaches_the_report_tables_on_synthetic_beds(toy_metric,
                                                                              tmp_path):
    rng = np.random.default_rng(7)
    flows = {cid: synthetic_case(cid, cg, rep, 25 + 3 * rng.standard_normal(10))
             for cid, cg, rep in [("cg1-none-r0", 1, 0), ("cg1-none-r1", 1, 1),
                                  ("cg2-weber-r0", 2, 0), ("cg2-weber-r1", 2, 1)]}
    path = tmp_path / "flow_profiles.json"
    path.write_text(flow_record(flows, {}, 0.0, []).to_text())
    flow = FlowRecord.read(path)                      # what the report reads: the record
    assert flow.metric("bed_top") == toy_metric
    table = flow_table(flow).set_index("case_id")     # the analysis' flow table
    top = [v for v in flow.cases["cg2-weber-r0"].series["bed_top"]]
    assert table.loc["cg2-weber-r0", "bed_top"] == pytest.approx(np.mean(top))

    cases = merge_analysis(synthetic_cases(flow), tmp_path, flow)
    assert cases.set_index("case_id").loc["cg2-weber-r0", "bed_top"] == pytest.approx(np.mean(top))
    stats = ConditionStats(case_series(list(cases["case_id"]), flow, pd.DataFrame()), 200, 1,
                           report_metrics(flow))
    df = compare_to_cg1(cases, stats, list(flow.error_metrics))
    cond = condition_table(df, stats, metric_columns(flow))
    for _, row in cond.iterrows():
        assert row["replicas"] == 2
        lo, value, hi, se = (row[f"bed_top{s}"] for s in ("_lo", "", "_hi", "_se"))
        assert all(math.isfinite(x) for x in (lo, value, hi, se)) and lo <= value <= hi
        assert hi - lo >= se > 0                   # never narrower than the within-run error
        assert lo >= 0                             # bounded: the spec's POSITIVE
    md = markdown_tables(df, cond, flow)
    heads = [line for line in md.splitlines() if line.startswith("| case |")
             or line.startswith("| group | CG | rule | replicas")]
    assert len(heads) == 2 and all("bed top [m]" in h for h in heads)
    lines = md.splitlines()
    column = heads[1].split("|").index(" bed top [m] ")
    row = lines[lines.index(heads[1]) + 2].split("|")   # first condition: value [lo, hi]
    assert f"{cond['bed_top'].iloc[0]:.3g} [{cond['bed_top_lo'].iloc[0]:.3g}, " in row[column]


@pytest.mark.engine
def test_a_registered_flow_metric_reaches_the_report_tables_on_a_real_study(
        toy_metric, engine, tmp_path_factory):
    """``ligwf analyse`` on real dumps (two CG3 replicas) evaluates the toy metric on every
    steady frame; the report's tables built from what it wrote carry it with an interval.
    (The shared wet study's manifests hold no run costs, so the case table's cost columns
    are invented, as in the synthetic test.)"""
    study = tmp_path_factory.mktemp("toy_metric") / "study"
    shutil.copytree(wet_study(engine, tmp_path_factory), study)
    record = json.loads((study / "study.json").read_text())
    record["analysis"] = {"granules": "communities", "bootstrap": 50, "sensitivity_frames": 0}
    (study / "study.json").write_text(json.dumps(record))
    assert main(["analyse", str(study), "--no-vtu"]) == 0

    flow = FlowRecord.read(study / "analysis" / layout.FLOW_PROFILES)
    assert flow.metric("bed_top") == toy_metric
    series = flow.cases["cg3-weber-r0"].series["bed_top"]
    assert len(series) >= 2 and all(v is not None and v > 0 for v in series)
    table = pd.read_csv(study / "analysis" / layout.FLOW_TABLE).set_index("case_id")
    assert table.loc["cg3-weber-r0", "bed_top"] == pytest.approx(np.mean(series))

    cases = merge_analysis(synthetic_cases(flow), study / "analysis", flow)
    assert cases.set_index("case_id").loc["cg3-weber-r0", "bed_top"] == pytest.approx(
        np.mean(series))
    stats = ConditionStats(case_series(list(cases["case_id"]), flow, pd.DataFrame()), 50, 1,
                           report_metrics(flow))
    cond = condition_table(compare_to_cg1(cases, stats, list(flow.error_metrics)), stats,
                           metric_columns(flow))
    row = cond.iloc[0]
    assert row["replicas"] == 2
    lo, value, hi = row["bed_top_lo"], row["bed_top"], row["bed_top_hi"]
    assert all(math.isfinite(x) for x in (lo, value, hi)) and lo <= value <= hi
    assert hi - lo >= row["bed_top_se"] > 0        # never narrower than the within-run error


def test_registration_refuses_duplicates_and_unknown_series():
    with pytest.raises(ValueError, match="already registered"):
        flow_metrics.register(MetricSpec("angle_of_repose", "again", "angle"))
    with pytest.raises(ValueError, match="no series 'nowhere'"):
        flow_metrics.register(MetricSpec("lost", "lost", "nowhere"))
    with pytest.raises(ValueError, match="unknown statistic"):
        MetricSpec("odd", "odd", "angle", "median")
    assert "lost" not in flow_metrics.METRICS
