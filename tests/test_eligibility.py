"""What a study still needs (ligwf.eligibility), read from its folder, and the one answer
a local run, ``ligwf slurm resubmit`` and the rounds on a scheduler all give: no engine, no
scheduler (Slurm's commands answered by a recorder that knows no job)."""

from __future__ import annotations

import os
import subprocess

import pytest

from ligwf.eligibility import (DONE, EXTEND, FRESH, HELD, RESUME, UNSTABLE, analysis_due,
                               eligible, report_due)
from ligwf.pipeline.prepare import prepare_workflow, write
from ligwf.pipeline.submit import plan_resubmission
from ligwf.pipeline.rounds import INCOMPLETE, LOOK_DUE
from ligwf.pipeline.submit_rounds import progress
from ligwf.slurm.jobs import append_record
from ligwf.slurm.scheduler import SlurmScheduler
from ligwf.slurm.site import SlurmSite
from ligwf.study.extension import extend_production
from ligwf.study.layout import REPORT_FILES_RECORD, ROUNDS_FILE
from ligwf.study.manifest import Manifest
from ligwf.study.study import Study

from helpers import ROOT

WORKFLOW = ROOT / "tests" / "workflows" / "rounds_tiny.yaml"      # 4 cases
SITE = SlurmSite(ligwf="/venv/bin/ligwf", ntasks=1)


def idle_slurm(argv):
    """squeue: nothing queued; scontrol: every job forgotten; sbatch: job 100."""
    if argv[0] == "squeue":
        return subprocess.CompletedProcess(argv, 0, stdout="", stderr="")
    if argv[0] == "scontrol":
        return subprocess.CompletedProcess(argv, 1, stdout="", stderr="slurm_load_jobs error: Invalid job id specified")
    return subprocess.CompletedProcess(argv, 0, stdout="100\n", stderr="")


def set_manifest(case, status: str, steps_done: int | None = None, **more) -> None:
    steps = case.scaled.total_steps if steps_done is None else steps_done
    more.setdefault("scene_hash", case.scene_hash)
    case.write_manifest(Manifest(case_id=case.case_id, index=case.index, ligwf_version="",
                                 liggghts_version="", status=status, steps_done=steps,
                                 total_steps=case.scaled.total_steps, **more))


@pytest.fixture
def study(tmp_path, monkeypatch):
    """The tiny rounds study written, submitted as round 1 of a sequential study (array 1,
    follow-up 2, both ended): case 0 done, case 1 done and then its production extended
    (its manifest still reads done), case 2 killed before any restart, case 3 never ran."""
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    out = tmp_path / "study"
    write(prepare_workflow(WORKFLOW), out)
    cases = Study.open(out).cases
    set_manifest(cases[0], "done")
    set_manifest(cases[1], "done")
    assert extend_production([cases[1]], 0.1)
    set_manifest(cases[2], "killed", steps_done=10)
    append_record(out, {"kind": "array", "job_id": "1", "indices": [0, 1, 2, 3],
                        "study_round": 1})
    append_record(out, {"kind": "analysis", "job_id": "2", "indices": [0, 1, 2, 3],
                        "after": "1", "steps": ["slurm next-round"], "study_round": 1})
    return out


def test_each_case_need_is_read_from_its_folder(study):
    cases = Study.open(study).cases
    needs = eligible(cases)
    assert [t.need for t in needs.tasks] == [DONE, EXTEND, RESUME, FRESH]
    assert needs.indices == (1, 2, 3) and not needs.settled
    assert "production extended" in needs.of(1).reason
    # a task the executor still has queued holds its case, whatever the folder says
    assert eligible(cases, queued={1: "7_1"}).of(1).need is HELD
    assert eligible(cases, queued={1: "7_1"}).indices == (2, 3)
    # unstable is left alone unless asked; failed and re-rendered cases run afresh
    set_manifest(cases[3], "unstable", reason="blew up")
    assert eligible(cases).of(3).need is UNSTABLE
    assert eligible(cases, retry_unstable=True).of(3).need is FRESH
    set_manifest(cases[3], "failed", reason="engine error")
    assert eligible(cases).of(3).need is FRESH
    set_manifest(cases[0], "done", scene_hash="another scene")
    assert eligible(cases).of(0).need is FRESH
    # 'running' whose runner is gone (SIGKILL, a time limit): stopped, to be continued
    gone = subprocess.Popen(["true"])
    gone.wait()
    set_manifest(cases[0], "running", steps_done=10, pid=gone.pid)
    assert eligible(cases).of(0).need is RESUME


def test_a_run_a_resubmit_and_the_rounds_agree_on_an_extended_done_case(study):
    """The disagreement of issue 48: ``slurm resubmit`` chose by the manifest's word
    (missing, failed, killed, running) and skipped a done case whose production was
    extended, which a local run and the rounds continue. One rule now."""
    local = eligible(Study.open(study).cases).indices
    resubmit = plan_resubmission(study, SlurmScheduler(SITE, idle_slurm), False, None,
                                 planned=False, analysis=False)
    rounds = progress(study, SlurmScheduler(SITE, idle_slurm))
    assert local == resubmit.indices == rounds.unfinished == (1, 2, 3)
    assert rounds.state == INCOMPLETE
    assert sorted(i for j in resubmit.jobs for i in j.indices) == [1, 2, 3]
    # every case done to its (extended) end: nothing to run anywhere, the look is due
    cases = Study.open(study).cases
    for case in cases:
        set_manifest(case, "done")
    assert eligible(cases).settled
    assert plan_resubmission(study, SlurmScheduler(SITE, idle_slurm), False, None,
                             planned=False).indices == ()
    assert progress(study, SlurmScheduler(SITE, idle_slurm)).state == LOOK_DUE


def test_the_analysis_and_the_report_are_due_until_their_records_hold(study):
    s = Study.open(study)
    assert analysis_due(s) == "not analysed yet"
    s.analysis_dir.mkdir()
    (s.analysis_dir / "analysis.json").write_text("[1]")
    assert analysis_due(s).startswith("its record is unreadable")
    (s.analysis_dir / "analysis.json").write_text("{}")
    assert "records no provenance" in analysis_due(s)
    assert report_due(s)
    s.report_dir.mkdir()
    written = s.report_dir / REPORT_FILES_RECORD
    written.write_text("{}")
    os.utime(s.analysis_dir / "analysis.json", ns=(1, 1))
    assert not report_due(s)
    (study / ROUNDS_FILE).write_text("{}")          # a look taken since: the report is due
    os.utime(written, ns=(2, 2))
    assert report_due(s)


def test_slurm_status_shows_each_case_need_beside_its_manifest(study, monkeypatch):
    import ligwf.cli.slurm as cli_slurm
    from ligwf.slurm.jobs import study_status

    monkeypatch.setattr(cli_slurm, "study_status", lambda path, tolerant: study_status(
        path, idle_slurm, tolerant=tolerant))
    _, data = cli_slurm.status_table(study)
    assert [(c["manifest"], c["next"]) for c in data["cases"]] == [
        ("done", "done"), ("done", "extend"), ("killed", "resume"), ("missing", "fresh")]
    assert data["analysis_due"] == "not analysed yet"


def test_local_status_says_what_each_case_needs_next(study, capsys):
    """``ligwf status`` (this machine) names the same need as the Slurm status and a run:
    the extended done case is to be extended, the killed one resumed; a live runner's case
    is held."""
    from ligwf.cli.main import main
    from ligwf.cli.run import needs_lines

    assert main(["status", str(study)]) == 0
    shown = capsys.readouterr().out
    assert "extend (production extended to step" in shown
    assert "next resume (killed at step 10)" in shown and "next fresh (not run yet)" in shown
    assert "analysis due: not analysed yet" in shown
    lines = needs_lines(Study.open(study), {2: "123@here"})
    assert lines[1].endswith(": next held (queued or running as 123@here)"), lines
