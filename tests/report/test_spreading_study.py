"""Placed liquid's spreading in a real study (issue 47 item 2), on the real engine: ``ligwf
study`` of a tiny drum with one wet sphere in a dry bed at CG1 and We-CG2 writes each
case's spreading series into the flow record, ``spreading.csv`` (CG2 against CG1) and the
report's section, and open_study reads it; a study without placed liquid writes the table
with no rows (tests/api/test_api.py)."""

from __future__ import annotations

import pandas as pd
import pytest

import ligwf
from helpers import ROOT
from ligwf.analysis.records.flow import FlowRecord
from ligwf.cli.main import main
from ligwf.inference.spreading import LEVEL_COLUMNS

TINY = ROOT / "tests" / "workflows" / "tiny_study.yaml"
pytestmark = [pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]


def test_placed_liquid_spreads_and_is_reported(engine, tmp_path):
    out = tmp_path / "spread"
    rc = main(["study", str(TINY), "--out", str(out), "--mesh-cache", str(tmp_path / "m"),
               "--set", "scene.process.fill_fraction=0.4",
               "--set", "scene.liquid.placement=granules",
               "--set", "scene.liquid.wet_granules={count: 1, radius: 0.0045, "
                        "liquid_content: 0.05}",
               "--set", "scene.liquid.viscosity=0.01", "--set", "sweep.rules=[weber]",
               "--set", "sweep.replicas={1: 2, 2: 2}",
               "--set", "scene.analysis.contact_dumps=false", "--no-snapshots"])
    assert rc == 0
    record = FlowRecord.read(out / "analysis" / "flow_profiles.json")
    for case in record.cases.values():
        s = case.spreading
        assert 0 < s["dry_particles"] < s["particles"], case.case_id
        # a little passes on while the bed settles, before production starts
        assert s["revolutions"][0] == 0.0 and 0.0 <= s["dry_content_share"][0] < 0.01
        # the engine passes liquid on at ruptures: the dry particles gain, never lose it all
        assert max(s["dry_content_share"]) > 0.0
        assert all(0.0 <= v <= 1.0 for v in s["dry_wet_share"])
    table = pd.read_csv(out / "report" / "spreading.csv")
    assert list(table.columns) == list(LEVEL_COLUMNS)
    assert table["cg"].tolist() == [2.0] and table["cg1_runs"].tolist() == [2]
    assert table["expected_ratio"].tolist() == [4.0]
    summary = (out / "report" / "summary.md").read_text()
    assert "## Liquid spreading" in summary and "cg2-weber-r1" in summary
    assert len(ligwf.open_study(out).spreading) == 1
