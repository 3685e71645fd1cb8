"""Two nodes for real (issue 34), on the two-node Slurm of tests/slurm/two_node_cluster.py.

A case the rank plan puts on 2 ranks (spanning_drum.yaml: 6,085 particles), submitted with
``cores_per_node: 1``, asks for ``--nodes=2``; Slurm allocates both hosts and OpenMPI's
mpirun (the site launcher ``mpirun --display-map``, its TCP traffic kept on the cluster
network by the site's set-up lines) puts one engine rank on each: the launch map in the
engine's log says so, and each node's namespace holds one engine process that sees that
node's host name. ``ligwf slurm cancel`` then stops it on both nodes (the case is
``killed``, no engine process is left on either): the case's fill alone would cost minutes
on 2 cores, the map is what this test is after.

The tiny study's case cut short (~3,500 steps) on ``--ntasks 2``: one core a node, so one
rank on each host (the launch map again, and jobcomp's NodeList); it ends ``done`` with every
particle, and its thermo rows (less the engine's wall-clock column) and dumps are those of
the same case on 2 ranks of one machine (``ligwf run --np 2``, the same processor grid),
byte for byte. Under ``srun --mpi=pmix --kill-on-bad-exit=1`` the same case's remote rank
(the engine process inside node 2) is SIGKILLed in its production phase: the case ends
``killed`` with srun's signal as the reason (``ligwf slurm status``: FAILED), and
``ligwf slurm resubmit`` resumes it from its own restart to ``done``, every thermo step and
dump once.

The analysis across nodes: a tiny study run and analysed locally (two ~200-particle CG3
cases, as in test_analysis_array.py) is analysed again by ``ligwf analyse DIR --slurm 2``:
its two array tasks run one on each node, and the merged tables are the local ones, byte
for byte.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from ligwf.slurm.jobs import read_record
from ligwf.study.study import Study

from two_node_cluster import NODES, SUBNET, TwoNodeSlurm

HERE = Path(__file__).resolve().parent
SPANNING = HERE / "spanning_drum.yaml"
TINY = HERE / "tiny_drum.yaml"
#: the tiny study cut to one cheap case: ~3,500 steps of 222 CG3 particles (soft, long dt)
CHEAP = ["--set", "sweep.replicas=1", "--set", "scene.particles.youngs_modulus=5.0e+5",
         "--set", "scene.numerics.dt_rayleigh_fraction=0.18",
         "--set", "scene.numerics.dump_interval=0.01",
         "--set", "scene.numerics.restart_interval=0.01"]

SHORT = ["--set", "scene.process.settle_time=0.02", "--set", "scene.process.run_time=0.04"]

#: the killed case settles and turns longer: the engine's screen (what the runner reads) is
#: block-buffered and a SIGKILL loses its tail, so the kill waits until the screen shows the
#: production phase, and the run must go on well past that
LONG = ["--set", "scene.process.settle_time=0.1", "--set", "scene.process.run_time=0.6"]
PARTICLES = 222             # the tiny case's particles

TABLES = ("granules.parquet", "frames.csv", "gsd.csv", "gsd_summary.csv", "gsd_pooling.csv",
          "kinetics.csv", "kinetics_summary.csv", "sensitivity.csv", "flow.csv",
          "flow_profiles.json")
LIGWF = str(Path(sys.executable).parent / "ligwf")

pytestmark = [pytest.mark.slurm, pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]


def site_file(path: Path, launcher: str) -> Path:
    """A site file as a cluster user writes it: partition, cores per node, launcher, and
    OpenMPI's TCP traffic kept on the cluster network (here the veth's subnet). Ranks are
    not bound to cores: both nodes are this machine, so OpenMPI's default (each rank bound
    to the first core of its node) put both ranks on one physical core, where they took
    turns at every message (measured: 25 ms a step, the case 96 s instead of 1 s)."""
    setup = [*(f"export OMPI_MCA_{kind}_tcp_if_include={SUBNET}" for kind in ("btl", "oob")),
             "export OMPI_MCA_hwloc_base_binding_policy=none"]
    path.write_text("slurm:\n  partition: debug\n  cores_per_node: 1\n  time: \"00:40:00\"\n"
                    f"  launcher: {launcher}\n  setup: {json.dumps(setup)}\n")
    return path


def clean_env(**extra: str) -> dict[str, str]:
    """This environment without site overrides (LIGWF_SLURM_*, LIGWF_MPIRUN*)."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("LIGWF_SLURM_", "LIGWF_MPIRUN", "SLURM_"))}
    return dict(env, **extra)


def ligwf(cluster: TwoNodeSlurm, *args: str, env: dict[str, str], expect: int = 0,
          timeout: float = 900) -> subprocess.CompletedProcess:
    """``ligwf ARGS`` on node 1 (the cluster's addresses exist only in its namespaces)."""
    out = cluster.run([LIGWF, *args], env=env, timeout=timeout)
    assert out.returncode == expect, f"ligwf {' '.join(args)} exited {out.returncode}:\n" \
                                     f"{out.stdout}\n{out.stderr}"
    return out


def local_ligwf(*args: str, env: dict[str, str]) -> None:
    """``ligwf ARGS`` on this machine outside the cluster; must exit 0."""
    out = subprocess.run([LIGWF, *args], capture_output=True, text=True, env=env,
                         timeout=1800, stdin=subprocess.DEVNULL)
    assert out.returncode == 0, f"ligwf {' '.join(args)} exited {out.returncode}:\n" \
                                f"{out.stdout}\n{out.stderr}"


def jobcomp_nodes(cluster: TwoNodeSlurm, job_id: str) -> dict[int, str]:
    """Array task id -> NodeList of the finished tasks of ``job_id`` (the jobcomp file)."""
    nodes = {}
    for line in cluster.jobcomp.read_text().splitlines():
        fields = dict(f.split("=", 1) for f in line.split() if "=" in f)
        if fields.get("ArrayJobId") == job_id and fields.get("ArrayTaskId", "").isdigit():
            nodes[int(fields["ArrayTaskId"])] = fields.get("NodeList", "")
    return nodes


def tables(folder: Path) -> dict[str, bytes]:
    return {name: (folder / name).read_bytes() for name in TABLES if (folder / name).is_file()}


def logs(study: Path) -> str:
    parts = []
    for log in sorted((study / "slurm" / "logs").glob("*.out")):
        parts.append(f"--- {log.name} ---\n" + "\n".join(log.read_text().splitlines()[-15:]))
    return "\n".join(parts)


def wait_for_jobs(cluster: TwoNodeSlurm, study: Path, timeout: float) -> None:
    """Until squeue lists no job (the cluster runs this module's jobs only)."""
    deadline = time.monotonic() + timeout
    last = ""
    while time.monotonic() < deadline:
        out = cluster.run(["squeue", "-h", "-r", "-o", "%i %T %N"])
        last = out.stdout.strip()
        if out.returncode == 0 and not last:
            return
        time.sleep(1.0)
    raise AssertionError(f"jobs still queued after {timeout:.0f} s: {last}\n{logs(study)}\n"
                         f"{cluster.log_tail()}")


def engine_ranks(cluster: TwoNodeSlurm) -> dict[str, list[tuple[int, str]]]:
    """The running LIGGGHTS processes of each node (its network namespace), with the host
    name each one sees (its UTS namespace)."""
    ranks: dict[str, list[tuple[int, str]]] = {}
    for node in cluster.nodes:
        pids = subprocess.run(["ip", "netns", "pids", node], capture_output=True,
                              text=True).stdout.split()
        for pid in pids:
            try:
                argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
            except OSError:
                continue
            if Path(argv[0].decode()).name == "liggghts" and b"-in" in argv:  # not a probe
                host = subprocess.run(["nsenter", "-t", pid, "-u", "hostname"],
                                      capture_output=True, text=True).stdout.strip()
                ranks.setdefault(node, []).append((int(pid), host))
    return ranks


def launch_map(screen: str) -> list[tuple[str, str, str]]:
    """(node, procs, rank) of each node in mpirun's ``--display-map`` in the engine's log."""
    return re.findall(r"Data for node: (\S+)\s+Num slots: \d+\s+Max slots: \d+\s+"
                      r"Num procs: (\d+)\s+Process OMPI jobid: \S+ App: 0 Process rank: (\d+)",
                      screen)


ONE_RANK_EACH = [(NODES[0][0], "1", "0"), (NODES[1][0], "1", "1")]


def test_a_planned_two_rank_case_asks_two_nodes_and_gets_a_rank_on_each(two_node_slurm,
                                                                          tmp_path):
    env = clean_env(LIGWF_MESH_CACHE=str(tmp_path / "meshes"),
                    LIGWF_SITE=str(site_file(tmp_path / "site.yaml", "mpirun --display-map")))
    study = tmp_path / "planned"
    out = ligwf(two_node_slurm, "slurm", "submit", str(SPANNING), "--out", str(study),
                "--no-analysis", env=env).stdout
    assert "array-1.sh: 1 case(s), --ntasks=2, --nodes=2" in out, out
    script = (study / "slurm" / "array-1.sh").read_text()
    assert "#SBATCH --ntasks=2\n#SBATCH --nodes=2\n" in script
    case = Study.open(study).case(0)
    deadline = time.monotonic() + 1800
    while time.monotonic() < deadline and not launch_map(
            case.screen.read_text(errors="replace") if case.screen.is_file() else ""):
        time.sleep(0.5)
    assert launch_map(case.screen.read_text()) == ONE_RANK_EACH, logs(study)
    ranks: dict = {}
    while time.monotonic() < deadline and sum(map(len, ranks.values())) < 2:
        ranks = engine_ranks(two_node_slurm)
        time.sleep(0.2)
    assert {node: [host for _, host in found] for node, found in ranks.items()} == \
        {node: [node] for node in two_node_slurm.nodes}, ranks   # each rank sees its host
    ligwf(two_node_slurm, "slurm", "cancel", str(study), env=env)
    wait_for_jobs(two_node_slurm, study, timeout=900)
    assert case.manifest().status == "killed", (case.manifest().reason, logs(study))
    assert not engine_ranks(two_node_slurm)                   # nothing left on either node


def test_the_analysis_split_over_both_nodes_gives_the_local_tables(two_node_slurm, tmp_path):
    study = tmp_path / "study"
    local_ligwf("study", str(TINY), "--out", str(study), "--no-snapshots",
                "--set", "sweep.replicas=2", "--set", "analysis.bootstrap=50",
                env=clean_env(LIGWF_MESH_CACHE=str(tmp_path / "meshes"),
                              LIGWF_SITE=str(tmp_path / "none.yaml")))
    local = tables(study / "analysis")
    assert {"granules.parquet", "frames.csv", "gsd.csv", "flow.csv"} <= set(local)
    (study / "analysis" / "frames.csv").unlink()            # the merge must write it again
    env = clean_env(LIGWF_SITE=str(site_file(tmp_path / "site.yaml", "mpirun")))
    out = ligwf(two_node_slurm, "analyse", str(study), "--slurm", "2", env=env).stdout
    token = re.search(r"token (\w+)", out).group(1)
    subs = [s for s in read_record(study) if token in s["script"]]
    assert [s["kind"] for s in subs] == ["analysis-array", "analysis-merge"]
    wait_for_jobs(two_node_slurm, study, timeout=1800)
    placed = jobcomp_nodes(two_node_slurm, subs[0]["job_id"])
    assert sorted(placed) == [0, 1] and sorted(placed.values()) == \
        sorted(two_node_slurm.nodes), placed                    # one task on each node
    assert tables(study / "analysis") == local, logs(study)


def dumps(case_dir: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted((case_dir / "post").glob("*.vtu"))}


def dump_step(name: str) -> int:
    return int(re.search(r"_(\d+)\.vtu$", name).group(1))


def thermo_rows(case_dir: Path) -> list[str]:
    """The case's thermo rows (header first) without the engine's ``cpu`` column (the wall
    seconds of the run, the one column that may differ between identical runs)."""
    lines = [line.split(",") for line in (case_dir / "thermo.csv").read_text().splitlines()]
    cpu = lines[0].index("cpu")
    return [",".join(cells[:cpu] + cells[cpu + 1:]) for cells in lines]


def row_step(row: str) -> int:
    return int(row.split(",")[0])


@dataclass(frozen=True)
class Spanned:
    """The tiny case on 2 ranks over the two nodes (mpirun) and on 2 ranks of this machine."""

    study: Path
    local: Path
    env: dict[str, str]
    seconds: float


@pytest.fixture(scope="module")
def spanned(two_node_slurm, tmp_path_factory) -> Spanned:
    root = tmp_path_factory.mktemp("two-nodes")
    env = clean_env(LIGWF_MESH_CACHE=str(root / "meshes"),
                    LIGWF_SITE=str(site_file(root / "site.yaml", "mpirun --display-map")))
    study, local = root / "two-nodes", root / "one-node"
    t0 = time.monotonic()
    ligwf(two_node_slurm, "slurm", "submit", str(TINY), "--out", str(study), "--ntasks", "2",
          "--no-analysis", *CHEAP, *SHORT, env=env)
    wait_for_jobs(two_node_slurm, study, timeout=2400)
    # the same case on 2 ranks of this machine (no Slurm, no site file)
    local_ligwf("run", str(TINY), "--out", str(local), "--np", "2", *CHEAP, *SHORT,
                env=clean_env(LIGWF_MESH_CACHE=str(root / "meshes"),
                              LIGWF_SITE=str(root / "none.yaml")))
    return Spanned(study, local, env, time.monotonic() - t0)


def test_a_case_on_both_nodes_matches_two_ranks_of_one(two_node_slurm, spanned):
    study = spanned.study
    job = read_record(study)[0]["job_id"]
    assert jobcomp_nodes(two_node_slurm, job) == {0: "ligwf-n[1-2]"}
    case = Study.open(study).case(0)
    manifest = case.manifest()
    assert manifest.status == "done", (manifest.reason, logs(study))
    assert manifest.nprocs == 2 and manifest.atoms_end == PARTICLES, manifest
    assert launch_map(case.screen.read_text()) == ONE_RANK_EACH      # one rank on each host
    task_log = "".join(p.read_text() for p in (study / "slurm" / "logs").glob("*_0.out"))
    assert "on ligwf-n1 with 2 task(s) on 2 node(s): ligwf-n[1-2]" in task_log, task_log
    reference = Study.open(spanned.local).case(0)
    assert reference.manifest().status == "done" and reference.manifest().nprocs == 2
    grids = {re.search(r"\d+ by \d+ by \d+ MPI processor grid",
                       (folder.path / "log.liggghts").read_text()).group(0)
             for folder in (case, reference)}
    assert len(grids) == 1, grids                                # the same processor grid
    assert thermo_rows(case.path) == thermo_rows(reference.path)
    ours, theirs = dumps(case.path), dumps(reference.path)
    assert len(ours) >= 4 and ours.keys() == theirs.keys()
    assert [name for name in ours if ours[name] != theirs[name]] == []
    print(f"\ntwo nodes: the case on the cluster and on 2 local ranks in {spanned.seconds:.0f} s")


def test_a_killed_remote_rank_stops_the_case_and_resubmit_resumes_it(two_node_slurm,
                                                                        tmp_path):
    t0 = time.monotonic()
    env = clean_env(LIGWF_MESH_CACHE=str(tmp_path / "meshes"),
                    LIGWF_SITE=str(site_file(tmp_path / "site.yaml",
                                             "srun --mpi=pmix --kill-on-bad-exit=1")))
    study = tmp_path / "killed"
    # a production long enough that the kill lands in it (LONG's 0.6 s can end within the
    # time the test takes to see the restarts)
    ligwf(two_node_slurm, "slurm", "submit", str(TINY), "--out", str(study), "--ntasks", "2",
          "--no-analysis", *CHEAP, *LONG, "--set", "scene.process.run_time=1.5", env=env)
    assert "export LIGWF_MPIRUN=srun\n" in (study / "slurm" / "array-1.sh").read_text()
    case = Study.open(study).case(0)
    restarts = case.path / "restart"
    deadline = time.monotonic() + 2400
    ranks: dict = {}
    while time.monotonic() < deadline and sum(map(len, ranks.values())) < 2:
        ranks = engine_ranks(two_node_slurm)
        time.sleep(0.2)
    assert {node: [host for _, host in found] for node, found in ranks.items()} == \
        {node: [node] for node in two_node_slurm.nodes}, ranks        # one rank per host
    remote = ranks[NODES[1][0]][0][0]
    # both periodic restarts written (one of the pair is always whole: the engine writes
    # them in turn) and the screen in production; then a few more restarts' worth of
    # production, so the kill lands mid-run (restarts come every few tens of ms here)
    while time.monotonic() < deadline and not (
            all((restarts / n).is_file() for n in ("restart_a.liggghts", "restart_b.liggghts"))
            and "ligwf-phase production" in
            (case.screen.read_text(errors="replace") if case.screen.is_file() else "")):
        time.sleep(0.05)
    time.sleep(0.3)
    try:
        os.kill(remote, signal.SIGKILL)
    except ProcessLookupError:
        pytest.fail(f"the remote rank {remote} ended before the kill ({case.manifest()}); "
                    f"{logs(study)}")
    wait_for_jobs(two_node_slurm, study, timeout=900)

    manifest = case.manifest()
    # a task killed from outside (here by SIGKILL; the OOM killer or a lost node alike) is a
    # stop, not an engine error: the case is killed, with srun's signal as the reason
    assert manifest.status == "killed", (manifest.status, manifest.reason, logs(study))
    assert "signal 9" in manifest.reason, manifest.reason
    status = json.loads(ligwf(two_node_slurm, "slurm", "status", str(study), "--json",
                              env=env).stdout)
    (row,) = status["cases"]
    assert row["manifest"] == "killed" and row["slurm_state"] == "FAILED", row
    killed_at = manifest.steps_done
    assert 0 < killed_at < manifest.total_steps, manifest

    out = ligwf(two_node_slurm, "slurm", "resubmit", str(study), "--no-analysis", env=env)
    assert "resubmitting 1 case(s): 0 cg3-weber-r0 (killed)" in out.stdout, out.stdout
    record = read_record(study)
    assert [r["kind"] for r in record] == ["array", "array"] and record[1]["indices"] == [0]
    wait_for_jobs(two_node_slurm, study, timeout=2400)

    manifest = case.manifest()
    assert manifest.status == "done", (manifest.reason, logs(study))
    assert manifest.atoms_end == PARTICLES
    # the killed case resumes from its own restart (ligwf.engine.resume), at or before the
    # step it was killed at, and its rows and dumps past the restart are replaced, not mixed
    assert len(manifest.attempts) == 2 and manifest.attempts[0].status == "killed"
    resumed = manifest.attempts[1]
    assert resumed.status == "done"
    if not resumed.from_restart:
        # run again from step 0 only when no restart was the case's own whole one at or
        # before its recorded progress (a kill mid-write, screen rows lost with the rank):
        # then every restart it did not use is named with why, never skipped silently
        skipped = [i for i in manifest.issues if i.get("kind") == "restart_skipped"]
        assert skipped, (resumed, manifest.issues)
    else:
        assert 0 < resumed.from_step <= killed_at, (resumed, manifest.issues)
    # nothing lost, nothing twice: every row and dump step once, up to the last step
    steps = [row_step(r) for r in thermo_rows(case.path)[1:]]
    assert steps == sorted(set(steps)) and steps[-1] == manifest.total_steps
    ours = dumps(case.path)
    particle_steps = sorted(dump_step(n) for n in ours if n.startswith("particles_"))
    assert particle_steps == case.expected_dump_steps(manifest.total_steps)
    assert all(f'NumberOfPoints="{PARTICLES}"'.encode() in data
               for name, data in ours.items() if name.startswith("particles_"))
    print(f"\ntwo nodes: kill of the remote rank at step {killed_at}, run again, done in "
          f"{time.monotonic() - t0:.0f} s")
