"""MPI ensembles on the real engine: one mpirun, mpi4py groups, libliggghts via ctypes."""

from __future__ import annotations

import subprocess
import sys

import pytest

from ligwf.engine.ensemble import run_ensemble
from ligwf.engine.resume import render_resume, RestartFile
from ligwf.engine.site import EngineConfig
from ligwf.study.study import Study

from helpers import ROOT  # noqa: E402

WORKFLOW = ROOT / "tests" / "workflows" / "runner_tiny.yaml"
FOUR = ["--set", "sweep.replicas=2"]   # weber and bond, two seeds each
LONGER = ["--set", "scene.process.run_time=1.0"]


def ligwf(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ligwf.cli.main", *args], capture_output=True,
                          text=True, timeout=600)


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.slow
def test_four_members_on_ensemble_2(tmp_path):
    out = tmp_path / "study"
    r = ligwf("run", str(WORKFLOW), "--out", str(out), "--ensemble", "2", *FOUR)
    assert r.returncode == 0, r.stdout + r.stderr
    cases = Study.open(out).cases
    assert len(cases) == 4
    for c in cases:
        m = c.manifest()
        assert m.status == "done", m.reason
        assert m.launcher == "ensemble" and m.steps_done == m.total_steps
        assert m.atoms_end == 84 and list((c.path / "post").glob("particles_*.vtu"))
    # one mpirun for all four members
    assert [p.name for p in (out / ".ensemble").iterdir()] == ["launch-1"]


# Two ways an engine error ends an ensemble: an input typo goes through Error::all (the
# failing rank finalises MPI and waits while the others go on), a missing include file
# through Error::one (MPI_Abort kills every member in flight).
BREAKAGES = {
    "typo": ('print "ligwf-phase production"', 'bogus_command 1\nprint "ligwf-phase production"'),
    "abort": ('print "ligwf-phase production"', 'include no_such_file.in\nprint "ligwf-phase production"'),
}


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(BREAKAGES))
def test_broken_member_does_not_lose_the_others(tmp_path, kind):
    out = tmp_path / "study"
    # a production long enough (~2 s) that the others are still in flight when the broken
    # member fails at its start (at 0.1 s they could all be done: a race, not a test)
    r = ligwf("render", str(WORKFLOW), "--out", str(out), *FOUR, *LONGER)
    assert r.returncode == 0, r.stderr
    cases = Study.open(out).cases
    broken = cases[1]
    old, new = BREAKAGES[kind]
    text = (broken.path / "in.liggghts").read_text()
    assert old in text
    (broken.path / "in.liggghts").write_text(text.replace(old, new))
    outcome = run_ensemble(out, list(cases), 2, 1, EngineConfig.from_site())
    assert outcome[broken.path.name] == "failed"
    m = broken.manifest()
    assert m.status == "failed" and m.reason.startswith("ERROR")
    for c in cases:
        if c != broken:
            m = c.manifest()
            assert m.status == "done", (c.case_id, m.reason)
            assert m.steps_done == m.total_steps
    launches = sorted(p.name for p in (out / ".ensemble").iterdir())
    if kind == "abort":  # the members killed by the abort were finished by a new mpirun
        assert len(launches) >= 2, launches


def test_resume_input_reissues_every_fix_of_the_drum_input(tmp_path):
    out = tmp_path / "study"
    r = ligwf("render", str(WORKFLOW), "--out", str(out), "--set", "sweep.rules=[weber]")
    assert r.returncode == 0, r.stderr
    case = Study.open(out).case(0)
    s = case.scaled
    drum = (case.path / "in.liggghts").read_text().splitlines()
    # (the skin depends on the phase resumed: tests/scene/test_neighbour.py)
    keep = ("fix ", "compute ", "region ", "thermo", "pair_style", "pair_coeff", "timestep",
            "neigh_modify", "dump", "restart ")
    wanted = [line for line in drum if line.startswith(keep)
              and not line.startswith(("fix ins", "region domain"))]
    for step, phase in [(1, "fill"), (s.insertion_steps + 1, "settle"),
                        (s.insertion_steps + s.numerics.settle_steps + 1, "production")]:
        text = render_resume(s, RestartFile("restart/restart_a.liggghts", step))[
            "resume.in.liggghts"]
        lines = text.splitlines()
        missing = [w for w in wanted if w not in lines]
        assert not missing, (phase, missing)
        assert lines[-1] == f"run {s.total_steps} upto"
