"""Where a sequential study stands (ligwf.pipeline.rounds.stand): the one decision the local
loop and a scheduler's follow-up job both act on, read from real study folders (written,
with the manifests a runner leaves) and the rounds record; the scheduler's ``progress`` gives
the same answer on the same folder. No engine; Slurm's commands answered by a recorder."""

from __future__ import annotations

import socket
import subprocess
from pathlib import Path

import pytest

from ligwf.eligibility import Eligible, eligible
from ligwf.errors import ConfigError
from ligwf.pipeline.prepare import prepare_workflow, write
from ligwf.pipeline.rounds import (INCOMPLETE, LOOK_DUE, ROUND_DUE, RUNNING, STOPPED,
                                   RoundPlan, drive, start_rounds, stand)
from ligwf.pipeline.submit_rounds import progress
from ligwf.slurm.jobs import append_record
from ligwf.slurm.scheduler import SlurmScheduler
from ligwf.slurm.site import SlurmSite
from ligwf.study.extension import extend_production
from ligwf.study.manifest import Manifest
from ligwf.study.processes import start_time
from ligwf.study.rounds import DECIDED, Look, read_rounds, write_rounds
from ligwf.study.study import Study

from helpers import ROOT

WORKFLOW = ROOT / "tests" / "workflows" / "rounds_tiny.yaml"      # 4 cases
SITE = SlurmSite(ligwf="/venv/bin/ligwf", ntasks=1)


class Squeue:
    """squeue answers ``text``; scontrol forgets every job."""

    def __init__(self, text: str = "") -> None:
        self.text = text

    def __call__(self, argv):
        if argv[0] == "squeue":
            return subprocess.CompletedProcess(argv, 0, stdout=self.text, stderr="")
        return subprocess.CompletedProcess(argv, 1, stdout="", stderr=(
            "slurm_load_jobs error: Invalid job id specified"))


def set_manifest(case, status: str, steps_done: int | None = None, **more) -> None:
    steps = case.scaled.total_steps if steps_done is None else steps_done
    case.write_manifest(Manifest(case_id=case.case_id, index=case.index, ligwf_version="",
                                 liggghts_version="", status=status, steps_done=steps,
                                 total_steps=case.scaled.total_steps,
                                 scene_hash=case.scene_hash, **more))


@pytest.fixture
def study(tmp_path, monkeypatch) -> Path:
    """The tiny rounds study written with its rounds record (no look yet)."""
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    out = tmp_path / "study"
    write(prepare_workflow(WORKFLOW), out)
    start_rounds(out, RoundPlan(2))
    return out


def local_stand(study: Path, handed: int):
    """What the local loop decides after writing round ``handed``."""
    return stand(read_rounds(study), handed, eligible(Study.open(study).cases), study)


def test_a_round_not_handed_out_is_due_and_its_cases_decide_the_rest(study):
    rounds = read_rounds(study)
    assert stand(rounds, 0, Eligible(()), study) == ROUND_DUE
    assert local_stand(study, 1) == INCOMPLETE             # nothing has run
    cases = Study.open(study).cases
    for case in cases:
        set_manifest(case, "done")
    assert local_stand(study, 1) == LOOK_DUE
    # a done case whose production was extended since is not done: no look
    assert extend_production([cases[1]], 0.1)
    assert local_stand(study, 1) == INCOMPLETE
    set_manifest(Study.open(study).cases[1], "done")
    assert local_stand(study, 1) == LOOK_DUE
    # an unstable case is not done either (left alone unless asked: no look)
    set_manifest(cases[3], "unstable", reason="blew up")
    assert local_stand(study, 1) == INCOMPLETE


def test_a_case_held_by_a_live_runner_or_a_queued_task_is_running(study):
    cases = Study.open(study).cases
    for case in cases:
        set_manifest(case, "done")
    runner = subprocess.Popen(["sleep", "60"])
    try:
        set_manifest(cases[2], "running", steps_done=10, host=socket.gethostname(),
                     pid=runner.pid, pid_start=start_time(runner.pid))
        assert local_stand(study, 1) == RUNNING
    finally:
        runner.kill()
        runner.wait()
    assert local_stand(study, 1) == INCOMPLETE             # its runner died: to resume
    held = eligible(Study.open(study).cases, queued={2: "7_2"})
    assert stand(read_rounds(study), 1, held, study) == RUNNING


def test_a_stopping_look_stops_it_and_a_round_ahead_of_the_looks_is_refused(study):
    rounds = read_rounds(study)
    with pytest.raises(ConfigError, match=r"names round 2, the rounds record 0 look\(s\)"):
        stand(rounds, 2, Eligible(()), study)
    write_rounds(study, rounds.with_look(Look(1, 0.025, 0.1, stop="decided: met",
                                              stop_kind=DECIDED)))
    assert stand(read_rounds(study), 1, Eligible(()), study) == STOPPED


def test_the_follow_up_job_and_the_local_loop_decide_alike(study):
    """``progress`` (a scheduler's view: the round its jobs name, their queued tasks) and
    the local loop's view of the same folder give the same state, state after state."""
    append_record(study, {"kind": "array", "job_id": "1", "indices": [0, 1, 2, 3],
                          "study_round": 1})
    idle = SlurmScheduler(SITE, Squeue())
    cases = Study.open(study).cases
    set_manifest(cases[0], "done")
    set_manifest(cases[2], "killed", steps_done=10)
    assert progress(study, idle).state == local_stand(study, 1) == INCOMPLETE
    assert progress(study, idle).unfinished == eligible(cases).indices == (1, 2, 3)
    for case in cases:
        set_manifest(case, "done")
    assert progress(study, idle).state == local_stand(study, 1) == LOOK_DUE
    busy = SlurmScheduler(SITE, Squeue("1_2|1|2|RUNNING|None\n"))
    assert progress(study, busy).state == RUNNING
    write_rounds(study, read_rounds(study).with_look(Look(1, 0.025, 0.1)))
    assert progress(study, idle).state == local_stand(study, 1) == ROUND_DUE


def test_one_loop_acts_on_each_state_until_the_study_stops_or_an_act_ends_it(study):
    """rounds.drive, the loop the local rounds and the follow-up job both run: on this
    folder a due round is handed out, its cases done, the look taken and the study
    stopped, each act on the state stand gives, read afresh each turn; an act that
    returns False (a round handed to a scheduler) ends the loop in its state."""
    done: list = []
    handed = [0]

    def state():
        rounds = read_rounds(study)
        return stand(rounds, handed[0], eligible(Study.open(study).cases)
                     if handed[0] > len(rounds.looks) else Eligible(()), study)

    def hand_out():
        done.append(ROUND_DUE)
        handed[0] = len(read_rounds(study).looks) + 1
        return True

    def run():
        done.append(INCOMPLETE)
        for case in Study.open(study).cases:
            set_manifest(case, "done")
        return True

    def look():
        done.append(LOOK_DUE)
        write_rounds(study, read_rounds(study).with_look(Look(
            1, 0.025, 0.1, stop="decided: met", stop_kind=DECIDED)))
        return True

    assert drive(state, {ROUND_DUE: hand_out, INCOMPLETE: run, RUNNING: run,
                         LOOK_DUE: look}) == STOPPED
    assert done == [ROUND_DUE, INCOMPLETE, LOOK_DUE]
    # a round handed to a scheduler that runs it on its own: the loop ends in its state
    assert drive(lambda: ROUND_DUE, {ROUND_DUE: lambda: False}) == ROUND_DUE
