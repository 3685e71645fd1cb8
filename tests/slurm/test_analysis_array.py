"""A study analysed by a Slurm array of analysis tasks gives the local analysis' tables,
byte for byte; a failed task is named by the merge, and re-running it completes the set.

On the real single-node Slurm of tests/slurm/local_cluster.py: a tiny study (two CG3
cases, ~200 particles, ``ligwf study`` locally: engine + analysis) is analysed again by
``ligwf analyse STUDY --executor slurm --tasks 3`` (three array tasks, ``--part K/3``, and
the merge job).
Then ``--slurm 2`` with task 1 made to fail (its site set-up line exits 3): the merge job
fails naming task 1 and the command that re-runs it, the outputs in place are untouched;
that command and the merge, run by hand, give the same tables again.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ligwf.slurm.jobs import read_record

HERE = Path(__file__).resolve().parent
WORKFLOW = HERE / "tiny_drum.yaml"
LIGWF = str(Path(sys.executable).parent / "ligwf")
TABLES = ("granules.parquet", "frames.csv", "gsd.csv", "gsd_summary.csv", "gsd_pooling.csv",
          "kinetics.csv", "kinetics_summary.csv", "sensitivity.csv", "flow.csv",
          "flow_profiles.json")

pytestmark = [pytest.mark.slurm, pytest.mark.engine, pytest.mark.slow]


def ligwf(*args: str, env: dict, expect: int = 0) -> subprocess.CompletedProcess:
    out = subprocess.run([LIGWF, *args], capture_output=True, text=True, env=env, timeout=900,
                         stdin=subprocess.DEVNULL)
    assert out.returncode == expect, f"ligwf {' '.join(args)} exited {out.returncode}:\n" \
                                     f"{out.stdout}\n{out.stderr}"
    return out


def wait_for_jobs(job_ids: list[str], timeout: float) -> None:
    """Until squeue lists none of ``job_ids`` (array tasks included)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        out = subprocess.run(["squeue", "-h", "-r", "-o", "%F"], capture_output=True, text=True)
        if not set(out.stdout.split()) & set(job_ids):
            return
        time.sleep(1.0)
    raise AssertionError(f"jobs {job_ids} still queued after {timeout:.0f} s")


def submissions(study: Path, token: str) -> list[dict]:
    return [s for s in read_record(study) if token in s["script"]]


def tables(folder: Path) -> dict[str, bytes]:
    return {name: (folder / name).read_bytes() for name in TABLES if (folder / name).is_file()}


def test_slurm_array_analysis_gives_the_local_tables(slurm_cluster, tmp_path):
    env = dict(os.environ, LIGWF_MESH_CACHE=str(tmp_path / "meshes"))
    env.pop("LIGWF_SLURM_PARTITION", None)
    study = tmp_path / "study"
    ligwf("study", str(WORKFLOW), "--out", str(study), "--no-snapshots",
          "--set", "sweep.replicas=2", "--set", "analysis.bootstrap=50", env=env)
    local = tables(study / "analysis")
    assert {"granules.parquet", "frames.csv", "gsd.csv", "flow.csv"} <= set(local)
    record = json.loads((study / "analysis" / "analysis.json").read_text())
    assert sum(c["analysed"] for c in record["cases"]) >= 4

    # three tasks for two cases of ~3 frames: a case's frames split over tasks (--executor
    # slurm --tasks 3; its old spelling --slurm N below)
    out = ligwf("analyse", str(study), "--executor", "slurm", "--tasks", "3", env=env).stdout
    token = re.search(r"token (\w+)", out).group(1)
    subs = submissions(study, token)
    assert [s["kind"] for s in subs] == ["analysis-array", "analysis-merge"]
    assert subs[1]["after"] == subs[0]["job_id"]
    (study / "analysis" / "frames.csv").unlink()        # the merge must write it again
    wait_for_jobs([s["job_id"] for s in subs], timeout=600)
    logs = "\n".join(p.read_text() for p in (study / "slurm" / "logs").glob("*.out"))
    assert tables(study / "analysis") == local, logs
    assert not (study / "analysis" / f".parts-{token}").exists()          # merged: dropped
    assert not list((study / "analysis").glob(".staging-*"))

    # task 1 of 2 fails: the merge names it, the outputs stay; re-run + merge completes
    env_fail = dict(env, LIGWF_SLURM_SETUP='[ "$SLURM_ARRAY_TASK_ID" != 1 ] || exit 3')
    out = ligwf("analyse", str(study), "--slurm", "2", env=env_fail).stdout
    token = re.search(r"token (\w+)", out).group(1)
    subs = submissions(study, token)
    wait_for_jobs([s["job_id"] for s in subs], timeout=600)
    merge_log = next((study / "slurm" / "logs").glob(f"*_{subs[1]['job_id']}.out")).read_text()
    rerun = f"ligwf analyse {study} --part 1/2 --token {token}"
    assert "AnalysisIncomplete" in merge_log and "task(s) 1 of 2 left no partial output" \
        in merge_log and rerun in merge_log, merge_log
    assert "Traceback" not in merge_log
    assert tables(study / "analysis") == local
    assert (study / "analysis" / f".parts-{token}" / "part-00000-of-00002.pkl").is_file()
    ligwf(*rerun.split()[1:], env=env)
    ligwf("analyse", str(study), "--merge", "2", "--token", token, env=env)
    assert tables(study / "analysis") == local
