"""The pipeline runs cases only through the executor interface (issue 33 item 1): a study
written, run by an executor that is not this machine's, analysed and reported, in the
fast lane (the analysis split into share processes, their kill -9 and the toy scheduler,
a few seconds of subprocesses each, run in the slow lane). The executor here replays the committed real engine output of
``tests/data/cg3_slice`` (its dumps are what the committed input of that scene wrote,
``tests/data/README.md``) into the case it is asked to run, so the analysis and the report
read real LIGGGHTS dumps; the local and Slurm executors satisfy the same interface."""

from __future__ import annotations

import json
import shutil
import threading
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd
import pytest

from helpers import DRUM, ROOT
from ligwf.local import LocalCase, LocalExecutor, LocalStatus
from ligwf.pipeline.post import postprocess
from ligwf.pipeline.prepare import prepare_workflow, write
from ligwf.pipeline.run import Interrupted, run_study
from ligwf.scheduler import Executor, JobRound, Scheduler, SubmitAndWait
from ligwf.slurm.scheduler import SlurmScheduler
from ligwf.slurm.site import SlurmSite
from ligwf.study import layout
from ligwf.study.manifest import MISSING, Manifest
from ligwf.study.study import Study

DATA = ROOT / "tests" / "data" / "cg3_slice" / "cg3-weber-r0"
# the scene of tests/data/cg3_slice (the command in tests/data/README.md)
SCENE = ["sweep.cg_levels=[3]", "sweep.rules=[weber]", "scene.process.settle_time=0.1",
         "scene.process.run_time=0.6", "scene.numerics.dump_interval=0.2"]


@dataclass
class ReplayExecutor:
    """Runs a case by copying the committed engine output of its scene into its folder
    and recording it done, as the engine's runner would; a case of another scene fails."""

    ran: list[str] = field(default_factory=list)
    analysed: list[int] = field(default_factory=list)
    name = "replay"

    def require(self) -> None:
        pass

    def run_cases(self, study, cases, monitor=None, stop=None) -> bool:
        done = True
        for case in cases:
            if stop is not None and stop.is_set():
                return False
            recorded = Manifest.from_dict(json.loads((DATA / layout.MANIFEST_FILE).read_text()))
            ok = recorded.scene_hash == case.scene_hash
            if ok:
                for dump in (DATA / layout.POST_DIR).iterdir():
                    shutil.copy2(dump, case.path / layout.POST_DIR / dump.name)
                shutil.copy2(DATA / layout.THERMO_FILE, case.path / layout.THERMO_FILE)
            case.write_manifest(Manifest(
                case_id=case.case_id, index=case.index, scene_hash=case.scene_hash,
                ligwf_version="", liggghts_version="3.8.0 (replayed)",
                status="done" if ok else "failed",
                reason="" if ok else "no committed output of this scene",
                steps_done=case.scaled.total_steps, total_steps=case.scaled.total_steps,
                atoms_start=222, atoms_end=222, wall_seconds=41.0, core_seconds=41.0))
            self.ran.append(case.case_id)
            done = done and ok
        return done

    def analyse(self, study, tasks: int = 1, stop=None) -> dict | None:
        """The replayed dumps lie on this machine: analysed here."""
        self.analysed.append(tasks)
        return LocalExecutor().analyse(study, tasks, stop)

    def status(self, study_dir: Path, tolerant: bool = False) -> LocalStatus:
        return LocalStatus([LocalCase(c.index, c.case_id,
                                      m.status if (m := c.manifest()) else MISSING)
                            for c in Study.open(study_dir).cases])

    def cancel(self, study_dir: Path) -> list[str]:
        return []


def test_every_executor_has_the_one_interface():
    for ex in (ReplayExecutor(), LocalExecutor(), SlurmScheduler(SlurmSite())):
        assert isinstance(ex, Executor), ex
    assert isinstance(SlurmScheduler(SlurmSite()), Scheduler)
    assert not isinstance(LocalExecutor(), Scheduler)      # this machine queues nothing


def test_the_whole_pipeline_runs_through_an_executor(tmp_path):
    study = write(prepare_workflow(DRUM, SCENE), tmp_path / "study", tmp_path / "meshes")
    (case,) = study.cases
    ex = ReplayExecutor()
    assert run_study(study, study.cases, ex)
    assert ex.ran == [case.case_id]
    postprocess(study.path, ex, snapshots=False)
    assert ex.analysed == [1]
    analysis = pd.read_csv(study.path / layout.ANALYSIS_DIR / "flow.csv")
    assert list(analysis["case_id"]) == [case.case_id]
    cases = pd.read_csv(study.report_dir / layout.CASES_REPORT)
    assert list(cases["case_id"]) == [case.case_id]
    # the flow metrics of the replayed frames (the engine's own dumps), as measured
    assert 30 < cases["angle_of_repose"].iloc[0] < 60
    assert (study.report_dir / "summary.md").is_file()
    assert [c.manifest for c in ex.status(study.path).cases] == ["done"]


def test_a_case_the_executor_cannot_run_is_not_done_and_nothing_else_runs_after_a_stop(
        tmp_path):
    study = write(prepare_workflow(DRUM, [*SCENE, "scene.process.run_time=0.4"]),
                  tmp_path / "study", tmp_path / "meshes")
    assert not run_study(study, study.cases, ReplayExecutor())    # another scene: failed
    assert study.cases[0].manifest().status == "failed"
    stop = threading.Event()
    stop.set()
    with pytest.raises(Interrupted):
        run_study(study, study.cases, ReplayExecutor(), None, stop)


@pytest.mark.slow
def test_a_local_analysis_split_into_shares_writes_the_same_bytes(tmp_path):
    """LocalExecutor.analyse in 2 shares (2 processes, then the merge) against 1, on the
    replayed real dumps: every table byte for byte, the share screens kept."""
    study = write(prepare_workflow(DRUM, SCENE), tmp_path / "study", tmp_path / "meshes")
    assert run_study(study, study.cases, ReplayExecutor())
    one = LocalExecutor().analyse(study, 1)
    tables = {p.name: p.read_bytes() for p in study.analysis_dir.glob("*.csv")}
    assert "flow.csv" in tables
    two = LocalExecutor().analyse(study, 2)
    assert {p.name: p.read_bytes() for p in study.analysis_dir.glob("*.csv")} == tables
    assert [c["analysed"] for c in two["cases"]] == [c["analysed"] for c in one["cases"]]
    assert len(list((study.path / layout.ANALYSIS_SHARE_LOG_DIR).glob("share-*.log"))) == 2


def test_a_local_analysis_stopped_mid_way_merges_nothing(tmp_path):
    study = write(prepare_workflow(DRUM, SCENE), tmp_path / "study", tmp_path / "meshes")
    assert run_study(study, study.cases, ReplayExecutor())
    stop = threading.Event()
    stop.set()
    assert LocalExecutor().analyse(study, 2, stop) is None
    assert not (study.analysis_dir / layout.ANALYSIS_RECORD).exists()


def _shares_of(study: Path) -> list[int]:
    """Pids of the analysis shares (``ligwf analyse STUDY --part``) running on ``study``."""
    pids = []
    for proc in Path("/proc").iterdir():
        try:
            argv = (proc / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        if b"--part" in argv and str(study).encode() in argv:
            pids.append(int(proc.name))
    return pids


@pytest.mark.slow
def test_shares_end_with_a_sigkilled_ligwf_and_leave_no_part(tmp_path):
    """kill -9 of the process running LocalExecutor.analyse(study, 2): its shares end with
    it (the kernel's parent-death signal) instead of computing on for nobody: no share
    process is left and none wrote its part. Without the signal they finish their shares
    (a few seconds of work after their imports) and write both parts."""
    import os
    import signal
    import subprocess
    import sys
    import time

    study = write(prepare_workflow(DRUM, SCENE), tmp_path / "study", tmp_path / "meshes")
    assert run_study(study, study.cases, ReplayExecutor())
    parent = subprocess.Popen(
        [sys.executable, "-c", "import sys; from ligwf.local import LocalExecutor; "
         "from ligwf.study.study import Study; "
         "LocalExecutor().analyse(Study.open(sys.argv[1]), 2)", str(study.path)])
    deadline = time.monotonic() + 60
    while len(_shares_of(study.path)) < 2:
        assert parent.poll() is None and time.monotonic() < deadline, "no shares started"
        time.sleep(0.05)
    os.kill(parent.pid, signal.SIGKILL)
    parent.wait()
    deadline = time.monotonic() + 30
    while _shares_of(study.path):
        assert time.monotonic() < deadline, "the shares outlived their ligwf"
        time.sleep(0.1)
    assert not list(study.analysis_dir.parent.rglob("part-*")), "a share finished its part"
    assert not (study.analysis_dir / layout.ANALYSIS_RECORD).exists()


@dataclass
class ToyQueue(SubmitAndWait):
    """A batch scheduler with the job verbs only (plan, submit, status, cancel, require):
    a job runs when it is submitted (an array replays its cases, an analysis job analyses
    here in its shares), so nothing is ever queued. Running and waiting come from
    SubmitAndWait, as for Slurm."""

    asked: list = field(default_factory=list)
    record: list = field(default_factory=list)
    name = "toy"
    poll_seconds: float = 0.01

    def require(self) -> None:
        pass

    def plan_jobs(self, study_dir, study_name, request: JobRound) -> list[dict]:
        self.asked.append(request)
        jobs = [{"kind": "array", "indices": request.indices}] if request.indices else []
        if request.post_steps:
            jobs.append({"kind": "analysis", "tasks": request.analysis_tasks})
        return jobs

    def submit(self, study_dir, jobs) -> list[dict]:
        study = Study.open(study_dir)
        entries = []
        for job in jobs:
            if job["kind"] == "array":
                ReplayExecutor().run_cases(study, [study.case(i) for i in job["indices"]])
            else:
                LocalExecutor().analyse(study, job["tasks"])
            entries.append({**job, "job_id": str(len(self.record) + 1)})
            self.record.append(entries[-1])
        return entries

    def status(self, study_dir, tolerant: bool = False) -> LocalStatus:
        cases = [LocalCase(c.index, c.case_id, m.status if (m := c.manifest()) else MISSING)
                 for c in Study.open(study_dir).cases]
        return LocalStatus(cases, [{**j, "state": "ENDED", "active": False,
                                    "completed": True} for j in self.record])

    def cancel(self, study_dir) -> list[str]:
        return []


@pytest.mark.slow
def test_a_scheduler_with_the_job_verbs_only_runs_the_whole_pipeline(tmp_path):
    """Issue 48 item 1: a new scheduler implements plan, submit, status, cancel and
    require; running the cases and the analysis and waiting for them are SubmitAndWait's,
    written once. The study runs, is analysed in 2 shares and reported through it."""
    queue = ToyQueue()
    assert isinstance(queue, Scheduler) and isinstance(queue, Executor)
    study = write(prepare_workflow(DRUM, SCENE), tmp_path / "study", tmp_path / "meshes")
    (case,) = study.cases
    assert run_study(study, study.cases, queue)
    cases_round, = queue.asked
    assert cases_round.indices == (case.index,) and set(cases_round.ranks) == {case.index}
    assert not cases_round.post_steps                   # the cases alone, no follow-up job
    record, report = postprocess(study.path, queue, snapshots=False, analysis_tasks=2)
    split = queue.asked[-1]
    assert (split.indices, split.post_steps, split.analysis_tasks) == ((), ("analyse",), 2)
    assert split.token and record is not None and record["cases"]
    assert (report / "summary.md").is_file()
