"""The runners branch on kinds, not on words (issue 33 item 1): a case's plan says why as a
:class:`ligwf.engine.resume.Why`, a manifest's stop as a :class:`ligwf.study.manifest.Stop`,
and a manifest written before ``stop`` was recorded gets its kind from its words."""

from __future__ import annotations

import json
import subprocess

import pytest

from helpers import ROOT
from ligwf.cli.main import main
from ligwf.cli.run import elsewhere
from ligwf.engine.resume import FRESH, SKIP, Why, plan_case
from ligwf.study.manifest import Manifest, Stop
from ligwf.study.processes import start_time
from ligwf.study.study import Study

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


@pytest.mark.parametrize("reason, kind", [
    ("disk full (812 bytes left in /x): engine segfault", Stop.DISK_FULL),
    ("incomplete record (no rows past step 400): resume before it", Stop.INCOMPLETE_RECORD),
    ("restart restart/restart_a.liggghts unreadable (ERROR: bad restart); set aside",
     Stop.RESTART_SET_ASIDE),
    ("interrupted by the user (SIGINT) at step 3 of 9", Stop.INTERRUPTED),
    ("stopped when the ensemble job ended (mpirun exit code 1) at step 3 of 9", Stop.JOB_ENDED),
    ("ensemble job ended (mpirun exit code 1) with no member making progress", Stop.NO_PROGRESS),
    ("finished: all 9 steps", Stop.NONE),
    ("restart file restart/restart_a.liggghts was fine", Stop.NONE),
])
def test_a_manifest_from_before_stop_kinds_reads_its_kind_from_its_words(reason, kind):
    legacy = {"case_id": "c", "scene_hash": "h", "status": "killed", "reason": reason}
    assert Manifest.from_dict(legacy).stop is kind


def test_a_stored_stop_wins_over_the_words_and_round_trips_as_its_value():
    m = Manifest(case_id="c", index=0, scene_hash="h", ligwf_version="", liggghts_version="",
                 status="killed", reason="disk full, said in passing", stop=Stop.JOB_ENDED)
    data = json.loads(json.dumps(m.to_dict()))
    assert data["stop"] == "job_ended"
    assert Manifest.from_dict(data).stop is Stop.JOB_ENDED
    # a kind this ligwf does not know (a newer one's) falls back to the words
    assert Manifest.from_dict({**data, "stop": "meteor"}).stop is Stop.DISK_FULL


def test_a_case_held_by_a_live_runner_is_said_by_its_kind_not_its_words(tmp_path):
    out = tmp_path / "study"
    assert main(["render", str(TINY), "--out", str(out), "--set", "sweep.rules=[bond]"]) == 0
    case = Study.open(out).cases[0]
    assert plan_case(case).why is Why.NOT_RUN and plan_case(case).action is FRESH
    runner = subprocess.Popen(["sleep", "60"])      # another live process holds the case
    try:
        case.write_manifest(Manifest(case_id=case.case_id, index=case.index,
                                     scene_hash=case.scene_hash, ligwf_version="",
                                     liggghts_version="", status="running",
                                     reason="held by another word entirely", pid=runner.pid,
                                     pid_start=start_time(runner.pid)))
        plan = plan_case(case)
        assert (plan.action, plan.why) == (SKIP, Why.HELD)
        assert elsewhere([case], False) == [
            f"{case.path.name}: {plan.reason}: left to that runner"]
    finally:
        runner.kill()
        runner.wait()
    # its runner gone, the case is killed: resumed or run again, not left to anyone
    assert plan_case(case).why is Why.KILLED and elsewhere([case], False) == []
    case.write_manifest(Manifest(case_id=case.case_id, index=case.index,
                                 scene_hash=case.scene_hash, ligwf_version="",
                                 liggghts_version="", status="done"))
    assert plan_case(case).why is Why.DONE and elsewhere([case], False) == []
