"""One workflow, two paths: ``ligwf study`` locally and ``ligwf slurm submit`` on a real
single-node Slurm run the same pipeline (:mod:`ligwf.pipeline`).

The workflow's ``analysis:`` settings differ from every default; both paths must refuse
the same unsafe case before writing anything, store the same settings in the study, and
produce identical analysis tables (frames, GSD, GSD summary) with the same steady window
and granule settings recorded. Two tiny CG3 cases per path (~200 particles each).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ligwf.local import LocalExecutor
from ligwf.pipeline.post import POSTPROCESS_COMMANDS, postprocess
from ligwf.slurm.jobs import read_record
from ligwf.study.study import Study

from test_slurm_integration import _logs, wait_until_idle

HERE = Path(__file__).resolve().parent
WORKFLOW = HERE / "tiny_drum.yaml"
LIGWF = str(Path(sys.executable).parent / "ligwf")
#: analysis settings, every one away from its default
ANALYSIS = {"steady_after": 0.5, "granules": "communities", "min_bridge_force": 1.0e-9,
            "min_relative_force": 0.1, "max_velocity_angle": 60.0, "velocity_frame": "drum",
            "flow_radius": 2.5, "resolution": 0.01, "community_weight": "force",
            "community_seed": 3, "bins_per_decade": 4,
            "min_particles": 3, "error_band": 0.2, "bootstrap": 50, "seed": 7,
            "sensitivity_frames": 2, "gsd_volume": "primary", "hold_time": 0.5,
            "field_kernel": 2.0, "surface_strip": 0.0}
SETS = ["--set", "sweep.replicas=2", *[x for k, v in ANALYSIS.items()
                                       for x in ("--set", f"analysis.{k}={v}")]]
#: a periodic slice shorter than one CG3 particle: the pre-flight refuses it
UNSAFE = ["--set", "scene.drum.length=0.002"]
TABLES = ("frames.csv", "gsd.csv", "gsd_summary.csv", "kinetics.csv", "kinetics_summary.csv",
          "sensitivity.csv")

pytestmark = [pytest.mark.slurm, pytest.mark.engine, pytest.mark.slow]


def ligwf(*args: str, env: dict[str, str], expect: int = 0) -> subprocess.CompletedProcess:
    out = subprocess.run([LIGWF, *args], capture_output=True, text=True, env=env, timeout=600,
                         stdin=subprocess.DEVNULL)
    assert out.returncode == expect, f"ligwf {' '.join(args)} exited {out.returncode}:\n" \
                                     f"{out.stdout}\n{out.stderr}"
    return out


@pytest.fixture
def env(tmp_path):
    e = dict(os.environ, LIGWF_MESH_CACHE=str(tmp_path / "meshes"))
    e.pop("LIGWF_SLURM_PARTITION", None)
    return e


def test_both_paths_refuse_the_same_unsafe_case(tmp_path, env):
    for argv in (["study", str(WORKFLOW), "--out", str(tmp_path / "local")],
                 ["slurm", "submit", str(WORKFLOW), "--out", str(tmp_path / "slurm")],
                 ["slurm", "submit", str(WORKFLOW), "--out", str(tmp_path / "dry"), "--dry-run"]):
        res = ligwf(*argv, *SETS, *UNSAFE, env=env, expect=2)
        assert "UnstableCase" in res.stderr and "drum.length" in res.stderr
        assert not Path(argv[argv.index("--out") + 1]).exists()
    # --allow-unstable is honoured by the Slurm path too
    res = ligwf("slurm", "submit", str(WORKFLOW), "--out", str(tmp_path / "dry"), "--dry-run",
                "--allow-unstable", *SETS, *UNSAFE, env=env)
    assert "allowed by --allow-unstable" in res.stderr


def _record(study: Path) -> dict:
    rec = json.loads((study / "analysis" / "analysis.json").read_text())
    rec.pop("run_dir")
    return rec


def test_local_and_slurm_give_identical_analysis(slurm_cluster, tmp_path, env):
    local, slurm, split = tmp_path / "local", tmp_path / "slurm", tmp_path / "split"
    ligwf("slurm", "submit", str(WORKFLOW), "--out", str(slurm), "--ntasks", "1",
          "--time", "00:10:00", *SETS, env=env)
    script = (slurm / "slurm" / "analysis-1.sh").read_text()
    assert [f"{LIGWF} {c} {slurm}" for c in POSTPROCESS_COMMANDS] == \
        [ln for ln in script.splitlines() if ln.startswith(LIGWF)]
    # the same study with its analysis split over 3 array tasks after the cases, merged
    ligwf("slurm", "submit", str(WORKFLOW), "--out", str(split), "--ntasks", "1",
          "--time", "00:10:00", "--analysis-tasks", "3", *SETS, env=env)
    record = read_record(split)
    assert [e["kind"] for e in record] == ["array", "analysis-array", "analysis-merge"]
    assert record[1]["after"] == record[0]["job_id"]                 # the tasks after the runs
    assert record[2]["after"] == f"{record[0]['job_id']}:{record[1]['job_id']}"
    ligwf("study", str(WORKFLOW), "--out", str(local), "--no-snapshots", *SETS, env=env)
    wait_until_idle(slurm, timeout=300)
    assert (slurm / "report" / "summary.md").is_file(), _logs(slurm)
    wait_until_idle(split, timeout=300)
    assert (split / "report" / "summary.md").is_file(), _logs(split)
    for name in TABLES:                       # split over tasks = one analysis job, bytewise
        assert (split / "analysis" / name).read_bytes() == \
            (slurm / "analysis" / name).read_bytes(), name
    assert not list((split / "analysis").glob(".parts-*"))

    for study in (local, slurm):
        s = Study.open(study)
        assert s.analysis.model_dump() == ANALYSIS
        assert all(c.manifest().status == "done" for c in s.cases)
    rec_local, rec_slurm = _record(local), _record(slurm)
    assert rec_local["settings"] == ANALYSIS
    assert "definition" not in rec_local     # the settings are the definition: no renamed copy
    assert rec_local["settings"]["bootstrap"] == 50
    assert rec_local["settings"]["bins_per_decade"] == 4
    assert rec_local["settings"]["error_band"] == 0.2
    cases = Study.open(local).cases
    assert [c["steady_from_step"] for c in rec_local["cases"]] == \
        [c.steady_start_step(0.5) for c in cases]
    assert all(0 < c["steady_frames"] < c["analysed"] for c in rec_local["cases"])
    flow = json.loads((local / "analysis" / "flow_profiles.json").read_text())
    assert flow["steady_after"] == 0.5

    # the Slurm job's post-processing is the local one: rerun locally on a copy, same bytes
    again = tmp_path / "again"
    shutil.copytree(slurm, again, ignore=shutil.ignore_patterns("analysis", "report"))
    postprocess(again, LocalExecutor(), snapshots=False)
    for name in TABLES:
        assert (again / "analysis" / name).read_bytes() == (slurm / "analysis" / name).read_bytes()
    assert _record(again) == rec_slurm

    # and the two paths (same seeds, one rank each) give the same tables
    assert rec_slurm == rec_local
    for name in TABLES:
        assert (slurm / "analysis" / name).read_bytes() == \
            (local / "analysis" / name).read_bytes(), name
