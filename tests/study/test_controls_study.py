"""A tiny study with a cohesionless twin, end to end: the twin runs beside its wet case,
the analysis measures both with every candidate definition, and the report prints the
control table and the verdict of the study's own definition (real engine runs)."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from ligwf.analysis.control_verdict import verdict
from ligwf.cli.main import main

from helpers import ROOT

pytestmark = [pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]

TINY = ROOT / "tests" / "workflows" / "tiny_study.yaml"


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("controls") / "tiny"
    rc = main(["study", str(TINY), "--out", str(out), "--no-snapshots",
               "--set", "sweep.cg_levels=[1]", "--set", "sweep.controls=[cohesionless]",
               "--set", "scene.process.run_time=0.6", "--set", "scene.numerics.dump_interval=0.02",
               "--set", "analysis.granules=held", "--set", "analysis.hold_time=0.1"])
    assert rc == 0
    return out


def test_twin_runs_beside_its_case_with_the_bridge_forces_off(study):
    wet = json.loads((study / "cg1-none-r0" / "scene.json").read_text())
    twin = json.loads((study / "cg1-none-r0_cohesionless" / "scene.json").read_text())
    assert twin["varied"] == {"control": "cohesionless"}
    assert twin["scaled"]["surface_tension"] == pytest.approx(wet["scaled"]["surface_tension"] / 1e3)
    assert twin["scaled"]["viscosity"] == pytest.approx(wet["scaled"]["viscosity"] / 1e3)
    assert twin["scaled"]["seeds"] == wet["scaled"]["seeds"]
    for d in ("cg1-none-r0", "cg1-none-r0_cohesionless"):
        assert json.loads((study / d / "manifest.json").read_text())["status"] == "done"


def test_controls_table_measures_every_definition_on_both(study):
    table = pd.read_csv(study / "analysis" / "controls.csv")
    assert set(table["case_id"]) == {"cg1-none-r0"}
    assert set(table["twin_id"]) == {"cg1-none-r0_cohesionless"}
    assert table["definition"].iloc[0] == "study definition (held)"
    assert {"communities", "source_components_angle30", "held_0.25s"} <= set(table["definition"])
    # frame-wise components of every bridge: the whole wet bed, in the twin as well (bridges
    # form in both; only their forces differ): a definition blind to cohesion
    comp = table.set_index("definition").loc["bridge_components"]
    assert comp["share_10"] > 0.9 and comp["twin_share_10"] > 0.9
    # the stored verdict is the pre-registered criteria applied to the stored numbers
    for _, r in table.iterrows():
        wet = {k: r[k] for k in r.index if not k.startswith("twin_")}
        twin = {k.removeprefix("twin_"): r[k] for k in r.index if k.startswith("twin_")}
        assert verdict(wet, twin, r["definition"]) == (bool(r["passes"]), r["verdict"])
    # the held definition is deterministic (no optimiser, contact order irrelevant)
    assert table.set_index("definition").loc["study definition (held)", "ari_order"] == 1.0


def test_report_prints_the_control_section_and_its_verdict(study):
    md = (study / "report" / "summary.md").read_text()
    table = pd.read_csv(study / "analysis" / "controls.csv")
    assert "## Granule controls (wet bed / cohesionless twin)" in md
    assert table["verdict"].iloc[0] in md
    html = (study / "report" / "index.html").read_text()
    assert "Granule controls" in html and "cg1-none-r0_cohesionless" in html
