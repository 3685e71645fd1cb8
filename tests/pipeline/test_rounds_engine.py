"""Sequential studies on the real engine (tests/workflows/rounds_tiny.yaml: a CG1 bed of
~490 particles and its We-CG1.5 twin of ~140, two seeds each, seconds a run).

* A production extension (``ligwf run --extend-production``, the user's path to the
  rounds' extension record) continues a done case from its own restart: one manifest (two
  attempts, the second from a restart), one thermo table without gap or repeat up to the
  new end, the frames of the new production beside the old ones, the scene hash as
  rendered, the case usable.
* ``ligwf study --until-decided`` killed with SIGKILL while a round runs, then the same
  command again: the looks are numbered once each, every case ends done with a whole
  record, and the study stops with a stated reason.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ligwf.study.case import CaseFolder
from ligwf.study.manifest import read_manifest
from ligwf.study.rounds import read_rounds
from ligwf.study.thermo_table import rows_from_csv

from helpers import ROOT

WORKFLOW = ROOT / "tests" / "workflows" / "rounds_tiny.yaml"
pytestmark = [pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]


def ligwf_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "ligwf.cli.main", *args]


def whole_record(case_dir: Path) -> None:
    """done up to its (extended) end, thermo without gap or repeat, one frame per dump
    step of the production, usable by the analysis."""
    case = CaseFolder.open(case_dir)
    m = read_manifest(case_dir)
    assert m.status == "done", (m.status, m.reason)
    assert m.steps_done == case.scaled.total_steps == m.total_steps
    steps = [r.step for r in rows_from_csv((case_dir / "thermo.csv").read_text())]
    every = case.scaled.numerics.thermo_every
    assert steps[0] == 0 and steps[-1] == m.total_steps
    assert not [(a, b) for a, b in zip(steps, steps[1:]) if not 0 < b - a <= every]
    frames = sorted(int(p.stem.split("_")[1]) for p in (case_dir / "post").glob("particles_*.vtu"))
    assert frames == case.expected_dump_steps(m.total_steps)
    assert case.why_not_usable() is None


def test_an_extension_continues_the_done_case_from_its_restart(tmp_path, engine):
    out = tmp_path / "s"
    r = subprocess.run(ligwf_cmd("run", str(WORKFLOW), "--out", str(out), "--set",
                                 "sweep.cg_levels=[1.5]", "--set", "sweep.replicas=1"),
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    case_dir = out / "cg1.5-weber-r0"
    before = CaseFolder.open(case_dir)
    first = read_manifest(case_dir)
    more = math.ceil(0.1 / before.scaled.numerics.dt)
    # the user's path (the fix the verdict names for runs too short): the same command
    # with --extend-production writes the extension record and continues the done case
    r = subprocess.run(ligwf_cmd("run", str(WORKFLOW), "--out", str(out), "--set",
                                 "sweep.cg_levels=[1.5]", "--set", "sweep.replicas=1",
                                 "--extend-production", "0.1"),
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert "cg1.5-weber-r0: production 0.1 s longer than rendered" in r.stdout
    after = CaseFolder.open(case_dir)
    m = read_manifest(case_dir)
    assert after.scene_hash == before.scene_hash == m.scene_hash
    assert len(m.attempts) == 2 and m.attempts[1].from_restart is not None
    assert 0 < m.attempts[1].from_step <= first.steps_done
    assert m.attempts[1].input == "resume.in.liggghts"
    whole_record(case_dir)
    assert m.total_steps == first.total_steps + more


def test_until_decided_survives_kill_9_and_ends_with_a_reason(tmp_path, engine):
    out = tmp_path / "s"
    cmd = ligwf_cmd("study", str(WORKFLOW), "--out", str(out), "--until-decided",
                    "--max-looks", "2", "--no-snapshots")
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         start_new_session=True)
    deadline = time.monotonic() + 900
    # kill -9 ligwf while the first round's engines run (a case running, past its fill)
    while time.monotonic() < deadline:
        running = [d for d in out.glob("cg*") if (d / "manifest.json").is_file()
                   and (m := read_manifest(d)) is not None and m.status == "running"]
        if any("ligwf-phase settle" in (d / "run.log").read_text(errors="replace")
               for d in running if (d / "run.log").is_file()):
            break
        assert p.poll() is None, "the study ended before it could be killed"
        time.sleep(0.2)
    os.killpg(p.pid, signal.SIGKILL)        # ligwf, mpirun and the ranks: the whole group
    p.wait(timeout=60)
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=1800)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    rounds = read_rounds(out)
    assert [x.number for x in rounds.looks] == list(range(1, len(rounds.looks) + 1))
    assert rounds.stopped and rounds.looks[-1].stop
    assert all(x.alpha == pytest.approx(0.05 / 2) for x in rounds.looks)
    for d in sorted(out.glob("cg*")):
        whole_record(d)
    assert "look 1" in r.stdout and (out / "report" / "figures" / "rounds.png").is_file()
    # the same command on the stopped study: nothing runs again, the answer is printed
    again = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    assert again.returncode == 0 and read_rounds(out) == rounds
