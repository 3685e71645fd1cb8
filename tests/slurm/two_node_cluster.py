"""A real two-node Slurm cluster on this one machine, for the multi-node tests.

Why: a paper-scale case asks for ``--nodes=2`` and its engine ranks meet over the network;
a one-node cluster on 127.0.0.1 never exercises that path (issue 34). Two hosts are made
from Linux namespaces, nothing leaves the machine:

* one network namespace per node (``ip netns``: ``ligwf-n1``, ``ligwf-n2``), joined by a
  veth pair on a private /24 (:data:`SUBNET`) that exists only inside these two namespaces,
  each with its own loopback; nothing is routed anywhere else, and every process of a node
  sees ``/etc/netns/<ns>/hosts`` (both nodes, bind-mounted over /etc/hosts in a mount
  namespace of its own), so a name lookup never leaves the node;
* one UTS namespace per daemon (``unshare --uts``) so ``hostname`` on node 2 says
  ``ligwf-n2``: slurmd finds its NodeName by it, OpenMPI's mpirun matches it against the
  allocation's node list (:func:`in_node` starts a process "on" a node);
* one slurm.conf (:data:`CONF`, passed with ``-f`` and ``SLURM_CONF``, never the machine's
  /etc/slurm/slurm.conf): slurmctld on node 1, one slurmd per node with
  ``NodeName``/``NodeHostname``/``NodeAddr``, one core each (so a 2-rank case must span
  both), ``%n`` in the per-node spool, pid, log and TmpFS paths (the nodes share one /tmp:
  srun's PMIx plugin would otherwise collide on its per-step directory there);
* munge shared: its socket is a file, the same from every network namespace
  (:func:`local_cluster.start_munge`).

Client commands (sbatch, squeue, ``ligwf slurm ...``) run "on node 1" through
:meth:`TwoNodeSlurm.command` (:func:`in_node` of ``ligwf-n1``): the cluster's addresses
are reachable only from inside its namespaces. Jobs inherit that environment from sbatch.

:meth:`TwoNodeSlurm.stop` always leaves nothing behind: ``scontrol shutdown``, then every
process still inside the two namespaces (job steps, orted, engine ranks) is killed, the
namespaces (with the veth) are deleted and the hosts files removed; our munged is stopped.
Leftovers of an earlier, crashed session (same namespace names) are cleaned the same way
before a start. Every failure raises :class:`SlurmUnavailable` with the reason and the
daemons' log tails, so the test fails instead of skipping.
"""

from __future__ import annotations

import os
import signal
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

from local_cluster import SlurmUnavailable, _run, _wait_pidfile_gone, ensure_installed, \
    start_munge

from ligwf.study.manifest import pid_alive

#: (network namespace = host name, veth end, address) of each node; node 1 runs slurmctld
NODES = (("ligwf-n1", "lwveth1", "10.254.34.1"), ("ligwf-n2", "lwveth2", "10.254.34.2"))
SUBNET = "10.254.34.0/24"
ROOT = Path("/var/lib/ligwf-test-slurm2")
LOG_DIR = Path("/var/log/ligwf-test-slurm2")
CONF = ROOT / "slurm.conf"
NETNS_ETC = Path("/etc/netns")
#: what OpenMPI needs on these nodes: root allowed, its TCP traffic on the veth only
OMPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
            "OMPI_MCA_btl_tcp_if_include": SUBNET, "OMPI_MCA_oob_tcp_if_include": SUBNET}


def two_node_conf(root: Path = ROOT, log_dir: Path = LOG_DIR, cores_per_node: int = 1) -> str:
    """The slurm.conf text of the two-node cluster (pure)."""
    head, _, head_addr = NODES[0]
    nodes = [f"NodeName={name} NodeHostname={name} NodeAddr={addr} CPUs={cores_per_node} "
             f"Boards=1 SocketsPerBoard=1 CoresPerSocket={cores_per_node} ThreadsPerCore=1 "
             "RealMemory=500 State=UNKNOWN" for name, _, addr in NODES]
    return "\n".join([
        "# written by ligwf's test fixture (tests/slurm/two_node_cluster.py)",
        "ClusterName=ligwftwo",
        f"SlurmctldHost={head}({head_addr})",
        "SlurmUser=root",
        "AuthType=auth/munge",
        "ProctrackType=proctrack/linuxproc",
        "TaskPlugin=task/none",
        "SelectType=select/cons_tres",
        "SelectTypeParameters=CR_Core",
        "SchedulerType=sched/backfill",
        "SchedulerParameters=batch_sched_delay=0",
        "AccountingStorageType=accounting_storage/none",
        "JobAcctGatherType=jobacct_gather/none",
        "JobCompType=jobcomp/filetxt",
        f"JobCompLoc={log_dir}/jobcomp.txt",
        "MpiDefault=none",
        "ReturnToService=2",
        "KillWait=10",
        "MinJobAge=600",
        "SlurmdTimeout=30",
        "SlurmdParameters=config_overrides",    # 1 core of the machine's 2 per node
        f"TmpFS={root}/tmp-%n",
        f"StateSaveLocation={root}/state",
        f"SlurmdSpoolDir={root}/spool-%n",
        f"SlurmctldPidFile={root}/slurmctld.pid",
        f"SlurmdPidFile={root}/slurmd-%n.pid",
        f"SlurmctldLogFile={log_dir}/slurmctld.log",
        f"SlurmdLogFile={log_dir}/slurmd-%n.log",
        *nodes,
        f"PartitionName=debug Nodes={','.join(n for n, _, _ in NODES)} Default=YES "
        "MaxTime=INFINITE State=UP",
        "",
    ])


def hosts_file() -> str:
    """/etc/hosts inside each node's namespace: loopback and both nodes (pure)."""
    return "\n".join(["127.0.0.1 localhost", *[f"{addr} {name}" for name, _, addr in NODES],
                      ""])


def in_node(node: str, argv: list[str]) -> list[str]:
    """``argv`` as a process of ``node``: its network namespace, a UTS namespace whose host
    name is the node's, and a mount namespace (slave of the machine's: every other mount is
    seen as it is) where the node's hosts file covers /etc/hosts. (``ip netns exec`` would
    also remount /sys, hiding the cgroup file system slurmd needs.)"""
    script = 'mount --bind "$1" /etc/hosts && hostname "$0" && shift && exec "$@"'
    return ["nsenter", f"--net=/run/netns/{node}", "unshare", "--uts", "--mount",
            "--propagation", "slave", "--", "sh", "-c", script, node,
            str(NETNS_ETC / node / "hosts"), *argv]


def _namespaces() -> set[str]:
    out = _run(["ip", "netns", "list"], check=False).stdout
    return {line.split()[0] for line in out.splitlines() if line.strip()}


def _kill_namespace_processes(node: str, timeout: float = 10.0) -> None:
    """SIGTERM, then SIGKILL, every process inside ``node``'s network namespace (they are
    this fixture's: daemons, job steps, engine ranks)."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        pids = [int(p) for p in _run(["ip", "netns", "pids", node], check=False).stdout.split()]
        for pid in pids:
            try:
                os.kill(pid, sig)
            except ProcessLookupError:
                pass
        deadline = time.monotonic() + timeout
        while pids and time.monotonic() < deadline:
            pids = [p for p in pids if pid_alive(p)]
            time.sleep(0.2)
        if not pids:
            return


def teardown_network() -> None:
    """Delete the nodes' namespaces (with whatever still runs there) and hosts files."""
    present = _namespaces()
    for node, _, _ in NODES:
        if node in present:
            _kill_namespace_processes(node)
            _run(["ip", "netns", "delete", node], check=False)
        shutil.rmtree(NETNS_ETC / node, ignore_errors=True)


def setup_network() -> None:
    """Two namespaces, a veth pair between them on :data:`SUBNET`, loopback up in each."""
    (n1, v1, _), (n2, v2, _) = NODES
    for node, _, _ in NODES:
        _run(["ip", "netns", "add", node])
        (NETNS_ETC / node).mkdir(parents=True, exist_ok=True)
        (NETNS_ETC / node / "hosts").write_text(hosts_file())
        _run(["ip", "-n", node, "link", "set", "lo", "up"])
    _run(["ip", "link", "add", v1, "netns", n1, "type", "veth", "peer", "name", v2,
          "netns", n2])
    prefix = SUBNET.split("/")[1]
    for node, veth, addr in NODES:
        _run(["ip", "-n", node, "addr", "add", f"{addr}/{prefix}", "dev", veth])
        _run(["ip", "-n", node, "link", "set", veth, "up"])


@dataclass
class TwoNodeSlurm:
    """Start and stop the two-node cluster; run client commands on its node 1."""

    root: Path = ROOT
    log_dir: Path = LOG_DIR
    munged_pid: int | None = None
    started: bool = False

    @property
    def conf(self) -> Path:
        return self.root / "slurm.conf"

    @property
    def jobcomp(self) -> Path:
        return self.log_dir / "jobcomp.txt"

    @property
    def nodes(self) -> tuple[str, ...]:
        return tuple(name for name, _, _ in NODES)

    def env(self, base: dict[str, str] | None = None) -> dict[str, str]:
        """``base`` (default: this process's) with SLURM_CONF and the OpenMPI settings."""
        return dict(os.environ if base is None else base, SLURM_CONF=str(self.conf),
                    **OMPI_ENV)

    def command(self, argv: list[str]) -> list[str]:
        """``argv`` run on node 1 (where the login shell of a real cluster would be)."""
        return in_node(NODES[0][0], argv)

    def run(self, argv: list[str], env: dict[str, str] | None = None,
            timeout: float = 60) -> subprocess.CompletedProcess:
        """``argv`` on node 1 with the cluster's environment; output captured, not checked."""
        return subprocess.run(self.command(argv), capture_output=True, text=True,
                              timeout=timeout, stdin=subprocess.DEVNULL, env=self.env(env))

    def log_tail(self, lines: int = 15) -> str:
        parts = []
        for path in sorted(self.log_dir.glob("slurm*.log")):
            parts.append(f"--- {path} ---\n" + "\n".join(path.read_text(errors="replace")
                                                         .splitlines()[-lines:]))
        return "\n".join(parts)

    def _daemon(self, node: str, argv: list[str]) -> None:
        out = subprocess.run(in_node(node, argv), capture_output=True, text=True, timeout=60,
                             stdin=subprocess.DEVNULL, env=self.env())
        if out.returncode != 0:
            raise SlurmUnavailable(f"{' '.join(argv)} on {node} exited {out.returncode}: "
                                   f"{(out.stdout + out.stderr).strip()[-1500:]}\n"
                                   f"{self.log_tail()}")

    def start(self, timeout: float = 60.0) -> None:
        """Install if needed, build the two hosts, start munged, slurmctld and both
        slurmds, wait until both nodes are idle."""
        ensure_installed()
        if os.geteuid() != 0:
            raise SlurmUnavailable("network namespaces and slurmd need root")
        for tool in ("ip", "unshare", "nsenter"):
            if not shutil.which(tool):
                raise SlurmUnavailable(f"{tool} not found (Debian packages iproute2, "
                                       "util-linux)")
        teardown_network()                       # leftovers of a crashed earlier session
        self.started = True                      # from here on stop() must clean up
        self.munged_pid = start_munge()
        setup_network()
        n1 = NODES[0][0]
        # a clean start: job ids begin at 1 again, so no socket or file of an earlier job
        fresh = [self.root / "state", self.log_dir,
                 *[self.root / f"{kind}-{node}" for node in self.nodes
                   for kind in ("spool", "tmp")]]
        for d in fresh:
            shutil.rmtree(d, ignore_errors=True)
            d.mkdir(parents=True)
        self.conf.write_text(two_node_conf(self.root, self.log_dir))
        self._daemon(n1, ["slurmctld", "-c", "-f", str(self.conf)])
        for node in self.nodes:
            self._daemon(node, ["slurmd", "-f", str(self.conf)])
        deadline = time.monotonic() + timeout
        last = ""
        while time.monotonic() < deadline:
            out = self.run(["sinfo", "-h", "-N", "-o", "%N %T"])
            last = (out.stdout + out.stderr).strip()
            states = dict(line.split()[:2] for line in last.splitlines() if len(line.split()) > 1)
            if out.returncode == 0 and set(states) == set(self.nodes) and \
                    all(s == "idle" for s in states.values()):
                return
            time.sleep(0.5)
        raise SlurmUnavailable(f"sinfo did not show both nodes idle within {timeout:.0f} s "
                               f"(last: {last!r})\n{self.log_tail()}")

    def stop(self) -> None:
        """Shut Slurm down, kill what is left in the namespaces, delete them, stop our
        munged. Safe to call after a failed or partial start."""
        if self.started:
            if self.conf.is_file():
                try:
                    self.run(["scontrol", "shutdown"], timeout=20)
                except (OSError, subprocess.TimeoutExpired):
                    pass
                pids = [self.root / "slurmctld.pid",
                        *[self.root / f"slurmd-{n}.pid" for n in self.nodes]]
                for pidfile in pids:
                    _wait_pidfile_gone(pidfile, timeout=15)
            teardown_network()
            self.started = False
        if self.munged_pid and pid_alive(self.munged_pid):
            os.kill(self.munged_pid, signal.SIGTERM)
        self.munged_pid = None
