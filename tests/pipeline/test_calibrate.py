"""ligwf calibrate-control: the candidates it plans (pure), its choice (pure), and a real
calibration of a tiny CG1 bed with the engine."""

from __future__ import annotations

import pandas as pd
import pytest

from helpers import ROOT
from ligwf.errors import ConfigError
from ligwf.pipeline.calibrate import CalibrationGrid, calibration_workflows, choose
from ligwf.scene.workflow import expand
from ligwf.yamlio import read_yaml_mapping

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


def test_candidates_are_cohesionless_twins_over_the_grid_at_cg1():
    raw = read_yaml_mapping(TINY, "workflow")
    ref, cands = calibration_workflows(raw, CalibrationGrid((0.5, 1.0), (0.0, 0.3), 0.5))
    wf_ref, wf_c = expand(ref), expand(cands)
    assert [c.cg for c in wf_ref.cases] == [1.0]
    assert wf_ref.cases[0].scene.liquid.surface_tension == pytest.approx(0.024)
    assert len(wf_c.cases) == 4 and {c.cg for c in wf_c.cases} == {1.0}
    assert {(c.scene.particles.friction, c.scene.particles.rolling_friction)
            for c in wf_c.cases} == {(0.5, 0.0), (0.5, 0.3), (1.0, 0.0), (1.0, 0.3)}
    assert all(c.scene.liquid.surface_tension == pytest.approx(0.024e-3) for c in wf_c.cases)
    assert all(c.scene.process.run_time == 0.5 for c in wf_c.cases)


def test_a_dry_scene_and_bad_grids_are_refused():
    raw = read_yaml_mapping(TINY, "workflow")
    raw["scene"]["liquid"] = {"model": "none"}
    with pytest.raises(ConfigError, match="dry"):
        calibration_workflows(raw, CalibrationGrid())
    with pytest.raises(ConfigError, match="--rolling-friction"):
        CalibrationGrid(rolling_friction=())
    with pytest.raises(ConfigError, match="--run-time"):
        CalibrationGrid(run_time=-1.0)


def test_choice_matches_the_angle_first_then_the_fluctuation():
    ref = {"angle_deg": 40.0, "angle_std_deg": 5.0}
    cands = pd.DataFrame({"friction": [0.5, 0.8, 1.0], "rolling_friction": [0.0, 0.3, 0.6],
                          "angle_deg": [35.0, 39.5, 40.8], "angle_std_deg": [1.0, 1.5, 3.0]})
    out = choose(ref, cands, 1.0)
    assert list(out["matched"]) == [False, True, True]
    assert list(out["chosen"]) == [False, False, True]      # within 1 deg, std closest
    far = choose({"angle_deg": 50.0, "angle_std_deg": 5.0}, cands, 1.0)
    assert not far["matched"].any() and list(far["chosen"]) == [False, False, True]


@pytest.mark.engine
@pytest.mark.slow
def test_calibration_runs_candidates_and_names_the_closest(tmp_path):
    """A CG1 bed of 84 beads of 4.5 mm (runner_tiny's CG3 size as originals): the wet
    reference and two candidates, each 0.3 s; the table, the choice and the exit code."""
    import subprocess
    import sys

    out = tmp_path / "cal"
    cmd = [sys.executable, "-m", "ligwf.cli.main", "calibrate-control", str(TINY), "--out",
           str(out), "--set", "scene.particles.size_distribution=[{diameter: 0.0045, fraction: 1.0}]",
           "--set", "scene.numerics.dump_interval=0.02", "--friction", "0.5,1.0",
           "--rolling-friction", "0", "--run-time", "0.3", "--tolerance", "45"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    table = pd.read_csv(out / "calibration.csv")
    assert list(table["role"]) == ["wet reference", "candidate", "candidate"]
    assert sorted(table["friction"][1:]) == [0.5, 1.0]
    assert table["angle_deg"].notna().all() and (table["frames"] > 5).all()
    assert table["chosen"].sum() == 1
    assert "sweep.flow_match: {friction:" in proc.stdout
    # the named knobs make a workflow with a flow_matched twin that validates
    chosen = table[table["chosen"]].iloc[0]
    raw = read_yaml_mapping(TINY, "workflow")
    raw["sweep"].update(controls=["flow_matched"], control_cg_levels=[3],
                        flow_match={"friction": float(chosen["friction"]),
                                    "rolling_friction": float(chosen["rolling_friction"])})
    twins = [c for c in expand(raw).cases if c.case_id.endswith("_flow_matched")]
    assert twins and all(t.scene.particles.friction == chosen["friction"] for t in twins)


def test_a_flow_matched_twin_is_the_cohesionless_twin_with_the_named_friction():
    raw = read_yaml_mapping(TINY, "workflow")
    raw["sweep"].update(controls=["cohesionless", "flow_matched"], control_cg_levels=[3],
                        flow_match={"friction": 0.9, "rolling_friction": 0.4})
    cases = {c.case_id: c for c in expand(raw).cases}
    wet, twin = cases["cg3-weber-r0"], cases["cg3-weber-r0_flow_matched"]
    plain = cases["cg3-weber-r0_cohesionless"]
    assert twin.scene.particles.friction == 0.9 and twin.scene.particles.rolling_friction == 0.4
    assert plain.scene.particles.friction == wet.scene.particles.friction == 0.5
    assert twin.scene.liquid.surface_tension == plain.scene.liquid.surface_tension
    assert dict(twin.varied)["control"] == "flow_matched"
    raw["sweep"].pop("flow_match")
    with pytest.raises(ConfigError, match="sweep.flow_match is missing"):
        expand(raw)
