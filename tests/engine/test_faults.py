"""Fault injection on the real engine (84-particle case, one rank): kill -9 of ligwf, of
LIGGGHTS, of both, at chosen phases and several times in a row; two runners on one study;
a full disk; a read-only study. docs/reliability.md ("Faults during a run") says what each
test holds ligwf to.

Every scenario checks that no engine ever runs without its runner for long, that two
engines never write one case, and that the case ends ``done`` with a complete record.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import meshio
import pytest

from ligwf.engine.thermo import rows_from_csv
from ligwf.study.manifest import read_manifest

from helpers import ROOT  # noqa: E402

WORKFLOW = ROOT / "tests" / "workflows" / "runner_tiny.yaml"
# longer settling and production than the runner tests, so each phase can be hit on purpose
LONGER = ["--set", "sweep.rules=[weber]", "--set", "scene.process.settle_time=0.2",
          "--set", "scene.process.run_time=0.5"]
CASE = "cg3-weber-r0"
pytestmark = [pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]


def ligwf_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "ligwf.cli.main", *args]


def start(out: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(ligwf_cmd("run", str(WORKFLOW), "--out", str(out), *extra),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)


def run(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run(ligwf_cmd(*args), capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)


def engines_in(folder: Path, names=("liggghts", "mpirun", "orterun")) -> list[int]:
    """Pids of engine processes whose working folder is ``folder`` (from /proc)."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            comm = Path(f"/proc/{entry}/comm").read_text().strip()
            cwd = Path(os.readlink(f"/proc/{entry}/cwd"))
            state = Path(f"/proc/{entry}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if comm in names and cwd == folder.resolve() and state != "Z":
            found.append(int(entry))
    return found


class EngineWatch:
    """Samples /proc every 50 ms: the most LIGGGHTS ranks ever running in the case."""

    def __init__(self, folder: Path) -> None:
        self.folder, self.most, self._stop = folder, 0, threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)

    def _loop(self) -> None:
        while not self._stop.wait(0.05):
            self.most = max(self.most, len(engines_in(self.folder, ("liggghts",))))

    def __enter__(self) -> "EngineWatch":
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()


def screen_has(case: Path, text: str, attempt: int = 1) -> bool:
    """Whether attempt number ``attempt`` has begun and its screen shows ``text``."""
    m = read_manifest(case)
    if m is None or len(m.attempts) < attempt:
        return False
    try:
        return text in (case / "run.log").read_text(errors="replace")
    except FileNotFoundError:
        return False


def wait_for(pred, timeout: float = 120.0, what: str = "") -> None:
    t0 = time.monotonic()
    while not pred():
        assert time.monotonic() - t0 < timeout, f"timed out waiting for {what}"
        time.sleep(0.05)


def no_engine_left(case: Path, within: float = 15.0) -> None:
    wait_for(lambda: not engines_in(case), within, f"the engines of {case} to end")


def kill(proc: subprocess.Popen, case: Path, who: str) -> None:
    """SIGKILL ligwf, the engine ranks, or both at once."""
    ranks = engines_in(case, ("liggghts",))
    if who in ("ligwf", "both"):
        os.kill(proc.pid, signal.SIGKILL)
    if who in ("engine", "both"):
        assert ranks, "no engine to kill"
        for pid in ranks:
            os.kill(pid, signal.SIGKILL)
    proc.wait(timeout=60)


def assert_complete(case: Path, reference: Path) -> None:
    """done, exact particle count, thermo without gap or duplicate, the reference run's
    dumps, wall time and steps the sums over the attempts."""
    m = read_manifest(case)
    assert m.status == "done", (m.status, m.reason)
    assert m.steps_done == m.total_steps and m.atoms_end == m.atoms_after_settle == 84
    steps = [r.step for r in rows_from_csv((case / "thermo.csv").read_text())]
    every = _thermo_every(reference)
    assert steps[0] == 0 and steps[-1] == m.total_steps
    gaps = [(a, b) for a, b in zip(steps, steps[1:]) if not 0 < b - a <= every]
    assert not gaps, f"thermo gaps or duplicates: {gaps[:5]}"
    dumps = sorted(p.name for p in (case / "post").glob("*.vtu"))
    assert dumps == sorted(p.name for p in (reference / "post").glob("*.vtu"))
    for name in dumps:
        if name.startswith("particles_"):
            assert len(meshio.read(case / "post" / name).points) == 84, name
    assert m.wall_seconds == pytest.approx(sum(a.wall_seconds for a in m.attempts))
    assert m.core_seconds == pytest.approx(sum(a.wall_seconds * a.nprocs for a in m.attempts))
    assert sum(p["steps"] for p in m.phases.values()) == sum(a.steps for a in m.attempts)
    assert all(a.wall_seconds > 0 for a in m.attempts)
    # each attempt starts at or before the step the previous one reached: no step skipped
    reached = 0
    for a in m.attempts:
        assert a.from_step <= reached, (a.number, a.from_step, reached)
        reached = max(reached, a.from_step + a.steps)
    assert reached == m.total_steps


def _thermo_every(case: Path) -> int:
    return int(json.loads((case / "scene.json").read_text())["scaled"]["thermo_every"])


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    """The same case run without interruption."""
    out = tmp_path_factory.mktemp("reference")
    r = run("run", str(WORKFLOW), "--out", str(out), *LONGER)
    assert r.returncode == 0, r.stderr
    return out / CASE


def test_kills_of_ligwf_engine_and_both_in_every_phase(tmp_path, reference):
    out = tmp_path / "study"
    case = out / CASE
    t0 = time.monotonic()
    with EngineWatch(case) as watch:
        # 1. kill -9 ligwf in the fill (2nd wave); re-run AT ONCE, while the orphaned
        #    engine is still writing its forced restart: the new run must stop it first
        p = start(out, *LONGER)
        wait_for(lambda: screen_has(case, "ligwf-phase fill 2"), what="fill wave 2")
        kill(p, case, "ligwf")
        p = start(out, *LONGER)
        # 2. kill -9 LIGGGHTS only, in settling (after a periodic restart of settling)
        wait_for(lambda: screen_has(case, "ligwf-phase settle", 2)
                 and (case / "restart" / "restart_b.liggghts").exists(), what="settling")
        time.sleep(0.3)
        kill(p, case, "engine")
        assert p.returncode == 1, p.stderr.read()
        m = read_manifest(case)
        assert m.status == "killed" and "signal 9" in m.reason, m.reason
        no_engine_left(case)
        # 3. the re-run resumes from the newest restart of settling, not from step 0;
        #    kill -9 ligwf and LIGGGHTS together in production
        p = start(out, *LONGER)
        wait_for(lambda: screen_has(case, "ligwf-phase production", 3), what="production")
        time.sleep(0.5)
        kill(p, case, "both")
        no_engine_left(case)
        # 4. kill -9 ligwf alone in production, wait for its engine to die with it
        p = start(out, *LONGER)
        wait_for(lambda: screen_has(case, "ligwf-phase production", 4)
                 and engines_in(case, ("liggghts",)), what="production again")
        time.sleep(0.5)
        kill(p, case, "ligwf")
        no_engine_left(case)       # the watchdog stops the engine (forced restart)
        # 5. and the last run finishes the case
        r = run("run", str(WORKFLOW), "--out", str(out), *LONGER)
        assert r.returncode == 0, r.stdout + r.stderr
    assert watch.most == 1, f"{watch.most} engines wrote {case} at once"
    assert not engines_in(case)
    m = read_manifest(case)
    assert len(m.attempts) == 5, [(a.status, a.from_step) for a in m.attempts]
    resumed_in_settle = m.attempts[2]
    assert resumed_in_settle.from_restart.startswith("restart/restart_")
    settle_start = read_manifest(reference).phases["fill"]["steps"]
    assert resumed_in_settle.from_step >= settle_start - 5, resumed_in_settle
    assert_complete(case, reference)
    print(f"\nkill sequence: {time.monotonic() - t0:.1f} s")


def test_two_runners_split_the_cases_and_both_exit_0(tmp_path):
    out = tmp_path / "study"
    args = ["run", str(WORKFLOW), "--out", str(out)]
    procs = [subprocess.Popen(ligwf_cmd(*args), stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    codes = [p.wait(timeout=300) for p in procs]
    assert codes == [0, 0], [p.stderr.read() for p in procs]
    for case in ("cg3-weber-r0", "cg3-bond-r0"):
        m = read_manifest(out / case)
        assert m.status == "done" and len(m.attempts) == 1, (case, m.attempts)
    assert not list(out.rglob("*.tmp"))


@contextmanager
def tmpfs(path: Path, size: str):
    path.mkdir(parents=True, exist_ok=True)
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
                   check=True)
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=False)


def one_line_error(r: subprocess.CompletedProcess, folder: Path) -> None:
    assert r.returncode == 2, (r.returncode, r.stdout[-2000:], r.stderr)
    assert "Traceback" not in r.stderr + r.stdout, r.stderr
    lines = [x for x in r.stderr.splitlines() if x.strip() and "ligwf: warning:" not in x]
    assert len(lines) == 1 and str(folder) in lines[0], r.stderr


def test_disk_full_ends_in_one_line_and_a_manifest_that_says_so(tmp_path):
    with tmpfs(tmp_path / "disk", "4m") as disk:
        out = disk / "study"
        r = run("render", str(WORKFLOW), "--out", str(out), *LONGER)
        assert r.returncode == 0, r.stderr
        used = int(subprocess.run(["du", "-sk", str(disk)], capture_output=True,
                                  text=True).stdout.split()[0])
        # room for the rewrite of the inputs (the mesh is replaced atomically) and the
        # first dumps only
        mesh = (out / CASE / "drum.stl").stat().st_size // 1024
        subprocess.run(["mount", "-o", f"remount,size={used + mesh + 200}k", str(disk)],
                       check=True)
        r = run("run", str(WORKFLOW), "--out", str(out), *LONGER)
        one_line_error(r, out / CASE)
        assert "disk full" in r.stderr or "No space" in r.stderr
        m = read_manifest(out / CASE)
        assert m is not None and m.status == "killed" and m.reason.startswith("disk full"), m
        assert not engines_in(out / CASE)
        # with room again the case resumes and finishes
        subprocess.run(["mount", "-o", "remount,size=64m", str(disk)], check=True)
        r = run("run", str(WORKFLOW), "--out", str(out), *LONGER)
        assert r.returncode == 0, r.stdout[-3000:] + r.stderr
        assert read_manifest(out / CASE).status == "done"


def test_read_only_study_ends_in_one_line_per_command(tmp_path):
    with tmpfs(tmp_path / "ro", "64m") as disk:
        out = disk / "study"
        args = ["run", str(WORKFLOW), "--out", str(out), "--set", "sweep.rules=[weber]"]
        r = run(*args)
        assert r.returncode == 0, r.stderr
        subprocess.run(["mount", "-o", "remount,ro", str(disk)], check=True)
        (out / CASE / "manifest.json").read_text()
        one_line_error(run("render", *args[1:]), out)
        one_line_error(run("run", *args[1:], "--set", "scene.process.run_time=0.2"), out)
        for cmd in (["analyse", str(out)], ["report", str(out), "--no-snapshots"]):
            r = run(*cmd)
            one_line_error(r, out)
