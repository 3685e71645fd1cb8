"""ligwf.analysis.runner / ``ligwf analyse``: whole-study analysis on real dumps, manifests,
skipped frames, ParaView output, and MPI (-np 2) output identical to serial."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pandas as pd
import pytest

from ligwf.analysis.frames.dumps import discover_frames, read_particles
from ligwf.analysis.granule_stage import NothingAnalysed
from ligwf.analysis.granules.case import GranuleAnalysis
from ligwf.analysis.runner import AnalysisOptions, analyse
from ligwf.cli.main import main
from ligwf.study.case import CaseFolder
from ligwf.scene.settings import AnalysisSettings
from wetdump import wet_study

FAST = AnalysisOptions(settings=AnalysisSettings(granules="communities", bootstrap=100))
OUTPUTS = ("granules.parquet", "frames.csv", "gsd.csv", "gsd_summary.csv", "analysis.json")


@pytest.fixture(scope="module")
def study(engine, tmp_path_factory) -> Path:
    """The shared wet study, copied, with 100 bootstrap draws in its analysis settings
    (``ligwf analyse`` reads them from the study)."""
    out = tmp_path_factory.mktemp("analysed") / "study"
    shutil.copytree(wet_study(engine, tmp_path_factory), out)
    record = json.loads((out / "study.json").read_text())
    record["analysis"] = {"granules": "communities", "bootstrap": 100}
    (out / "study.json").write_text(json.dumps(record))
    return out


@pytest.fixture(scope="module")
def serial(study, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("serial")
    assert main(["analyse", str(study), "--out", str(out)]) == 0
    return out


@pytest.mark.engine
@pytest.mark.mpi
def test_outputs_of_a_study(study, serial):
    record = json.loads((serial / "analysis.json").read_text())
    assert record["settings"]["bootstrap"] == 100 and "gsd" not in record
    assert [c["case_id"] for c in record["cases"]] == ["cg3-weber-r0", "cg3-weber-r1"]
    assert record["skipped_cases"][0]["case_id"] == "cg3-bond-r0"
    assert "failed" in record["skipped_cases"][0]["reason"]
    assert record["skipped_frames"] == []
    g = pd.read_parquet(serial / "granules.parquet")
    frames = discover_frames(study / "cg3-weber-r0")
    assert set(g["case_id"]) == {"cg3-weber-r0", "cg3-weber-r1"}
    assert sorted(set(g["step"])) == [f.step for f in frames]
    total = read_particles(frames[0].particles).volumes.sum()
    per_frame = g.groupby(["case_id", "step"])
    np.testing.assert_allclose(per_frame["volume"].sum(), total, rtol=1e-12)
    assert (per_frame["members"].sum() == 222).all()
    np.testing.assert_allclose(g["primary_volume"], g["volume"] / 27)
    # the replica is a copy: identical granules
    a, b = (g[g.case_id == c].drop(columns=["case_id", "replica"]).reset_index(drop=True)
            for c in ("cg3-weber-r0", "cg3-weber-r1"))
    pd.testing.assert_frame_equal(a, b)
    # the table equals a direct run of the life-cycle class
    case = CaseFolder.open(study / "cg3-weber-r0")
    ref = GranuleAnalysis(case, AnalysisSettings(granules="communities")).run()   # the study's
    for r in ref.results:
        got = a[a.step == r.step].reset_index(drop=True)
        np.testing.assert_array_equal(got["members"], r.table["members"])
        np.testing.assert_allclose(got["volume"], r.table["volume"], rtol=1e-15)
    # the GSD uses the steady window only (the last 75 % of production, as the flow stage)
    first = case.steady_start_step(0.25)
    steady = [f for f in frames if f.step >= first]
    assert 0 < len(steady) < len(frames)
    assert record["cases"][0]["steady_from_step"] == first
    assert record["cases"][0]["steady_frames"] == len(steady)
    summary = pd.read_csv(serial / "gsd_summary.csv")
    assert summary["condition"].tolist() == ["cg3-weber"] and summary["frames"][0] == 2 * len(steady)
    gsd = pd.read_csv(serial / "gsd.csv")
    assert gsd["volume_fraction"].sum() == pytest.approx(1)


@pytest.mark.engine
@pytest.mark.mpi
def test_paraview_series(study, serial):
    pvd = (serial / "cg3-weber-r0" / "granules.pvd").read_text()
    frames = discover_frames(study / "cg3-weber-r0")
    g = pd.read_parquet(serial / "granules.parquet")
    for f in frames:
        assert f'file="granules_{f.step}.vtu"' in pvd
        m = meshio.read(serial / "cg3-weber-r0" / f"granules_{f.step}.vtu")
        labels = m.point_data["granule"]
        assert len(labels) == 222
        members = g[(g.case_id == "cg3-weber-r0") & (g.step == f.step)]["members"].to_numpy()
        np.testing.assert_array_equal(np.bincount(labels), members)
        np.testing.assert_array_equal(m.point_data["granule_members"], members[labels])


@pytest.mark.engine
@pytest.mark.mpi
def test_bad_frame_is_reported_and_skipped(study, tmp_path):
    copy = tmp_path / "study"
    shutil.copytree(study, copy)
    frames = discover_frames(copy / "cg3-weber-r1")
    bad = frames[1].contacts
    bad.write_bytes(bad.read_bytes()[: bad.stat().st_size // 2])
    record = analyse(copy, tmp_path / "out", FAST)
    assert len(record["skipped_frames"]) == 1
    skipped = record["skipped_frames"][0]
    assert skipped["case_id"] == "cg3-weber-r1" and skipped["step"] == frames[1].step
    assert str(bad) in skipped["reason"]
    g = pd.read_parquet(tmp_path / "out" / "granules.parquet")
    assert frames[1].step not in set(g[g.case_id == "cg3-weber-r1"]["step"])
    assert frames[1].step in set(g[g.case_id == "cg3-weber-r0"]["step"])
    fr = pd.read_csv(tmp_path / "out" / "frames.csv")
    assert (fr["status"] == "skipped").sum() == 1
    # the largest granule's percolation flag in frames.csv is the one of granules.parquet
    ok = fr[fr["status"] == "ok"]
    for row in ok.itertuples():
        frame = g[(g.case_id == row.case_id) & (g.step == row.step)]
        assert bool(frame.loc[frame["volume"].idxmax(), "percolating"]) == bool(row.largest_percolates)


@pytest.mark.engine
@pytest.mark.mpi
def test_manifest_gates_cases(study, tmp_path):
    copy = tmp_path / "study"
    shutil.copytree(study, copy)
    (copy / "cg3-weber-r1" / "manifest.json").unlink()
    m = json.loads((copy / "cg3-weber-r0" / "manifest.json").read_text())
    m["status"] = "unstable"
    (copy / "cg3-weber-r0" / "manifest.json").write_text(json.dumps(m))
    with pytest.raises(NothingAnalysed, match="unstable"):     # no usable case: refused
        analyse(copy, tmp_path / "out", FAST)
    assert not (tmp_path / "out").exists()
    opened = analyse(copy, tmp_path / "out2", AnalysisOptions(
        settings=AnalysisSettings(granules="communities", bootstrap=10), require_manifest=False))
    analysed = {c["case_id"]: c["analysed"] for c in opened["cases"]}
    n = len(discover_frames(copy / "cg3-weber-r0"))
    # the bond case was never run: skipped with its missing frames; the others fully analysed
    assert analysed == {"cg3-weber-r0": n, "cg3-weber-r1": n}
    reasons = {s["case_id"]: s["reason"] for s in opened["skipped_cases"]}
    assert "no analysable frame" in reasons["cg3-bond-r0"]
    assert {f["kind"] for f in opened["skipped_frames"]} == {"missing"}


@pytest.mark.engine
@pytest.mark.mpi
def test_mpi_two_ranks_identical_to_serial(study, serial, engine, tmp_path):
    out = tmp_path / "mpi"
    cmd = engine.mpirun_prefix(2) + [sys.executable, "-m", "ligwf.cli.main", "analyse", str(study),
                                     "--out", str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300,
                          stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stdout.count("analysed") == 1, "only rank 0 reports"
    for name in OUTPUTS:
        assert (out / name).read_bytes() == (serial / name).read_bytes(), name
    for case in ("cg3-weber-r0", "cg3-weber-r1"):
        files = sorted(p.name for p in (serial / case).iterdir())
        assert files == sorted(p.name for p in (out / case).iterdir())
        for name in files:
            assert (out / case / name).read_bytes() == (serial / case / name).read_bytes(), name
