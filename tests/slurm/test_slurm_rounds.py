"""A sequential study on a real one-node Slurm (``ligwf study --executor slurm
--until-decided``, i.e. ``ligwf slurm submit --until-decided``): each round a dependent
array whose follow-up job (``ligwf slurm next-round``) takes the look and submits the next
round.

The tiny rounds workflow (tests/workflows/rounds_tiny.yaml: a CG1 bed of ~490 particles and
its We-CG1.5 twin, two seeds each) with two looks: after the jobs end the rounds record has
its looks, each round's array ran exactly what its look added (new replicas, extended
cases), every continued case has one manifest and a thermo table without gap, the report
draws the rounds. Round 1's follow-up job is killed while it works and ``resubmit``
keeps the study going; the follow-up command run again (or ``resubmit``), by hand while
round 2 runs or after the stop, changes nothing.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ligwf.pipeline.submit_rounds import submitted_round
from ligwf.slurm.jobs import read_record, study_status
from ligwf.slurm.parse import task_records
from ligwf.study.case import CaseFolder
from ligwf.study.layout import FIGURE_ROUNDS, FIGURES_DIR
from ligwf.study.manifest import read_manifest
from ligwf.study.rounds import AddReplicas, ExtendProduction, read_rounds
from ligwf.study.study import Study
from ligwf.study.thermo_table import rows_from_csv

from helpers import ROOT

WORKFLOW = ROOT / "tests" / "workflows" / "rounds_tiny.yaml"
LIGWF = str(Path(sys.executable).parent / "ligwf")

pytestmark = [pytest.mark.slurm, pytest.mark.engine, pytest.mark.slow]


def ligwf(*args: str, env: dict[str, str]) -> subprocess.CompletedProcess:
    out = subprocess.run([LIGWF, *args], capture_output=True, text=True, env=env, timeout=600,
                         stdin=subprocess.DEVNULL)
    assert out.returncode == 0, f"ligwf {' '.join(args)} exited {out.returncode}:\n" \
                                f"{out.stdout}\n{out.stderr}"
    return out


def _logs(study: Path) -> str:
    parts = []
    for log in sorted((study / "slurm" / "logs").glob("*.out")):
        parts.append(f"--- {log.name} ---\n" + "\n".join(log.read_text().splitlines()[-25:]))
    return "\n".join(parts)


def wait_until_stopped(study: Path, timeout: float, on_stall=None) -> None:
    """Poll until the rounds record says stopped and no job of the study is queued. When
    nothing is queued for 20 s and the study has not stopped (a stall), ``on_stall`` is
    called once (a resubmit: what a user does then); a second stall fails."""
    deadline = time.monotonic() + timeout
    idle_since = None
    while time.monotonic() < deadline:
        st = study_status(study)
        busy = any(c.queued for c in st.cases) or any(j.get("active") for j in st.jobs)
        if not busy and read_rounds(study).stopped:
            return
        idle_since = None if busy else (idle_since or time.monotonic())
        if idle_since is not None and time.monotonic() - idle_since > 20:
            assert on_stall is not None, \
                f"{study}: nothing queued and the study has not stopped:\n{_logs(study)}"
            on_stall()
            on_stall, idle_since = None, None
        time.sleep(2.0)
    raise AssertionError(f"{study}: not stopped after {timeout:.0f} s:\n{_logs(study)}")


def job_state(study: Path, job_id: str) -> tuple[str | None, bool]:
    """Slurm's state of the study's follow-up job ``job_id`` and whether it is active."""
    job = [j for j in study_status(study).jobs if str(j["job_id"]) == job_id][0]
    return job.get("state"), bool(job.get("active"))


def wait_for(what, timeout: float, study: Path) -> None:
    deadline = time.monotonic() + timeout
    while not what():
        assert time.monotonic() < deadline, _logs(study)
        time.sleep(0.5)


def one_continuous_record(case_dir: Path) -> None:
    """done to its (extended) end with one manifest, thermo 0..end without gap or repeat,
    one frame per dump step, usable by the analysis."""
    case = CaseFolder.open(case_dir)
    m = read_manifest(case_dir)
    assert m.status == "done", (case_dir.name, m.status, m.reason)
    assert m.steps_done == case.scaled.total_steps == m.total_steps
    steps = [r.step for r in rows_from_csv((case_dir / "thermo.csv").read_text())]
    assert steps[0] == 0 and steps[-1] == m.total_steps
    assert not [(a, b) for a, b in zip(steps, steps[1:])
                if not 0 < b - a <= case.scaled.numerics.thermo_every]
    frames = sorted(int(p.stem.split("_")[1]) for p in (case_dir / "post").glob("particles_*.vtu"))
    assert frames == case.expected_dump_steps(m.total_steps)
    assert case.why_not_usable() is None


@pytest.fixture
def env(tmp_path):
    e = dict(os.environ, LIGWF_MESH_CACHE=str(tmp_path / "meshes"))
    e.pop("LIGWF_SLURM_PARTITION", None)
    return e


def test_until_decided_runs_each_round_as_a_dependent_array(slurm_cluster, tmp_path, env):
    t0 = time.monotonic()
    study = tmp_path / "s"
    # ligwf study --executor slurm is ligwf slurm submit (tests/slurm/test_slurm_integration.py
    # submits with the old spelling)
    ligwf("study", str(WORKFLOW), "--out", str(study), "--executor", "slurm", "--until-decided",
          "--max-looks", "2", "--ntasks", "1", "--time", "00:20:00", "--no-snapshots", env=env)
    first = read_record(study)
    assert [(s["kind"], s.get("study_round")) for s in first] == [("array", 1), ("analysis", 1)]
    assert first[0]["indices"] == [0, 1, 2, 3]
    assert first[1]["steps"] == ["slurm next-round --no-snapshots"]
    assert f"{LIGWF} slurm next-round --no-snapshots" in (study / first[1]["script"]).read_text()
    assert read_rounds(study).max_looks == 2 and not read_rounds(study).looks

    # round 1's follow-up job killed while it works (scancel: SIGTERM, at whatever point
    # of analysis, look or submission it is), then a resubmit: the study goes on from its
    # records (the look taken once, round 2 submitted once)
    follow1 = str(first[1]["job_id"])
    wait_for(lambda: job_state(study, follow1)[0] == "RUNNING", 900, study)
    time.sleep(3.0)
    subprocess.run(["scancel", follow1], check=True)
    wait_for(lambda: not job_state(study, follow1)[1], 120, study)
    ligwf("slurm", "resubmit", str(study), env=env)

    # while round 2 is queued or running, the follow-up command by hand and a resubmit: at
    # any point of it they may wait, take the due look themselves or leave it to the job,
    # but never look twice or submit anything twice (checked on the record at the end)
    deadline = time.monotonic() + 900
    while submitted_round(read_record(study)) < 2 and not read_rounds(study).stopped:
        assert time.monotonic() < deadline, _logs(study)
        time.sleep(1.0)
    ligwf("slurm", "next-round", str(study), "--no-snapshots", env=env)
    ligwf("slurm", "resubmit", str(study), env=env)

    wait_until_stopped(study, timeout=1200,
                       on_stall=lambda: ligwf("slurm", "resubmit", str(study), env=env))
    rounds = read_rounds(study)
    assert [x.number for x in rounds.looks] == [1, 2], _logs(study)   # look 1 went on
    assert rounds.stopped and rounds.looks[-1].stop and not rounds.looks[0].stop
    assert all(x.alpha == pytest.approx(0.05 / 2) for x in rounds.looks)

    # each round: one submission of its arrays, exactly the cases its look added (new
    # replicas by their folder, extended runs by their id); besides the killed one, at most
    # one follow-up job alone (the resubmit's, when the kill came before round 2's arrays)
    record = read_record(study)
    arrays = [s for s in record if s["kind"] == "array"]
    assert [s["study_round"] for s in arrays] == [1, 2]
    follow = [s for s in record if s["kind"] == "analysis"]
    assert all(s["steps"] == first[1]["steps"] for s in follow)
    assert len(follow) <= 3 and len([s for s in follow if s.get("study_round") is None]) <= 1
    ids = Study.open(study).case_ids
    ran = {r: sorted(ids[i] for s in record if s["kind"] == "array" and s["study_round"] == r
                     for i in s["indices"]) for r in (1, 2)}
    assert ran[1] == sorted(ids[:4])
    look1 = rounds.looks[0]
    extended = sorted(cid for a in look1.actions if isinstance(a, ExtendProduction)
                      for cid in a.case_ids)
    added = sorted(f"cg{a.condition.cg:g}-{a.condition.rule}-r{r}" for a in look1.actions
                   if isinstance(a, AddReplicas) for r in a.replicas)
    assert look1.actions and ran[2] == sorted(extended + added), (ran, look1.actions)
    assert len(ids) == 4 + len(added)

    for case_dir in sorted(study.glob("cg*")):
        one_continuous_record(case_dir)
    for cid in extended:              # continued from its own restart, one manifest
        m = read_manifest(study / cid)
        assert len(m.attempts) == 2 and m.attempts[1].from_step > 0, (cid, m.attempts)
    done = task_records(slurm_cluster.jobcomp.read_text())
    for s in record:                  # every task and job ended well but the killed one
        states = {r.state for r in done if s["job_id"] in (r.array_job_id, r.job_id)}
        assert states == ({"CANCELLED"} if s["job_id"] == follow1 else {"COMPLETED"}), \
            (s, states, _logs(study))
    assert (study / "report" / FIGURES_DIR / FIGURE_ROUNDS).is_file()
    assert "look 2" in (study / "report" / "summary.md").read_text()
    t1 = time.monotonic()

    # after the stop, again (by hand, or a resubmit): no look, no submission
    again = ligwf("slurm", "next-round", str(study), "--no-snapshots", env=env)
    assert "stopped at look 2" in again.stdout
    resub = ligwf("slurm", "resubmit", str(study), env=env)
    assert "stopped at look 2" in resub.stdout
    assert read_rounds(study) == rounds and read_record(study) == record
    print(f"\nslurm rounds: {t1 - t0:.0f} s to the stop, {time.monotonic() - t1:.0f} s again")
