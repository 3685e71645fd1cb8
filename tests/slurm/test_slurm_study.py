"""Submission planning, resubmit selection and the CLI paths that need no scheduler."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from ligwf.slurm.jobs import (CaseStatus, append_record, cases_to_resubmit, dry_run_text, job_name,
                         next_round, plan_jobs, read_record, recorded_site)
from ligwf.slurm.site import SlurmSite

HERE = Path(__file__).resolve().parent
WORKFLOW = HERE / "tiny_drum.yaml"
LIGWF = str(Path(sys.executable).parent / "ligwf")


def case(i: int, manifest: str, state: str | None = None) -> CaseStatus:
    return CaseStatus(i, f"c{i}", manifest, job=f"7_{i}", slurm_state=state)


def test_resubmit_picks_missing_failed_killed_and_stale_only():
    cases = [case(0, "done", "COMPLETED"), case(1, "failed", "FAILED"),
             case(2, "killed", "CANCELLED"), case(3, "missing", None),
             case(4, "running", None),          # task gone, manifest never finished: stale
             case(5, "unstable", "COMPLETED"),
             case(6, "missing", "PENDING"),     # still queued: not again
             case(7, "running", "RUNNING")]
    assert cases_to_resubmit(cases) == [1, 2, 3, 4]
    assert cases_to_resubmit(cases, include_unstable=True) == [1, 2, 3, 4, 5]


def test_plan_has_array_of_exact_indices_and_dependent_analysis(tmp_path):
    site = SlurmSite(ligwf="/venv/bin/ligwf", max_concurrent=3)
    jobs = plan_jobs(tmp_path, "my study", site, [4, 1, 9], ["analyse", "report"], 2)
    array, analysis = jobs
    assert array.indices == (1, 4, 9) and not array.after_array
    assert array.script_path == tmp_path.resolve() / "slurm" / "array-2.sh"
    assert "#SBATCH --array=1,4,9%3\n" in array.script_text
    assert "#SBATCH --job-name=ligwf-my-study\n" in array.script_text
    assert analysis.after_array and analysis.script_path.name == "analysis-2.sh"
    assert "/venv/bin/ligwf analyse" in analysis.script_text
    assert "/venv/bin/ligwf report" in analysis.script_text
    text = dry_run_text(jobs)
    assert "--dependency=afterany:<array job id>" in text
    assert f"sbatch --parsable {array.script_path}" in text
    assert plan_jobs(tmp_path, "s", site, [0], [], 1)[-1].kind == "array"


def test_record_round_and_recorded_site(tmp_path):
    assert read_record(tmp_path) == [] and next_round(tmp_path) == 1
    append_record(tmp_path, {"kind": "array", "job_id": "5", "indices": [0, 1],
                             "site": {"partition": "p", "ntasks": 2}})
    append_record(tmp_path, {"kind": "analysis", "job_id": "6", "indices": [0, 1]})
    assert [s["job_id"] for s in read_record(tmp_path)] == ["5", "6"]
    assert next_round(tmp_path) == 2
    assert recorded_site(tmp_path) == {"partition": "p", "ntasks": 2}
    assert json.loads((tmp_path / "slurm" / "jobs.json").read_text())["submissions"]


def test_job_name_is_safe():
    assert job_name("demo", "array") == "ligwf-demo"
    assert job_name("a b;c", "analysis") == "ligwf-a-b-c-analysis"


def _ligwf(*args, env=None):
    return subprocess.run([LIGWF, *args], capture_output=True, text=True, timeout=120,
                          env=env, stdin=subprocess.DEVNULL)


def test_cli_dry_run_prints_scripts_and_writes_nothing(tmp_path):
    out = tmp_path / "study"
    env = dict(os.environ, LIGWF_MESH_CACHE=str(tmp_path / "meshes"),
               LIGWF_SLURM_MODULES="openmpi/4.1", LIGWF_SITE=str(tmp_path / "none.yaml"))
    res = _ligwf("slurm", "submit", str(WORKFLOW), "--out", str(out), "--dry-run",
                 "--partition", "debug", "--time", "00:05:00", "--max-concurrent", "2",
                 "--account", "proj", env=env)
    assert res.returncode == 0, res.stderr
    assert "#!/bin/bash" in res.stdout
    assert "#SBATCH --array=0-3%2" in res.stdout
    assert "#SBATCH --partition=debug" in res.stdout and "#SBATCH --account=proj" in res.stdout
    assert "#SBATCH --time=00:05:00" in res.stdout
    assert "module load openmpi/4.1" in res.stdout
    assert f"exec {LIGWF} run-case {out.resolve()}" in res.stdout
    assert "analyse" in res.stdout and "afterany:<array job id>" in res.stdout
    assert not out.exists() and not (tmp_path / "meshes").exists()


def test_cli_rejects_bad_site_value_before_writing(tmp_path):
    out = tmp_path / "study"
    res = _ligwf("slurm", "submit", str(WORKFLOW), "--out", str(out), "--time", "soon",
                 env=dict(os.environ, LIGWF_MESH_CACHE=str(tmp_path / "m")))
    assert res.returncode == 2 and "not a Slurm time" in res.stderr
    assert not out.exists()


def test_cli_without_sbatch_fails_before_writing(tmp_path):
    out = tmp_path / "study"
    env = dict(os.environ, PATH=str(Path(sys.executable).parent),
               LIGWF_MESH_CACHE=str(tmp_path / "m"))
    res = _ligwf("slurm", "submit", str(WORKFLOW), "--out", str(out), env=env)
    assert res.returncode == 2 and "sbatch not found" in res.stderr
    assert not out.exists()


def test_cli_status_of_a_folder_that_is_not_a_study(tmp_path):
    res = _ligwf("slurm", "status", str(tmp_path))
    assert res.returncode == 2 and "not a ligwf study folder" in res.stderr
