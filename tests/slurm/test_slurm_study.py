"""Submission planning and the CLI paths that need no scheduler (which cases a resubmit
selects: tests/test_eligibility.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from ligwf.errors import ConfigError
from ligwf.scheduler import JobRound
from ligwf.slurm.jobs import (append_record, dry_run_text, job_name, next_round,
                              plan_jobs, read_record, recorded_plan, recorded_site, submit_jobs)
from ligwf.slurm.site import SlurmSite

from helpers import DRUM

HERE = Path(__file__).resolve().parent
WORKFLOW = HERE / "tiny_drum.yaml"
LIGWF = str(Path(sys.executable).parent / "ligwf")


def test_plan_has_array_of_exact_indices_and_dependent_analysis(tmp_path):
    site = SlurmSite(ligwf="/venv/bin/ligwf", max_concurrent=3)
    jobs = plan_jobs(tmp_path, "my study", site,
                     JobRound((4, 1, 9), 2, post_steps=("analyse", "report")))
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
    assert plan_jobs(tmp_path, "s", site, JobRound((0,)))[-1].kind == "array"


def test_a_split_analysis_is_an_array_after_the_cases_then_a_merge_that_reports(tmp_path):
    site = SlurmSite(ligwf="/venv/bin/ligwf")
    jobs = plan_jobs(tmp_path, "s", site, JobRound(
        (0, 1), ranks={0: 2, 1: 1}, post_steps=("analyse", "report"), analysis_tasks=3,
        token="abc123"))
    assert [j.kind for j in jobs] == ["array", "array", "analysis-array", "analysis-merge"]
    tasks, merge = jobs[2:]
    assert tasks.after_array and merge.after_array and tasks.indices == (0, 1, 2)
    assert "#SBATCH --array=0-2\n" in tasks.script_text
    assert '--part "$SLURM_ARRAY_TASK_ID/3" --token abc123' in tasks.script_text
    lines = [ln for ln in merge.script_text.splitlines() if ln.startswith("/venv/bin/ligwf")]
    study = tmp_path.resolve()
    assert lines == [f"/venv/bin/ligwf analyse {study} --merge 3 --token abc123",
                     f"/venv/bin/ligwf report {study}"]       # analyse is the split, not again
    text = dry_run_text(jobs).splitlines()
    runs = [ln for ln in text if ln.startswith("# would run:")]
    assert "--dependency" not in runs[0] + runs[1]
    assert "--dependency=afterany:<array job id 1>:<array job id 2> " in runs[2]
    assert "--dependency=afterany:<array job id 1>:<array job id 2>:<array job id 3> " in runs[3]
    one = plan_jobs(tmp_path, "s", site, JobRound((0,), post_steps=("analyse", "report")))
    assert [j.kind for j in one] == ["array", "analysis"]
    with pytest.raises(ConfigError, match="token"):
        plan_jobs(tmp_path, "s", site, JobRound((0,), post_steps=("analyse",), analysis_tasks=2))


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


# --------------------------------------------------------------------- the rank plan

def test_planned_ranks_give_one_array_per_rank_count_and_the_analysis_waits_for_all(tmp_path):
    site = SlurmSite(ligwf="/venv/bin/ligwf", ntasks=1)
    jobs = plan_jobs(tmp_path, "s", site, JobRound(
        (0, 1, 2, 3), ranks={0: 1, 1: 4, 2: 1, 3: 4}, post_steps=("analyse",), plan_cores=8))
    arrays = [j for j in jobs if j.kind == "array"]
    assert [j.script_path.name for j in arrays] == ["array-1-np4.sh", "array-1-np1.sh"]
    assert [j.indices for j in arrays] == [(1, 3), (0, 2)]
    assert "#SBATCH --ntasks=4\n" in arrays[0].script_text
    assert "#SBATCH --array=1,3\n" in arrays[0].script_text
    assert "#SBATCH --ntasks=1\n" in arrays[1].script_text
    assert all(j.planned and j.plan_cores == 8 for j in arrays)
    assert jobs[-1].kind == "analysis" and jobs[-1].indices == (0, 1, 2, 3)
    assert ("--dependency=afterany:<array job id 1>:<array job id 2>"
            in dry_run_text(jobs))
    # one rank count: the usual single array-R.sh
    one = plan_jobs(tmp_path, "s", site, JobRound((0, 1), ranks={0: 2, 1: 2}))
    assert [j.script_path.name for j in one] == ["array-1.sh"]
    assert "#SBATCH --ntasks=2\n" in one[0].script_text
    with pytest.raises(ConfigError, match=r"no ranks for case index\(es\) \[1\]"):
        plan_jobs(tmp_path, "s", site, JobRound((0, 1), ranks={0: 2}))


def test_submit_records_every_array_and_makes_the_analysis_wait_for_all(tmp_path):
    site = SlurmSite(ligwf="/venv/bin/ligwf")
    jobs = plan_jobs(tmp_path, "s", site, JobRound((0, 1), ranks={0: 2, 1: 1},
                                                post_steps=("analyse",)))
    ids = iter(["101", "102", "103"])
    commands = []

    def fake_sbatch(argv):
        commands.append(list(argv))
        return subprocess.CompletedProcess(argv, 0, stdout=f"{next(ids)}\n", stderr="")

    entries = submit_jobs(tmp_path, jobs, site, run=fake_sbatch)
    assert [e["job_id"] for e in entries] == ["101", "102", "103"]
    assert "--dependency=afterany:101:102" in commands[2]
    assert entries[2]["after"] == "101:102"
    assert [e["site"]["ntasks"] for e in entries[:2]] == [2, 1]
    assert entries[0]["planned"] == {"cores": None}
    assert recorded_plan(tmp_path) == {"cores": None}


def test_an_unplanned_submission_records_no_plan(tmp_path):
    site = SlurmSite(ligwf="/venv/bin/ligwf", ntasks=3)
    jobs = plan_jobs(tmp_path, "s", site, JobRound((0,)))
    ok = lambda argv: subprocess.CompletedProcess(argv, 0, stdout="7\n", stderr="")  # noqa: E731
    (entry,) = submit_jobs(tmp_path, jobs, site, run=ok)
    assert "planned" not in entry and entry["site"]["ntasks"] == 3
    assert recorded_plan(tmp_path) is None


def _dry_run(tmp_path, monkeypatch, capsys, *extra, site_file=""):
    from ligwf.cli.main import main

    (tmp_path / "site.yaml").write_text(site_file)
    monkeypatch.setenv("LIGWF_SITE", str(tmp_path / "site.yaml"))
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    monkeypatch.delenv("LIGWF_SLURM_NTASKS", raising=False)
    out = tmp_path / "study"
    assert main(["slurm", "submit", str(DRUM), "--out", str(out), "--dry-run",
                 "--set", "sweep.cg_levels=[3,1]", "--set", "scene.drum.length=0.018",
                 *extra]) == 0
    assert not out.exists()
    return capsys.readouterr().out


def test_dry_run_shows_the_rank_plan_and_one_array_per_rank_count(tmp_path, monkeypatch,
                                                                  capsys):
    text = _dry_run(tmp_path, monkeypatch, capsys)
    assert "rank plan" in text
    plan_rows = [[c.strip() for c in line.split("│")[1:-1]] for line in text.splitlines()
                 if line.startswith("│ cg")][3:]
    # CG1 (11,963 particles, 18 mm): 3 ranks by particles per rank, no core limit
    assert [(r[0], r[2], r[3]) for r in plan_rows] == [
        ("cg3-weber-r0", "1", "slab, particles"), ("cg3-bond-r0", "1", "slab, particles"),
        ("cg1-none-r0", "3", "particles")]
    assert "array-1-np3.sh: 1 case(s), --ntasks=3" in text
    assert "array-1-np1.sh: 2 case(s), --ntasks=1" in text
    assert "core-hours in all" in text
    assert "#SBATCH --array=2\n#SBATCH --ntasks=3\n" in text
    assert "#SBATCH --array=0-1\n#SBATCH --ntasks=1\n" in text
    assert "afterany:<array job id 1>:<array job id 2>" in text


def test_dry_run_with_cores_caps_the_ranks(tmp_path, monkeypatch, capsys):
    text = _dry_run(tmp_path, monkeypatch, capsys, "--cores", "2")
    assert "rank plan (at most 2 per case)" in text
    assert "array-1-np2.sh: 1 case(s), --ntasks=2" in text


@pytest.mark.parametrize("extra, site_file", [(("--ntasks", "3"), ""),
                                               ((), "slurm:\n  ntasks: 3\n")])
def test_ntasks_overrides_the_plan_as_before(tmp_path, monkeypatch, capsys, extra, site_file):
    text = _dry_run(tmp_path, monkeypatch, capsys, *extra, site_file=site_file)
    assert "ranks as asked (--ntasks / site ntasks)" in text
    assert "array-1.sh: 3 case(s), --ntasks=3" in text
    assert text.count("#SBATCH --array=") == 1 and "#SBATCH --ntasks=3\n" in text
    assert "afterany:<array job id>" in text
