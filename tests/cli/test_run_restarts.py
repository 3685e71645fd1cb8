"""A restart the runner does not use is said, not skipped silently (issue 32, item 4): one
line in the run output and one ``restart_skipped`` issue in the case's manifest, each
naming the file, why, and what the case does instead."""

from __future__ import annotations

import struct

from helpers import ROOT
from ligwf.cli.main import main
from ligwf.cli.run import skipped_restarts
from ligwf.engine.attempt import begin_attempt, finish_attempt, resume_before
from ligwf.engine.restart_id import CaseIdentity, stamp
from ligwf.engine.resume import FRESH, RESTART_SKIPPED, RESUME, plan_case
from ligwf.study.manifest import Manifest
from ligwf.study.study import Study

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


def restart_header(step: int) -> bytes:
    """The header of a LIGGGHTS 3.8.0 restart file (ligwf.engine.liggghts.restart_step)."""
    version = b"LIGGGHTS-PUBLIC 3.8.0"
    return (struct.pack("<ii", 0, len(version)) + version
            + b"".join(struct.pack("<ii", k, 4) for k in (1, 2, 3))
            + struct.pack("<ii", 4, 2) + b"si" + struct.pack("<iq", 5, step) + bytes(64))


def killed_case(tmp_path, steps_done: int = 3000, complete_upto: int | None = None):
    out = tmp_path / "study"
    assert main(["render", str(TINY), "--out", str(out), "--set", "sweep.rules=[bond]"]) == 0
    case = Study.open(out).cases[0]
    case.write_manifest(Manifest(case_id=case.case_id, index=case.index,
                                 scene_hash=case.scene_hash, ligwf_version="",
                                 liggghts_version="", status="killed", steps_done=steps_done,
                                 complete_upto=complete_upto,
                                 total_steps=case.scaled.total_steps))
    (case.path / "restart").mkdir(exist_ok=True)
    return out, case


def test_a_truncated_or_foreign_restart_is_named_with_what_the_case_does_instead(tmp_path):
    out, case = killed_case(tmp_path)
    (case.path / "restart" / "restart_a.liggghts").write_bytes(b"")
    (case.path / "restart" / "restart_b.liggghts").write_bytes(restart_header(3000)[:12])
    lines = skipped_restarts(Study.open(out).cases, False)
    assert lines == [f"{case.case_id}: restart file restart/{n}: header unreadable (empty or "
                     "truncated), not used: the case runs again from step 0"
                     for n in ("restart_a.liggghts", "restart_b.liggghts")]
    # a whole restart the case did not write (no identity record) is not used either
    (case.path / "restart" / "restart_b.liggghts").write_bytes(restart_header(3000))
    (case.path / "restart" / "restart_a.liggghts").unlink()
    (line,) = skipped_restarts(Study.open(out).cases, False)
    assert "restart/restart_b.liggghts: no identity record" in line
    assert line.endswith("not used: the case runs again from step 0")


def test_a_skipped_restart_lands_in_the_manifest_issues_and_stays(tmp_path):
    _, case = killed_case(tmp_path)
    (case.path / "restart" / "restart_a.liggghts").write_bytes(restart_header(3000)[:12])
    plan = plan_case(case)
    assert plan.action == FRESH and len(plan.skipped) == 1
    manifest, attempt = begin_attempt(case, plan, 1, "mpirun")
    (issue,) = case.manifest().issues
    assert issue["kind"] == RESTART_SKIPPED and issue["message"] == plan.skipped[0]
    # the attempt's own verdict keeps it beside the health issues
    finish_attempt(case, manifest, attempt, exit_code=1, wall_seconds=0.0)
    assert [i["message"] for i in case.manifest().issues
            if i["kind"] == RESTART_SKIPPED] == list(plan.skipped)


def test_a_hole_left_by_a_full_disk_says_where_the_case_resumes_or_that_it_starts_over(
        tmp_path):
    """'resumes from a restart at or before step N' was promised and the case re-ran from
    step 0 when every restart lay past the hole: now the message says which it is."""
    _, case = killed_case(tmp_path, steps_done=3000, complete_upto=1500)
    restart = case.path / "restart" / "restart_a.liggghts"
    restart.write_bytes(restart_header(2000))
    assert stamp(case.path, CaseIdentity.of(case), 1, 0.0) == ["restart/restart_a.liggghts"]
    assert resume_before(case, 2500) == ("resumes from restart/restart_a.liggghts at step 2000 "
                                         "(the newest restart of its own at or before step 2500)")
    assert resume_before(case, 1500) == ("no restart of its own at or before step 1500: runs "
                                         "again from step 0")
    plan = plan_case(case)
    assert plan.action == FRESH
    assert "no restart file of its own at or before step 1500" in plan.reason
    assert plan.skipped == ("restart file restart/restart_a.liggghts: step 2000 is past the "
                            "case's recorded progress (step 1500), not used: the case runs "
                            "again from step 0",)
    # with the hole after the restart the case resumes from it, nothing skipped
    case.write_manifest(Manifest(case_id=case.case_id, index=case.index,
                                 scene_hash=case.scene_hash, ligwf_version="",
                                 liggghts_version="", status="killed", steps_done=3000,
                                 complete_upto=2500, total_steps=case.scaled.total_steps))
    plan = plan_case(case)
    assert plan.action == RESUME and plan.restart.step == 2000 and plan.skipped == ()


def test_the_planner_prices_what_is_left_of_a_resumed_case_not_the_whole_run(tmp_path):
    """An extended or killed case continues from its restart: the rank plan's estimate
    counts the steps after it (before, a 4.5 s extension of the source drum was planned as
    27 min, the whole runs again)."""
    from ligwf.local import RunSettings, study_schedule

    _, case = killed_case(tmp_path, steps_done=3000)
    fresh = study_schedule([case], RunSettings(nprocs=1)).cases[0]
    restart = case.path / "restart" / "restart_a.liggghts"
    restart.write_bytes(restart_header(2000))
    stamp(case.path, CaseIdentity.of(case), 1, 0.0)
    assert plan_case(case).action == RESUME
    left = study_schedule([case], RunSettings(nprocs=1)).cases[0]
    total = case.scaled.total_steps
    assert fresh.particle_steps == case.scaled.particles.count * total
    assert left.particle_steps == case.scaled.particles.count * (total - 2000)
    assert left.estimated_seconds < fresh.estimated_seconds
