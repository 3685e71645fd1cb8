"""The site assumptions ``ligwf slurm submit --dry-run`` prints (ligwf.slurm.assumptions):
the launch line is the engine's, every assumption names the command that checks it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from ligwf.engine.site import EngineConfig
from ligwf.slurm.assumptions import launch_line, site_assumptions
from ligwf.scheduler import JobRound
from ligwf.slurm.jobs import plan_jobs
from ligwf.slurm.site import SlurmSite

HERE = Path(__file__).resolve().parent
LIGWF = str(Path(sys.executable).parent / "ligwf")


@pytest.mark.parametrize("launcher", ["srun --mpi=pmix", "mpirun --display-map"])
def test_launch_line_is_the_engines(launcher, tmp_path, monkeypatch):
    """The block's line and EngineConfig.mpirun_prefix agree (a fake launcher on the PATH
    makes the engine's path lookup succeed; the root switch is the engine's addition)."""
    name = launcher.split()[0]
    (tmp_path / name).write_text("#!/bin/sh\n")
    (tmp_path / name).chmod(0o755)
    words = launcher.split()
    monkeypatch.setenv("PATH", f"{tmp_path}:{os.environ['PATH']}")
    prefix = EngineConfig(mpirun=words[0], mpirun_args=tuple(words[1:])).mpirun_prefix(4)
    engine = " ".join([Path(prefix[0]).name] + [w for w in prefix[1:]
                                                if w != "--allow-run-as-root"])
    assert launch_line(launcher, "4").startswith(engine + " liggghts ")


def test_block_names_launcher_cores_partition_and_account(tmp_path):
    site = SlurmSite(ligwf="/v/ligwf", partition="compute", time="02:00:00", cores_per_node=64,
                     launcher="srun --mpi=pmix")
    jobs = plan_jobs(tmp_path, "s", site, JobRound(
        (0, 1, 2), ranks={0: 119, 1: 8, 2: 8}, post_steps=("analyse",)))
    lines = site_assumptions(site, jobs, "mpirun")
    text = "\n".join(lines)
    assert lines[0].startswith("site assumptions") and len(lines) == 5
    assert "srun --mpi=pmix (the site's slurm launcher)" in text
    assert "'srun --mpi=pmix --ntasks=RANKS liggghts" in text and "srun --mpi=list" in text
    assert "cores per node: 64" in text and "ceil(ranks / 64)" in text
    assert "--ntasks=119 --nodes=2, --time=02:00:00 per case" in text     # the largest case
    assert "scontrol show partition compute" in text
    assert "account: none given" in text


def test_block_without_site_launcher_cores_or_partition(tmp_path):
    site = SlurmSite(ligwf="/v/ligwf", ntasks=4)
    jobs = plan_jobs(tmp_path, "s", site, JobRound((0,)))
    text = "\n".join(site_assumptions(site, jobs, "mpirun --bind-to core"))
    assert "mpirun --bind-to core (the engine settings; no slurm launcher set" in text
    assert "'mpirun --bind-to core -np RANKS liggghts" in text and "plm: slurm" in text
    assert "cores per node: unknown" in text
    assert "the default partition" in text and "--ntasks=4," in text
    assert "no --time (the partition's default time limit)" in text
    srun = "\n".join(site_assumptions(SlurmSite(ligwf="l", launcher="srun"), jobs, "mpirun"))
    assert "no --mpi= given: the site's MpiDefault" in srun


def test_dry_run_prints_the_block_once(tmp_path):
    env = dict(os.environ, LIGWF_MESH_CACHE=str(tmp_path / "meshes"),
               LIGWF_SITE=str(tmp_path / "none.yaml"), LIGWF_SLURM_LAUNCHER="srun --mpi=pmix")
    out = subprocess.run([LIGWF, "slurm", "submit", str(HERE / "spanning_drum.yaml"), "--out",
                          str(tmp_path / "s"), "--dry-run", "--cores-per-node", "1",
                          "--partition", "debug", "--time", "00:10:00"],
                         capture_output=True, text=True, env=env, timeout=120,
                         stdin=subprocess.DEVNULL)
    assert out.returncode == 0, out.stderr
    assert out.stdout.count("site assumptions") == 1
    block = out.stdout[out.stdout.index("site assumptions"):].split("# -----")[0]
    assert "srun --mpi=pmix (the site's slurm launcher)" in block
    assert "cores per node: 1" in block and "--ntasks=2 --nodes=2" in block
    assert "scontrol show partition debug" in block
    assert not (tmp_path / "s").exists()
