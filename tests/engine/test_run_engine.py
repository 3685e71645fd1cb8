"""`ligwf run` / `run-case` / `status` on the real engine with tiny scenes (84 particles)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import meshio
import pytest

from ligwf.study.manifest import effective_status, read_manifest
from ligwf.engine.liggghts import restart_step
from ligwf.engine.guard import live_engines
from ligwf.engine.resume import restart_files

from helpers import ROOT  # noqa: E402

WORKFLOW = ROOT / "tests" / "workflows" / "runner_tiny.yaml"
ONE_CASE = ["--set", "sweep.rules=[weber]"]
LONGER = ["--set", "scene.process.run_time=1.0"]
pytestmark = [pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]


def ligwf(*args: str, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ligwf.cli.main", *args], capture_output=True,
                          text=True, timeout=600, **kw)


def start_run(out: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "ligwf.cli.main", "run", str(WORKFLOW), "--out",
                             str(out), *ONE_CASE, *extra], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)


def wait_for(pred, timeout: float = 120.0) -> None:
    t0 = time.monotonic()
    while not pred():
        assert time.monotonic() - t0 < timeout, "timed out waiting for the engine"
        time.sleep(0.1)


def test_two_cases_np2_end_to_end_then_skipped(tmp_path):
    out = tmp_path / "study"
    r = ligwf("run", str(WORKFLOW), "--out", str(out), "--np", "2")
    assert r.returncode == 0, r.stdout + r.stderr
    dirs = sorted(p for p in out.iterdir() if (p / "scene.json").exists())
    assert len(dirs) == 2
    for d in dirs:
        m = read_manifest(d)
        assert m.status == "done", m.reason
        assert m.steps_done == m.total_steps > 0
        assert m.atoms_end == m.atoms_after_settle == 84 and m.atoms_start == 0
        assert m.nprocs == 2 and m.core_seconds == pytest.approx(2 * m.wall_seconds)
        assert "-np" in m.command and "2" in m.command
        assert m.liggghts_version.startswith("LIGGGHTS Version LIGGGHTS-PUBLIC 3.8.0")
        assert m.liggghts_executable == m.command[m.command.index("-in") - 1]
        assert Path(m.liggghts_library).name.startswith("libliggghts")
        assert m.scene_hash == json.loads((d / "scene.json").read_text())["scene_hash"]
        assert set(m.phases) == {"fill", "settle", "production"}
        assert all(p["wall_seconds"] > 0 and p["core_seconds"] == pytest.approx(
            2 * p["wall_seconds"]) for p in m.phases.values())
        assert (d / "thermo.csv").read_text().splitlines()[-1].startswith(str(m.total_steps))
        vtus = sorted((d / "post").glob("particles_*.vtu"))
        assert vtus
        mesh = meshio.read(vtus[-1])
        assert len(mesh.points) == 84 and "radius" in mesh.point_data
    status = ligwf("status", str(out))
    assert status.returncode == 0 and status.stdout.count("done") >= 2
    # the same command again: nothing to do, manifests untouched
    before = [(d / "manifest.json").read_text() for d in dirs]
    t0 = time.monotonic()
    r = ligwf("run", str(WORKFLOW), "--out", str(out), "--np", "2")
    assert r.returncode == 0
    assert [(d / "manifest.json").read_text() for d in dirs] == before
    assert time.monotonic() - t0 < 30


def test_sigterm_then_resume_from_forced_restart(tmp_path):
    out = tmp_path / "study"
    case = out / "cg3-weber-r0"
    # a production of ~2 s, so the signal lands inside it (0.1 s can be over before)
    proc = start_run(out, *LONGER)
    wait_for(lambda: "ligwf-phase production" in _read(case / "run.log"))
    os.kill(proc.pid, signal.SIGTERM)          # ligwf forwards it to the engine ranks
    assert proc.wait(timeout=120) == 143       # 128 + SIGTERM, as a shell reports it
    m = read_manifest(case)
    assert m.status == "killed" and 0 < m.steps_done < m.total_steps
    assert m.reason.startswith("interrupted by the user (SIGTERM)"), m.reason
    forced = list(case.glob("restart_forced_liggghts_*.data"))
    assert len(forced) == 1 and restart_step(forced[0]) == m.steps_done
    r = ligwf("run", str(WORKFLOW), "--out", str(out), *ONE_CASE, *LONGER)
    assert r.returncode == 0, r.stdout + r.stderr
    m = read_manifest(case)
    assert m.status == "done" and m.steps_done == m.total_steps
    assert [a.status for a in m.attempts] == ["killed", "done"]
    assert m.attempts[1].from_restart == forced[0].name
    assert m.attempts[1].from_step == restart_step(forced[0])
    assert (case / "run.1.log").exists()


def test_sigkill_then_resume_from_periodic_restart(tmp_path):
    out = tmp_path / "study"
    case = out / "cg3-weber-r0"
    proc = start_run(out)
    wait_for(lambda: (case / "restart" / "restart_b.liggghts").exists())
    engines = live_engines(case)               # ligwf, mpirun and the engine, no warning
    os.killpg(proc.pid, signal.SIGKILL)
    for p in engines:
        os.kill(p.pid, signal.SIGKILL)
    proc.wait(timeout=30)
    m = read_manifest(case)                    # complete JSON although killed mid-run
    assert m.status == "running" and effective_status(m) == "killed"
    assert not list(case.glob("restart_forced_*"))
    periodic = restart_files(case)
    assert periodic and all(r.path.startswith("restart/") for r in periodic)
    r = ligwf("run", str(WORKFLOW), "--out", str(out), *ONE_CASE)
    assert r.returncode == 0, r.stdout + r.stderr
    m = read_manifest(case)
    assert m.status == "done" and m.steps_done == m.total_steps
    assert m.attempts[-1].from_restart.startswith("restart/restart_")
    assert m.attempts[-1].from_step >= periodic[-1].step


def _read(path: Path) -> str:
    try:
        return path.read_text(errors="replace")
    except FileNotFoundError:
        return ""


def _broken_case(tmp_path, edit) -> Path:
    out = tmp_path / "study"
    r = ligwf("render", str(WORKFLOW), "--out", str(out), *ONE_CASE)
    assert r.returncode == 0, r.stderr
    case = out / "cg3-weber-r0"
    text = (case / "in.liggghts").read_text()
    (case / "in.liggghts").write_text(edit(text))
    r = ligwf("run-case", str(out), "--index", "0", "--np", "1")
    assert r.returncode == 1
    return case


def test_typo_is_failed_with_its_error_line(tmp_path):
    case = _broken_case(tmp_path, lambda t: t.replace('print "ligwf-phase settle"',
                                                      'bogus_command 1\nprint "ligwf-phase settle"'))
    m = read_manifest(case)
    assert m.status == "failed" and m.reason.startswith("ERROR: Unknown command: bogus_command")
    assert m.attempts[-1].exit_code == 1


def test_atom_loss_with_exit_0_is_unstable(tmp_path):
    # a 20x larger time step: atoms leave the drum; the engine would exit 0
    def edit(text):
        line = next(x for x in text.splitlines() if x.startswith("timestep "))
        return text.replace(line, f"timestep {20 * float(line.split()[1])!r}")
    case = _broken_case(tmp_path, edit)
    m = read_manifest(case)
    assert m.status == "unstable"
    assert {i["kind"] for i in m.issues} & {"atom_loss", "lost_atoms", "nan", "ke_blowup"}


def test_nan_with_exit_0_is_unstable(tmp_path):
    # an infinite force (1e308*10) from the settling phase on: the thermo shows -nan and
    # LIGGGHTS exits 0
    case = _broken_case(tmp_path, lambda t: t.replace(
        'print "ligwf-phase settle"', 'variable big equal 1e308*10\n'
        'fix boom all addforce v_big 0.0 0.0\nprint "ligwf-phase settle"'))
    m = read_manifest(case)
    assert m.status == "unstable" and m.attempts[-1].exit_code == 0
    assert m.reason.startswith("nan:") and m.reason_step is not None
