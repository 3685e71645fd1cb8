"""``ligwf status`` shows the live step of a case whose attempt is under way (issue 46 item 6).

A manifest records the steps of finished attempts only; the runner (alone or an ensemble
member) writes the engine's screen into the case's ``run.log``. The status table read
0/315,231 and "not run yet" (the plan's reason) for a case at step 168,640; it now reads
the screen. A real process stands for the live runner, a dead one for a killed runner.
"""

from __future__ import annotations

import subprocess

from ligwf.cli.main import main
from ligwf.engine.progress import summary_table
from ligwf.study.case import CaseFolder
from ligwf.study.manifest import Manifest, write_manifest
from ligwf.study.processes import start_time
from ligwf.study.study import Study

from helpers import ROOT

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"
SCREEN = """LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0)
ligwf-phase production
    Step           Time    Atoms         KinEng            rke          ts[1]          ts[2]            CPU
  168470      1.6577892    13333    0.013659931  0.00071004061           0.16     0.05872488      365.88859
  168640      1.6627825    13333    0.012566988  0.00071630089           0.16    0.056537588      367.93925
"""


def _running(case: CaseFolder, pid: int) -> None:
    m = Manifest(case_id=case.case_id, index=case.index, scene_hash=case.scene_hash,
                 ligwf_version="test", liggghts_version="", launcher="ensemble", pid=pid,
                 pid_start=start_time(pid), reason="not run yet", total_steps=315231)
    write_manifest(case.path, m)
    case.screen.write_text(SCREEN)


def test_status_shows_the_live_step_of_a_running_and_of_a_killed_case(tmp_path, capsys):
    out = tmp_path / "study"
    assert main(["render", str(TINY), "--out", str(out), "--mesh-cache",
                 str(tmp_path / "meshes")]) == 0
    live, dead = Study.open(out).cases
    runner = subprocess.Popen(["sleep", "60"])
    gone = subprocess.Popen(["true"])
    gone.wait()
    try:
        _running(live, runner.pid)
        _running(dead, gone.pid)
        capsys.readouterr()
        assert main(["status", str(out)]) == 0
        table = summary_table(Study.open(out).cases)
    finally:
        runner.kill()
        runner.wait()
    cells = {c.header: list(c.cells) for c in table.columns}
    assert cells["steps"] == ["168,640/315,231", "168,640/315,231"]
    assert cells["reason"][0] == "running: step 168,640 of 315,231 (live, run.log)"
    assert cells["reason"][1].startswith("killed: its runner is gone; the screen reached step "
                                         "168,640")
    assert "not run yet" not in capsys.readouterr().out
