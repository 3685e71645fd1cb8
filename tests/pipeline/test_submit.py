"""The pipeline on a scheduler: the ranks come from the planner local runs use, one array per
phase of that schedule, and the scheduler interface's cancel (Slurm, on captured text).
No scheduler, no engine: Slurm's commands are answered by recorders."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from ligwf.engine.plan import plan_study
from ligwf.errors import SubmitError
from ligwf.pipeline.prepare import prepare_workflow, prepared_loads, write
from ligwf.pipeline.submit import plan_resubmission, plan_submission
from ligwf.scheduler import Scheduler
from ligwf.slurm.jobs import append_record
from ligwf.slurm.scheduler import SlurmScheduler
from ligwf.slurm.site import SlurmSite

from helpers import DRUM, ROOT

CAPTURED = ROOT / "tests" / "data" / "slurm"
WITH_BIG = ["sweep.cg_levels=[3,1]", "scene.drum.length=0.018"]  # CG1: ~12,000 particles
SITE = SlurmSite(ligwf="/venv/bin/ligwf", ntasks=1)


def _arrays(submission) -> list[tuple[tuple[int, ...], int]]:
    return [(j.indices, j.site.ntasks) for j in submission.jobs if j.kind == "array"]


@pytest.mark.parametrize("cores", [2, 3])
def test_slurm_ranks_are_the_local_rank_plan_and_each_phase_is_one_array(tmp_path, cores):
    prepared = prepare_workflow(DRUM, WITH_BIG)
    scheduler = SlurmScheduler(SITE)
    assert isinstance(scheduler, Scheduler)     # every operation of the interface is there
    sub = plan_submission(prepared, tmp_path / "s", scheduler, cores, None)
    local = plan_study(prepared_loads(prepared), cores)
    assert [(c.name, c.ranks, c.bound) for c in sub.schedule.cases] == [
        (c.name, c.ranks, c.bound) for c in local.cases]
    assert sub.planned
    index = {rc.case.case_id: rc.case.index for rc in prepared.rendered}
    assert _arrays(sub) == [(tuple(sorted(index[n] for n in ph.cases)), ph.ranks)
                            for ph in sub.schedule.phases]
    assert {ph.ranks for ph in sub.schedule.phases} == {c.ranks for c in local.cases}
    assert sub.jobs[-1].kind == "analysis"
    assert "ligwf analyse" in sub.jobs[-1].script_text


def test_ntasks_puts_every_case_on_that_many_ranks_in_one_array(tmp_path):
    prepared = prepare_workflow(DRUM, WITH_BIG)
    sub = plan_submission(prepared, tmp_path / "s", SlurmScheduler(SITE.with_overrides(ntasks=2)),
                          None, 2, analysis=False)
    assert not sub.planned
    assert {(c.ranks, c.bound) for c in sub.schedule.cases} == {(2, "--ntasks")}
    assert _arrays(sub) == [((0, 1, 2), 2)]
    assert all(j.kind == "array" for j in sub.jobs)


class Recorder:
    """Answers squeue with captured text, forgets every job in scontrol, records scancel."""

    def __init__(self, squeue: str, scancel_code: int = 0) -> None:
        self.squeue, self.scancel_code, self.cancelled = squeue, scancel_code, []

    def __call__(self, argv):
        if argv[0] == "squeue":
            return subprocess.CompletedProcess(argv, 0, stdout=self.squeue, stderr="")
        if argv[0] == "scontrol":
            return subprocess.CompletedProcess(
                argv, 1, stdout="", stderr="slurm_load_jobs error: Invalid job id specified")
        assert argv[0] == "scancel", argv
        self.cancelled.append(list(argv))
        return subprocess.CompletedProcess(argv, self.scancel_code, stdout="",
                                           stderr="scancel: error: Kill job error")


def _submitted_study(tmp_path, monkeypatch) -> Path:
    """A written 4-case study recorded as array job 1 (cases 0-3) + analysis job 2, the
    ids of the captured squeue text."""
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    out = tmp_path / "study"
    study = write(prepare_workflow(DRUM, ["sweep.cg_levels=[3,2]"]), out)
    assert len(study.cases) == 4
    append_record(out, {"kind": "array", "job_id": "1", "indices": [0, 1, 2, 3]})
    append_record(out, {"kind": "analysis", "job_id": "2", "indices": [0, 1, 2, 3],
                        "after": "1"})
    return out


def test_cancel_stops_the_queued_array_and_the_waiting_analysis_job(tmp_path, monkeypatch):
    out = _submitted_study(tmp_path, monkeypatch)
    run = Recorder((CAPTURED / "squeue_array_running.txt").read_text())
    assert SlurmScheduler(SITE, run).cancel(out) == ["1", "2"]
    assert run.cancelled == [["scancel", "1"], ["scancel", "2"]]


def test_cancel_of_a_finished_study_cancels_nothing_and_a_refusal_is_an_error(tmp_path,
                                                                            monkeypatch):
    out = _submitted_study(tmp_path, monkeypatch)
    idle = Recorder("")
    assert SlurmScheduler(SITE, idle).cancel(out) == [] and idle.cancelled == []
    refused = Recorder((CAPTURED / "squeue_array_running.txt").read_text(), scancel_code=1)
    with pytest.raises(SubmitError, match="scancel 1 exited 1: scancel: error: Kill job error"):
        SlurmScheduler(SITE, refused).cancel(out)


def test_resubmit_plans_the_missing_cases_again_on_the_recorded_cores(tmp_path, monkeypatch):
    out = _submitted_study(tmp_path, monkeypatch)
    again = plan_resubmission(out, SlurmScheduler(SITE, Recorder("")), False, None,
                              planned=True, recorded_cores=4)
    assert again.indices == (0, 1, 2, 3) and not again.busy
    arrays = [j for j in again.jobs if j.kind == "array"]
    assert all(j.planned and j.plan_cores == 4 for j in arrays)
    assert sorted(i for j in arrays for i in j.indices) == [0, 1, 2, 3]
    assert [j.script_path.name for j in again.jobs][-1] == "analysis-2.sh"
    queued = plan_resubmission(out, SlurmScheduler(
        SITE, Recorder((CAPTURED / "squeue_array_running.txt").read_text())), False, None,
        planned=True)
    assert queued.indices == () and queued.jobs == ()
    assert [c.index for c in queued.busy] == [0, 1, 2, 3]


def test_cli_cancel_says_what_it_cancelled(tmp_path, monkeypatch, capsys):
    import ligwf.slurm.scheduler as slurm_scheduler
    from ligwf.cli.main import main

    out = _submitted_study(tmp_path, monkeypatch)
    run = Recorder((CAPTURED / "squeue_array_running.txt").read_text())
    # the registry (ligwf.executors) builds the scheduler: it gets the recorder here
    monkeypatch.setattr(slurm_scheduler, "SlurmScheduler",
                        lambda site: SlurmScheduler(site, run))
    assert main(["slurm", "cancel", str(out)]) == 0
    text = capsys.readouterr().out
    assert "cancelled job(s) 1, 2" in text and "ligwf slurm resubmit" in text
    assert run.cancelled == [["scancel", "1"], ["scancel", "2"]]
    run.squeue = ""
    assert main(["slurm", "cancel", str(out)]) == 0
    assert "nothing to cancel" in capsys.readouterr().out
