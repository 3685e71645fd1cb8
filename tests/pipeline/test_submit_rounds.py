"""A sequential study on a scheduler (ligwf.pipeline.submit_rounds) without a scheduler:
where the study stands is read from the rounds record and the submission record (Slurm's
commands answered by a recorder with captured squeue text), and what a login-node call
submits from there. The whole chain on a real Slurm: tests/slurm/test_slurm_rounds.py."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from ligwf.errors import ConfigError
from ligwf.pipeline.prepare import prepare_workflow, write
from ligwf.pipeline.rounds import INCOMPLETE, ROUND_DUE, RUNNING
from ligwf.pipeline.submit_rounds import (FollowUp, keep_going, progress, recorded_steps,
                                          submitted_round)
from ligwf.slurm.jobs import append_record, read_record
from ligwf.slurm.scheduler import SlurmScheduler
from ligwf.slurm.site import SlurmSite
from ligwf.study.condition import Condition
from ligwf.study.rounds import AddReplicas, Look, Rounds, read_rounds, write_rounds

from helpers import ROOT

CAPTURED = ROOT / "tests" / "data" / "slurm"
WORKFLOW = ROOT / "tests" / "workflows" / "rounds_tiny.yaml"
SITE = SlurmSite(ligwf="/venv/bin/ligwf", ntasks=1)
STEP = "slurm next-round --no-snapshots"


class Slurm:
    """Answers squeue with ``squeue`` text, forgets every job in scontrol, and gives each
    sbatch the next job id (recorded)."""

    def __init__(self, squeue: str = "") -> None:
        self.squeue, self.sbatch, self.next_id = squeue, [], 100

    def __call__(self, argv):
        if argv[0] == "squeue":
            return subprocess.CompletedProcess(argv, 0, stdout=self.squeue, stderr="")
        if argv[0] == "scontrol":
            return subprocess.CompletedProcess(
                argv, 1, stdout="", stderr="slurm_load_jobs error: Invalid job id specified")
        assert argv[0] == "sbatch", argv
        self.sbatch.append(list(argv))
        self.next_id += 1
        return subprocess.CompletedProcess(argv, 0, stdout=f"{self.next_id}\n", stderr="")


def _round_one(tmp_path, monkeypatch) -> Path:
    """The tiny rounds study written and recorded as round 1: array job 1 (cases 0-3) and
    its follow-up job 2 (the ids of the captured squeue text)."""
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    out = tmp_path / "study"
    write(prepare_workflow(WORKFLOW), out)
    append_record(out, {"kind": "array", "job_id": "1", "indices": [0, 1, 2, 3],
                        "study_round": 1})
    append_record(out, {"kind": "analysis", "job_id": "2", "indices": [0, 1, 2, 3],
                        "after": "1", "steps": [STEP], "study_round": 1})
    return out


def test_the_follow_up_command_round_trips_through_the_record():
    how = FollowUp("slurm", True, 4, False, (Path("/t/a b"),), True, mesh_cache=Path("/m"))
    assert how.steps == ["slurm next-round --no-snapshots --templates '/t/a b' "
                         "--allow-unstable --mesh-cache /m"]
    assert FollowUp.from_steps(how.steps, True, 4) == how
    with pytest.raises(ConfigError, match="no follow-up job"):
        FollowUp.from_steps(["analyse"], True, None)


def test_the_state_is_read_from_the_two_records(tmp_path, monkeypatch):
    out = _round_one(tmp_path, monkeypatch)
    jobs = read_record(out)
    assert submitted_round(jobs) == 1 and recorded_steps(jobs) == [STEP]
    queued = SlurmScheduler(SITE, Slurm((CAPTURED / "squeue_array_running.txt").read_text()))
    p = progress(out, queued)
    assert (p.state, p.round, p.looks, p.follow_ups) == (RUNNING, 1, 0, ("2",))
    assert len(p.queued) == 4 and p.unfinished == ()
    p = progress(out, SlurmScheduler(SITE, Slurm("")))      # ended, no case ran: no look
    assert (p.state, p.round, p.unfinished) == (INCOMPLETE, 1, (0, 1, 2, 3))
    append_record(out, {"kind": "array", "job_id": "3", "indices": [0], "study_round": 3})
    with pytest.raises(ConfigError, match="names round 3, the rounds record 0 look"):
        progress(out, SlurmScheduler(SITE, Slurm("")))


def test_a_new_study_is_due_its_first_round(tmp_path, monkeypatch):
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    out = tmp_path / "study"
    write(prepare_workflow(WORKFLOW), out)
    p = progress(out, SlurmScheduler(SITE, Slurm("")))
    assert (p.state, p.round, p.looks) == (ROUND_DUE, 1, 0)


def test_a_login_node_call_resubmits_an_incomplete_round_once(tmp_path, monkeypatch):
    out = _round_one(tmp_path, monkeypatch)
    slurm = Slurm("")
    how = FollowUp.from_steps([STEP], planned=False, cores=None)
    moved = keep_going(out, SlurmScheduler(SITE, slurm), how)
    assert moved.indices == (0, 1, 2, 3) and "submitted again" in moved.note
    new = read_record(out)[2:]
    assert [(s["kind"], s["study_round"], s["indices"]) for s in new] == [
        ("array", 1, [0, 1, 2, 3]), ("analysis", 1, [0, 1, 2, 3])]
    assert new[1]["steps"] == [STEP] and new[1]["after"] == new[0]["job_id"]
    assert "ligwf slurm next-round --no-snapshots" in (out / new[1]["script"]).read_text()
    # the same call while they are queued submits nothing
    slurm.squeue = "".join(f"101_{i}|101|{i}|PENDING|None\n" for i in range(4))
    again = keep_going(out, SlurmScheduler(SITE, slurm), how)
    assert again.submitted == () and again.progress.state == RUNNING
    assert len(slurm.sbatch) == 2


def test_a_look_whose_round_was_never_submitted_gets_a_follow_up_job_once(tmp_path,
                                                                       monkeypatch):
    """The follow-up job killed after it wrote look 1 and before it submitted round 2:
    round 2 is due; a resubmit (no workflow at hand) submits the follow-up job alone, no
    look, no array; again while that job is queued: nothing."""
    out = _round_one(tmp_path, monkeypatch)
    write_rounds(out, Rounds(2, looks=(Look(1, 0.025, 0.01, target="cg1.5-weber", actions=(
        AddReplicas(Condition("{}", 1.5, "weber"), (2,), 100),)),)))
    slurm = Slurm("")
    p = progress(out, SlurmScheduler(SITE, slurm))
    assert (p.state, p.round, p.looks) == (ROUND_DUE, 2, 1)
    how = FollowUp.from_steps([STEP], planned=False, cores=None)
    moved = keep_going(out, SlurmScheduler(SITE, slurm), how)
    assert "round 2 is due: its follow-up job submitted" in moved.note
    new = read_record(out)[2:]
    assert [(s["kind"], s.get("study_round"), s["after"], s["steps"]) for s in new] == [
        ("analysis", None, None, [STEP])]
    slurm.squeue = f"{new[0]['job_id']}|{new[0]['job_id']}|N/A|PENDING|None\n"
    again = keep_going(out, SlurmScheduler(SITE, slurm), how)
    assert again.submitted == () and "is still queued" in again.note
    assert len(slurm.sbatch) == 1 and len(read_rounds(out).looks) == 1
