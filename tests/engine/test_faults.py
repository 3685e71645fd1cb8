"""Fault injection on the real engine (84-particle cases). On one case alone under mpirun:
kill -9 of ligwf, of LIGGGHTS, of both, at chosen phases and several times in a row; two
runners on one study; a full disk; a read-only study. On the DEFAULT path, the rank
planner's MPI ensemble of two replicas side by side (no --np): kill -9 of ligwf, of one
rank, of mpirun, SIGINT and SIGTERM of ligwf, each at fill, settle and production; a full
disk; another replica's restart dropped in. docs/reliability.md ("Faults during a run")
says what each test holds ligwf to.

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

from ligwf.study.manifest import read_manifest
from ligwf.study.thermo_table import rows_from_csv

from helpers import ROOT  # noqa: E402

WORKFLOW = ROOT / "tests" / "workflows" / "runner_tiny.yaml"
# longer settling and production than the runner tests, so each phase can be hit on purpose
# production long enough that a kill 0.5 s into it lands well before its end on a fast
# machine too: at 0.5 s of simulated time a CI runner finished the last 3,900 steps between
# the kill of ligwf and its watchdog, and the case ended one attempt early
LONGER = ["--set", "sweep.rules=[weber]", "--set", "scene.process.settle_time=0.2",
          "--set", "scene.process.run_time=2.0"]
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


RANKS = ("liggghts", "ligwf-ensemble")   # a local rank, an MPI-ensemble rank


def engines_in(folder: Path, names=RANKS + ("mpirun", "orterun")) -> list[int]:
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
            self.most = max(self.most, len(engines_in(self.folder, RANKS)))

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


# --------------------------------------------------------------------------------------
# The default path: the planner runs the two single-rank replicas as ONE MPI ensemble
# --------------------------------------------------------------------------------------

#: two replicas of one case (different insertion seeds) on 2 cores: the rank plan puts
#: them side by side in one mpirun -np 2 ensemble (no --np / --ensemble given)
#: phases long enough that a relaunched attempt is still in the next phase when the test
#: looks (with 0.3 / 0.6 s, a quiet machine ran a relaunch past settle and production
#: between two looks, and the mpirun campaign failed in a clean-clone CI run)
PAIR_ARGS = ["--cores", "2", "--set", "sweep.rules=[weber]", "--set", "sweep.replicas=2",
             "--set", "scene.process.settle_time=0.8", "--set", "scene.process.run_time=1.2"]
PAIR = ("cg3-weber-r0", "cg3-weber-r1")
PHASES = ("ligwf-phase fill 2", "ligwf-phase settle", "ligwf-phase production")
#: what ends a ligwf run (the test starts it again); the others it survives by itself
ENDS_LIGWF = {"ligwf": -signal.SIGKILL, "sigint": 130, "sigterm": 143}


def start_pair(out: Path) -> subprocess.Popen:
    return subprocess.Popen(ligwf_cmd("run", str(WORKFLOW), "--out", str(out), *PAIR_ARGS),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)


def attempts(case: Path) -> int:
    m = read_manifest(case)
    return len(m.attempts) if m is not None else 0


def in_phase(case: Path, marker: str, after: int) -> bool:
    """An attempt after the first ``after`` runs, its screen shows ``marker`` and its rank
    is up."""
    return (attempts(case) > after and screen_has(case, marker, after + 1)
            and bool(engines_in(case, ("ligwf-ensemble",))))


def mpirun_of(proc: subprocess.Popen) -> int:
    from ligwf.engine.guard import descendants
    from ligwf.study.processes import process
    found = [p for p in descendants(proc.pid) if (q := process(p)) and q.name == "mpirun"]
    assert found, "no mpirun below ligwf"
    return found[0]


class PairWatch(EngineWatch):
    """The most ranks ever running in either case folder at once."""

    def __init__(self, folders: list[Path]) -> None:
        super().__init__(folders[0])
        self.folders = folders

    def _loop(self) -> None:
        while not self._stop.wait(0.05):
            self.most = max([self.most] + [len(engines_in(f, RANKS)) for f in self.folders])


def assert_pair_complete(cases: list[Path]) -> None:
    """Every case done with an exact count, a whole thermo table, every expected dump
    non-empty with 84 particles, costs summed over all attempts; and each replica's
    frames its own (they differ from the other replica's at every step)."""
    from ligwf.study.case import CaseFolder

    frames = {}
    for path in cases:
        case = CaseFolder.open(path)
        m = read_manifest(path)
        assert m.status == "done", (path.name, m.status, m.reason)
        assert m.steps_done == m.total_steps and m.atoms_end == m.atoms_after_settle == 84
        steps = [r.step for r in rows_from_csv((path / "thermo.csv").read_text())]
        every = case.scaled.numerics.thermo_every
        assert steps[0] == 0 and steps[-1] == m.total_steps
        gaps = [(a, b) for a, b in zip(steps, steps[1:]) if not 0 < b - a <= every]
        assert not gaps, f"{path.name}: thermo gaps or duplicates: {gaps[:5]}"
        expected = case.expected_dump_steps(m.total_steps)
        assert expected
        for step in expected:
            for kind in ("particles", "contacts"):
                f = path / "post" / f"{kind}_{step}.vtu"
                assert f.is_file() and f.stat().st_size > 0, f
            points = meshio.read(path / "post" / f"particles_{step}.vtu").points
            assert len(points) == 84, (path.name, step)
            frames.setdefault(step, []).append(points)
        assert not [p for p in (path / "post").iterdir() if p.stat().st_size == 0]
        assert m.wall_seconds == pytest.approx(sum(a.wall_seconds for a in m.attempts))
        assert m.core_seconds == pytest.approx(sum(a.wall_seconds * a.nprocs for a in m.attempts))
        assert sum(p["steps"] for p in m.phases.values()) == sum(a.steps for a in m.attempts)
        assert all(a.wall_seconds > 0 and a.ended for a in m.attempts), m.attempts
        reached = 0
        for a in m.attempts:
            assert a.from_step <= reached, (path.name, a.number, a.from_step, reached)
            reached = max(reached, a.from_step + a.steps)
        assert reached == m.total_steps
    both = {step: f for step, f in frames.items() if len(f) == 2}
    assert len(both) == len(frames), "the replicas wrote different frame steps"
    for step, (a, b) in both.items():
        assert abs(a - b).max() > 1e-6, f"the replicas' frames are identical at step {step}"


@pytest.mark.parametrize("fault", ["ligwf", "rank", "mpirun", "sigint", "sigterm"])
def test_fault_campaign_on_the_planned_ensemble(tmp_path, fault):
    """One fault kind, once in each phase (fill, settle, production) of the replica r0,
    on the default planned path; then every case done, nothing mixed, nothing missing."""
    out = tmp_path / "study"
    cases = [out / c for c in PAIR]
    victim = cases[0]
    t0 = time.monotonic()
    with PairWatch(cases) as watch:
        p = start_pair(out)
        hit = 0                 # attempts of the victim when it was last hit
        for marker in PHASES:
            wait_for(lambda: in_phase(victim, marker, hit) or p.poll() is not None,
                     timeout=180, what=f"{marker} in an attempt after number {hit}")
            assert p.poll() is None, f"ligwf ended before {marker}: {p.stderr.read()}"
            time.sleep(0.3)
            before = hit = attempts(victim)
            if fault == "ligwf":
                os.kill(p.pid, signal.SIGKILL)
            elif fault in ("sigint", "sigterm"):
                os.kill(p.pid, signal.SIGINT if fault == "sigint" else signal.SIGTERM)
            elif fault == "rank":
                ranks = engines_in(victim, ("ligwf-ensemble",))
                assert ranks, "no rank to kill"
                os.kill(ranks[0], signal.SIGKILL)
            else:
                os.kill(mpirun_of(p), signal.SIGKILL)
            if fault in ENDS_LIGWF:
                rc = p.wait(timeout=120)
                err = p.stderr.read()
                assert rc == ENDS_LIGWF[fault], (rc, err)
                for case in cases:
                    no_engine_left(case, within=30)
                if fault != "ligwf":
                    assert "interrupted by the user" in err, err
                    assert "Traceback" not in err, err
                    for case in cases:
                        m = read_manifest(case)
                        if case != victim and m.status == "done":
                            continue    # the other replica had finished before the signal
                        assert m.status == "killed", (case.name, m.status, m.reason)
                        assert m.reason.startswith("interrupted by the user"), m.reason
                        assert m.attempts[-1].ended and m.attempts[-1].wall_seconds > 0
                        assert not (out / "report").exists() and not (out / "analysis").exists()
                p = start_pair(out)
            else:
                # the supervisor settles the job and relaunches both from their restarts
                wait_for(lambda: attempts(victim) > before or p.poll() is not None,
                         timeout=120, what="the relaunch")
                m = read_manifest(victim)
                lost = m.attempts[before - 1]
                assert lost.status == "killed" and lost.wall_seconds > 0, lost
                assert "ensemble job ended" in lost.reason, lost.reason
        rc = p.wait(timeout=300)
        assert rc == 0, p.stderr.read()[-3000:]
        r = run("run", str(WORKFLOW), "--out", str(out), *PAIR_ARGS)   # nothing left to do
        assert r.returncode == 0, r.stderr
    assert watch.most == 1, f"{watch.most} engines wrote one case at once"
    for case in cases:
        assert not engines_in(case)
    assert_pair_complete(cases)
    m = read_manifest(victim)
    assert len(m.attempts) >= 4, [(a.status, a.from_step) for a in m.attempts]
    assert [a.status for a in m.attempts][-1] == "done"
    assert all(a.status == "killed" for a in m.attempts[:-1]), [a.status for a in m.attempts]
    # the production fault resumed from a restart of its own, not from step 0
    assert m.attempts[-1].from_restart and m.attempts[-1].from_step > 0
    assert list((out / ".ensemble").iterdir()), "the planned run used no ensemble"
    print(f"\n{fault} campaign: {time.monotonic() - t0:.1f} s")


def test_foreign_truncated_and_garbled_restarts_are_never_resumed(tmp_path):
    """Both replicas stopped in production (SIGTERM: forced restarts). Then the replica
    behind gets the other's newer forced restart (with its identity record) and the
    other's periodic restart over its own, and its own forced restart is cut in half; the
    other replica's own periodic restart is garbled (same size). The re-run resumes each
    from an older restart of its own, and nothing is mixed or missing."""
    from ligwf.engine.liggghts import restart_step
    from ligwf.study.layout import FORCED_RESTART_RE

    out = tmp_path / "study"
    cases = [out / c for c in PAIR]
    p = start_pair(out)
    wait_for(lambda: all(in_phase(c, "ligwf-phase production", 0) for c in cases)
             or p.poll() is not None, timeout=180, what="production in both")
    time.sleep(1.0)
    os.kill(p.pid, signal.SIGTERM)
    assert p.wait(timeout=120) == 143, p.stderr.read()

    def forced(case: Path) -> Path:
        found = sorted((f for f in case.iterdir() if FORCED_RESTART_RE.match(f.name)),
                       key=restart_step)
        assert found, f"no forced restart in {case.name}"
        return found[-1]

    progress = {c: read_manifest(c).steps_done for c in cases}
    victim, donor = sorted(cases, key=lambda c: progress[c])
    theirs, mine = forced(donor), forced(victim)
    if restart_step(theirs) != restart_step(mine):     # else: same name, mine is replaced
        (victim / (theirs.name + ".id.json")).write_bytes(
            (donor / (theirs.name + ".id.json")).read_bytes())
    (victim / theirs.name).write_bytes(theirs.read_bytes())
    if restart_step(theirs) != restart_step(mine):
        data = mine.read_bytes()
        mine.write_bytes(data[: len(data) // 2])       # truncated
    periodic = {c: sorted((c / "restart").glob("restart_?.liggghts"), key=restart_step)
                for c in cases}
    (victim / "restart" / periodic[donor][-1].name).write_bytes(periodic[donor][-1].read_bytes())
    garbled = periodic[donor][0]
    data = bytearray(garbled.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 64] = bytes(64)
    garbled.write_bytes(bytes(data))
    before = {c: attempts(c) for c in cases}

    r = run("run", str(WORKFLOW), "--out", str(out), *PAIR_ARGS, timeout=300)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr
    for case in cases:
        resumed = read_manifest(case).attempts[before[case]]
        assert resumed.from_step <= progress[case], (case.name, resumed.from_step)
        assert resumed.from_restart not in (None, ), f"{case.name} re-ran from step 0"
        if case == victim:
            # not the other's forced restart, not its own cut one, not the other's periodic
            assert resumed.from_restart != theirs.name and resumed.from_restart != mine.name
            assert resumed.from_restart != f"restart/{periodic[donor][-1].name}"
        else:
            assert resumed.from_restart != f"restart/{garbled.name}"
    assert_pair_complete(cases)
    for case in cases:
        assert not engines_in(case)


def test_disk_full_in_the_planned_ensemble_then_resumed_whole(tmp_path):
    """A disk that fills while both replicas run side by side: one line, exit 2, no case
    left 'running', no engine left; with room again both end done with no thermo gap and
    no empty frame."""
    with tmpfs(tmp_path / "disk", "8m") as disk:
        out = disk / "study"
        r = run("render", str(WORKFLOW), "--out", str(out), *PAIR_ARGS[2:])
        assert r.returncode == 0, r.stderr
        used = int(subprocess.run(["du", "-sk", str(disk)], capture_output=True,
                                  text=True).stdout.split()[0])
        mesh = (out / PAIR[0] / "drum.stl").stat().st_size // 1024
        subprocess.run(["mount", "-o", f"remount,size={used + 2 * mesh + 400}k", str(disk)],
                       check=True)
        r = run("run", str(WORKFLOW), "--out", str(out), *PAIR_ARGS)
        one_line_error(r, out)
        assert "disk full" in r.stderr or "No space" in r.stderr, r.stderr
        cases = [out / c for c in PAIR]
        for case in cases:
            m = read_manifest(case)
            assert m is not None and m.status != "running", (case.name, m and m.reason)
            assert m.status != "done" or m.steps_done == m.total_steps
            assert not engines_in(case)
        assert any(read_manifest(c).reason.startswith("disk full") for c in cases)
        subprocess.run(["mount", "-o", "remount,size=64m", str(disk)], check=True)
        r = run("run", str(WORKFLOW), "--out", str(out), *PAIR_ARGS)
        assert r.returncode == 0, r.stdout[-3000:] + r.stderr
        assert_pair_complete(cases)


def test_ctrl_c_of_ligwf_study_stops_before_the_analysis(tmp_path):
    """`ligwf study` interrupted in production: forced restarts, both cases killed
    'interrupted by the user', no analysis and no report, exit 130; `ligwf run` then
    finishes both from their own restarts."""
    from ligwf.study.layout import FORCED_RESTART_RE

    out = tmp_path / "study"
    cases = [out / c for c in PAIR]
    p = subprocess.Popen(ligwf_cmd("study", str(WORKFLOW), "--out", str(out), "--no-snapshots",
                                   *PAIR_ARGS),
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    wait_for(lambda: all(in_phase(c, "ligwf-phase production", 0) for c in cases)
             or p.poll() is not None, timeout=180, what="production in both")
    os.kill(p.pid, signal.SIGINT)
    assert p.wait(timeout=120) == 130
    err = p.stderr.read()
    assert "Interrupted: interrupted by the user (SIGINT)" in err and "Traceback" not in err
    assert not (out / "analysis").exists() and not (out / "report").exists()
    for case in cases:
        m = read_manifest(case)
        assert m.status == "killed" and m.reason.startswith("interrupted by the user (SIGINT)")
        assert any(FORCED_RESTART_RE.match(f.name) for f in case.iterdir()), case.name
        assert not engines_in(case)
    r = run("run", str(WORKFLOW), "--out", str(out), *PAIR_ARGS)
    assert r.returncode == 0, r.stderr
    assert_pair_complete(cases)


def test_sigterm_in_the_last_fill_wave_resumes_from_its_forced_restart(tmp_path):
    """A forced restart written after the top-up insertion of the last fill wave: the
    resume input trims the extra particles after a 'run 0' (LIGGGHTS refuses delete_atoms
    straight after read_restart), so both replicas resume from it and finish."""
    out = tmp_path / "study"
    cases = [out / c for c in PAIR]
    p = start_pair(out)
    wait_for(lambda: all(in_phase(c, "ligwf-phase fill 3", 0) for c in cases)
             or p.poll() is not None, timeout=180, what="the last fill wave in both")
    os.kill(p.pid, signal.SIGTERM)
    assert p.wait(timeout=120) == 143, p.stderr.read()
    from_steps = {c: read_manifest(c).steps_done for c in cases}
    r = run("run", str(WORKFLOW), "--out", str(out), *PAIR_ARGS)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr
    for case in cases:
        resumed = read_manifest(case).attempts[1]
        if read_manifest(case).attempts[0].status == "killed" and resumed.from_restart:
            assert resumed.status == "done" and resumed.from_step <= from_steps[case]
    assert any(read_manifest(c).attempts[1].from_restart for c in cases), \
        [read_manifest(c).attempts for c in cases]
    assert_pair_complete(cases)


def test_ligwf_cancel_stops_a_planned_ensemble_run_in_another_process(tmp_path):
    """`ligwf status` names the runner that holds the cases, `ligwf cancel` (the local
    executor's cancel) sends it SIGTERM: forced restarts, both ensemble members killed
    'interrupted by the user (SIGTERM)', the runner exits 143; `ligwf run` then finishes
    both from their own restarts, and a second cancel finds nothing to stop."""
    from ligwf.study.layout import FORCED_RESTART_RE

    out = tmp_path / "study"
    cases = [out / c for c in PAIR]
    # a production long enough to outlast two ligwf start-ups (status, cancel) on quiet cores
    args = [*PAIR_ARGS, "--set", "scene.process.run_time=4.0"]
    p = subprocess.Popen(ligwf_cmd("run", str(WORKFLOW), "--out", str(out), *args),
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    wait_for(lambda: all(in_phase(c, "ligwf-phase production", 0) for c in cases)
             or p.poll() is not None, timeout=180, what="production in both")
    status = run("status", str(out))
    assert f"running in ligwf process {p.pid}@" in status.stdout, status.stdout
    r = run("cancel", str(out))
    assert r.returncode == 0 and f"sent SIGTERM to the ligwf runner(s) {p.pid}@" in r.stdout, \
        r.stdout + r.stderr
    assert p.wait(timeout=120) == 143, p.stderr.read()
    for case in cases:
        m = read_manifest(case)
        assert m.status == "killed" and m.reason.startswith("interrupted by the user (SIGTERM)")
        assert m.stop == "interrupted"
        assert any(FORCED_RESTART_RE.match(f.name) for f in case.iterdir()), case.name
        assert not engines_in(case)
    again = run("cancel", str(out))
    assert again.returncode == 0 and "no live ligwf runner" in again.stdout
    r = run("run", str(WORKFLOW), "--out", str(out), *args)
    assert r.returncode == 0, r.stderr
    assert_pair_complete(cases)
