"""What a Slurm submission assumes about the site, in one block a user checks before a job.

A first multi-node job fails on things ligwf cannot see from the login node: an MPI
launcher that cannot start ranks on the other nodes of an allocation, a wrong number of
cores per node (ranks pile up, or a case asks for more nodes than it needs), a ``--time``
or node count beyond the partition's limits. ``ligwf slurm submit --dry-run`` prints these
assumptions, each with the command that checks it on the cluster (pure: from the resolved
site settings and the planned jobs; no Slurm is asked).

The launch line is the engine's (:meth:`ligwf.engine.site.EngineConfig.mpirun_prefix`):
``srun ARGS --ntasks=N`` for Slurm's srun, ``mpirun ARGS -np N`` for anything else (plus
``--allow-run-as-root`` when the job runs as root).
"""

from __future__ import annotations

import shlex
from pathlib import PurePosixPath
from typing import Sequence

from ligwf.slurm.site import SlurmSite
from ligwf.study.layout import INPUT_NAME

#: the kinds of array job whose tasks run the engine (see ligwf.slurm.jobs.PlannedJob)
_CASE_KINDS = ("array",)


def launch_line(launcher: str, ranks: str = "RANKS") -> str:
    """The engine's launch line inside an allocation for ``launcher`` (pure)."""
    words = shlex.split(launcher)
    if PurePosixPath(words[0]).name == "srun":
        return shlex.join(words) + f" --ntasks={ranks} liggghts -in {INPUT_NAME} ..."
    return shlex.join(words) + f" -np {ranks} liggghts -in {INPUT_NAME} ..."


def launcher_note(launcher: str) -> str:
    """What ``launcher`` needs from the site to start ranks on every node of the job."""
    name = PurePosixPath(shlex.split(launcher)[0]).name
    if name == "srun":
        mpi = [w for w in shlex.split(launcher) if w.startswith("--mpi")]
        plugin = ("" if mpi else "; no --mpi= given: the site's MpiDefault must be an MPI "
                  "plugin the engine's MPI speaks")
        return ("Slurm's srun starts the ranks on the allocation's nodes: 'srun --mpi=list' "
                "must list the plugin (pmix for OpenMPI 4)" + plugin)
    if name in ("mpirun", "mpiexec", "orterun"):
        return ("OpenMPI's mpirun reads the nodes from Slurm and starts its daemons on the "
                "other nodes through srun: needs an OpenMPI built with Slurm support "
                "('ompi_info | grep \"plm: slurm\"'); ranks talk over its TCP/fast network")
    return f"'{name}' is not srun or OpenMPI's mpirun: ligwf calls it as '{name} -np RANKS'"


def site_assumptions(site: SlurmSite, jobs: Sequence, engine_launcher: str) -> list[str]:
    """The block's lines: MPI launcher, cores per node, partition limits, account.

    ``jobs``: the planned jobs (:class:`ligwf.slurm.jobs.PlannedJob`); ``engine_launcher``:
    the engine settings' launcher and arguments (what the job uses when the site sets no
    Slurm launcher: the job inherits the submitting environment)."""
    arrays = [job for job in jobs if job.kind in _CASE_KINDS]
    ranks = max((job.site.ntasks if job.site else site.ntasks for job in arrays), default=1)
    nodes = max((job.nodes for job in arrays if job.nodes is not None), default=None)
    if site.launcher is not None:
        launcher, source = site.launcher, "the site's slurm launcher"
    else:
        launcher, source = engine_launcher, ("the engine settings; no slurm launcher set in "
                                             "the site's 'slurm: launcher:' or "
                                             "LIGWF_SLURM_LAUNCHER")
    lines = ["site assumptions (check them against your cluster's documentation):",
             f"  MPI launcher: {launcher} ({source}); each case runs "
             f"'{launch_line(launcher)}' in its allocation. {launcher_note(launcher)}"]
    if site.cores_per_node is None:
        lines.append("  cores per node: unknown (--cores-per-node / site cores_per_node "
                     "unset): the scripts ask for --ntasks only and Slurm places the ranks")
    else:
        lines.append(f"  cores per node: {site.cores_per_node} (--cores-per-node / site "
                     f"cores_per_node): a planned case asks for --nodes = ceil(ranks / "
                     f"{site.cores_per_node}); a node with fewer cores gets more ranks than "
                     "cores, one with more leaves cores idle ('sinfo -o \"%P %c %D\"')")
    partition = site.partition or "the default partition"
    asks = f"--ntasks={ranks}" + (f" --nodes={nodes}" if nodes is not None else "")
    time = (f"--time={site.time} per case" if site.time
            else "no --time (the partition's default time limit)")
    show = f"'scontrol show partition {site.partition}'" if site.partition else \
        "'scontrol show partition'"
    lines.append(f"  partition: {partition}; its limits are not checked: the largest case "
                 f"asks for {asks}, {time}; MaxNodes, MaxTime and the cores per node must "
                 f"allow that ({show})")
    lines.append(f"  account: {site.account or 'none given (your default account)'}")
    return lines
