"""A tiny study end to end: ligwf study = run + analyse + report, numbers checked against
the manifests and the analysis outputs (not just the presence of files)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pandas as pd
import pytest

from ligwf.cli.main import main

from helpers import ROOT

pytestmark = [pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]

TINY = ROOT / "tests" / "workflows" / "tiny_study.yaml"


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("study") / "tiny"
    rc = main(["study", str(TINY), "--out", str(out), "--mesh-cache", str(out.parent / "meshes")])
    assert rc == 0
    return out


def test_every_case_done_and_reported(study):
    cases = pd.read_csv(study / "report" / "cases.csv")
    ids = [c["case_id"] for c in json.loads((study / "study.json").read_text())["cases"]]
    assert sorted(cases["case_id"]) == sorted(ids)
    for cid in ids:
        man = json.loads((study / cid / "manifest.json").read_text())
        assert man["status"] == "done"
        row = cases.set_index("case_id").loc[cid]
        assert row["core_seconds"] == pytest.approx(man["core_seconds"])
        assert row["wall_seconds"] == pytest.approx(man["wall_seconds"])
        assert row["steps"] == man["steps_done"]


def test_speedup_and_errors_against_cg1(study):
    cases = pd.read_csv(study / "report" / "cases.csv").set_index("case_id")
    flow = pd.read_csv(study / "analysis" / "flow.csv").set_index("case_id")
    frames = pd.read_csv(study / "analysis" / "frames.csv")
    rate = cases["production_core_seconds"] / cases["production_seconds"]
    assert np.allclose(cases["simulated_seconds"], cases["steps"] * cases["dt"])
    assert np.allclose(cases["production_core_rate"], rate)
    assert np.allclose(cases["production_core_rate_k"],
                       rate / cases["original_particles"] * 1000)
    rate = rate / cases["original_particles"]        # speedups on the original system
    ang1 = flow.loc["cg1-none-r0", "angle_of_repose"]
    for cid, row in cases.iterrows():
        assert row["speedup_core"] == pytest.approx(rate["cg1-none-r0"] / rate[cid])
        assert row["angle_of_repose"] == pytest.approx(flow.loc[cid, "angle_of_repose"])
        assert row["angle_error"] == pytest.approx(abs(row["angle_of_repose"] - ang1) / ang1)
        fr = frames[(frames["case_id"] == cid) & (frames["status"] == "ok")
                    & (frames["step"] >= flow.loc[cid, "steady_from_step"])]
        assert row["largest_cluster_fraction"] == pytest.approx(fr["largest_fraction"].mean())
    assert cases.loc["cg1-none-r0", "profile_error"] == pytest.approx(0.0)
    # CG2 is cheaper than CG1 (8x fewer particles, 2x fewer steps)
    assert (cases[cases["cg"] == 2]["speedup_core"] > 2).all()


def test_gsd_errors_and_condition_means(study):
    cases = pd.read_csv(study / "report" / "cases.csv")
    conds = pd.read_csv(study / "report" / "conditions.csv")
    summary = pd.read_csv(study / "analysis" / "gsd_summary.csv")
    for _, c in conds.iterrows():
        sub = cases[(cases["cg"] == c["cg"]) & (cases["rule"] == c["rule"])]
        assert c["replicas"] == len(sub) == (1 if c["cg"] == 1 else 2)
        assert c["speedup_core"] == pytest.approx(sub["speedup_core"].mean())
        assert c["angle_of_repose"] == pytest.approx(sub["angle_of_repose"].mean())
        if c["cg"] > 1:
            s = summary[(summary["cg"] == c["cg"]) & (summary["rule"] == c["rule"])].iloc[0]
            for e in ("error_below_lower", "error_above_lower", "error_all", "lower_limit"):
                assert c[f"gsd_{e}"] == pytest.approx(s[e], nan_ok=True)
            lo, hi = c["angle_of_repose_lo"], c["angle_of_repose_hi"]
            assert lo <= c["angle_of_repose"] <= hi


def test_gsd_pooling_table_and_report_section(study):
    """Pools of K = 1 and 2 of each CG2 condition's two replicas against CG1 (one CG1
    replica: no noise-floor rows); the report shows the section."""
    pooled = pd.read_csv(study / "analysis" / "gsd_pooling.csv")
    for rule in ("weber", "bond"):
        sub = pooled[(pooled["cg"] == 2) & (pooled["rule"] == rule)]
        assert sorted(zip(sub["k"], sub["pool"])) == [(1, "0"), (1, "1"), (2, "0+1")]
        assert (sub["frames"] > 0).all()
    assert "noise floor" not in set(pooled["rule"])
    md = (study / "report" / "summary.md").read_text()
    assert "## GSD size limit and replica pooling" in md


BOUNDS = {"rigid_frame_share": (0, 1), "largest_cluster_fraction": (0, 1),
          "one_granule_frame_share": (0, 1), "angle_of_repose": (-90, 90)}
POSITIVE = ("core_seconds", "wall_seconds", "production_core_rate", "speedup_core",
            "speedup_wall", "angle_error", "profile_error", "angle_of_repose_std",
            "rms_speed_rel_fluctuation")


def test_intervals_respect_within_run_noise_and_bounds(study):
    """No interval in the report is narrower than the within-run standard error of its
    metric; no bounded quantity has a bound outside its range; one replica: no interval."""
    conds = pd.read_csv(study / "report" / "conditions.csv")
    profiles = json.loads((study / "analysis" / "flow_profiles.json").read_text())["cases"]
    cases = pd.read_csv(study / "report" / "cases.csv")
    checked = 0
    for _, c in conds.iterrows():
        for col in [k[:-3] for k in conds.columns if k.endswith("_lo")]:
            lo, hi, v = c[f"{col}_lo"], c[f"{col}_hi"], c[col]
            if c["replicas"] < 2 and not col.startswith("gsd_"):
                assert np.isnan(lo) and np.isnan(hi), col
                continue
            if np.isnan(lo):
                continue
            assert lo <= v <= hi, col
            se = c.get(f"{col}_se", np.nan)
            if np.isfinite(se):
                assert hi - lo >= se, col
                checked += 1
            if col in BOUNDS:
                assert BOUNDS[col][0] <= lo and hi <= BOUNDS[col][1], col
            if col in POSITIVE:
                assert lo >= 0, col
        if c["replicas"] >= 2:   # independently: the angle's band vs the frames' plain SE
            ids = cases[(cases["cg"] == c["cg"]) & (cases["rule"] == c["rule"])]["case_id"]
            ses = [np.nanstd(np.array(profiles[i]["series"]["angle"], float), ddof=1)
                   / np.sqrt(len(profiles[i]["series"]["angle"])) for i in ids]
            naive = np.sqrt(np.sum(np.square(ses))) / len(ses)
            assert c["angle_of_repose_hi"] - c["angle_of_repose_lo"] >= naive
    assert checked > 0
    md = (study / "report" / "summary.md").read_text()
    assert "(no replica interval)" in md and "## CG1 noise floor" in md
    marks = set(conds.loc[conds["cg"] > 1, "angle_error_vs_floor"])
    assert {m.split(":")[0] for m in marks} <= {"within", "beyond", "undecided"}, marks


def test_figures_and_paraview_files(study):
    rep = study / "report"
    md = (rep / "summary.md").read_text()
    for name in ("error_vs_runtime.png", "velocity_profiles.png", "gsd_overlay.png",
                 "cg1-none-r0_speed.png", "cg2-bond-r1_granules.png"):
        png = rep / "figures" / name
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
        assert f"figures/{name}" in md
    assert "<table" in (rep / "index.html").read_text()
    pvd = rep / "paraview" / "cg2-weber-r0.pvd"
    entries = ET.parse(pvd).getroot().findall("./Collection/DataSet")
    parts = {e.get("part") for e in entries}
    assert parts == {"0", "1"}
    for e in entries:
        assert (pvd.parent / e.get("file")).is_file()
    # the drum turns between frames in the collection
    import meshio
    drums = [pvd.parent / e.get("file") for e in entries if e.get("part") == "1"]
    a, b = meshio.read(drums[0]).points, meshio.read(drums[-1]).points
    assert not np.allclose(a, b)
