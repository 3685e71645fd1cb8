"""A real single-node Slurm cluster on this machine, for the ``slurm`` integration tests.

Why a real one: the array/dependency/cancel behaviour ligwf relies on (``%A_%a`` log names,
``afterany`` dependencies, SIGTERM on ``scancel``) is Slurm's, and a fake would only repeat
our own assumptions back to us. The set-up follows ../shared/LIGGGHTS_NOTES.md: Debian
``slurmctld slurmd munge`` (installed with ``--no-install-recommends`` when missing), munged
under /run/munge, a ``slurm.conf`` with this host's ``slurmd -C`` node line on 127.0.0.1,
``proctrack/linuxproc``, ``task/none``, ``cons_tres`` with ``CR_Core``, no accounting and
``jobcomp/filetxt`` (the only record of finished jobs without slurmdbd).

Every failure raises :class:`SlurmUnavailable` with the reason and the daemons' log tail, so
a test that needs the cluster fails loudly instead of skipping.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

from ligwf.study.manifest import pid_alive

PACKAGES = ("slurmctld", "slurmd", "munge")
ROOT = Path("/var/lib/ligwf-test-slurm")
LOG_DIR = Path("/var/log/ligwf-test-slurm")
CONF = Path("/etc/slurm/slurm.conf")


class SlurmUnavailable(RuntimeError):
    """The local Slurm cluster could not be installed, configured or started."""


def _run(cmd: list[str], timeout: float = 60, check: bool = True,
         env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                             stdin=subprocess.DEVNULL, env=env)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise SlurmUnavailable(f"{' '.join(cmd)}: {exc}") from None
    if check and out.returncode != 0:
        raise SlurmUnavailable(f"{' '.join(cmd)} exited {out.returncode}: "
                               f"{(out.stdout + out.stderr).strip()[-2000:]}")
    return out


def ensure_installed() -> None:
    """Install the Debian Slurm and munge packages if any command is missing (needs root)."""
    missing = [c for c in ("slurmctld", "slurmd", "munged", "sbatch") if not shutil.which(c)]
    if not missing:
        return
    if os.geteuid() != 0:
        raise SlurmUnavailable(f"{', '.join(missing)} not installed and not root: install "
                               f"{' '.join(PACKAGES)} (apt-get install --no-install-recommends)")
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    _run(["apt-get", "update", "-qq"], timeout=600, env=env)
    _run(["apt-get", "install", "-y", "-qq", "--no-install-recommends", *PACKAGES],
         timeout=900, env=env)
    still = [c for c in ("slurmctld", "slurmd", "munged", "sbatch") if not shutil.which(c)]
    if still:
        raise SlurmUnavailable(f"installed {' '.join(PACKAGES)} but {', '.join(still)} missing")


def node_line() -> str:
    """This host's ``NodeName=...`` line as ``slurmd -C`` prints it, on 127.0.0.1."""
    out = _run(["slurmd", "-C"]).stdout
    for line in out.splitlines():
        if line.startswith("NodeName="):
            return f"{line.strip()} NodeAddr=127.0.0.1 State=UNKNOWN"
    raise SlurmUnavailable(f"slurmd -C printed no NodeName line: {out!r}")


def slurm_conf(host: str, node: str, root: Path = ROOT, log_dir: Path = LOG_DIR,
               extra: tuple[str, ...] = ()) -> str:
    """The slurm.conf text of the one-node cluster (pure)."""
    name = node.split()[0].split("=", 1)[1]
    return "\n".join([
        "# written by ligwf's test fixture (tests/slurm/local_cluster.py)",
        "ClusterName=ligwftest",
        f"SlurmctldHost={host}(127.0.0.1)",
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
        f"StateSaveLocation={root}/state",
        f"SlurmdSpoolDir={root}/spool",
        f"SlurmctldPidFile={root}/slurmctld.pid",
        f"SlurmdPidFile={root}/slurmd.pid",
        f"SlurmctldLogFile={log_dir}/slurmctld.log",
        f"SlurmdLogFile={log_dir}/slurmd.log",
        node,
        f"PartitionName=debug Nodes={name} Default=YES MaxTime=INFINITE State=UP",
        *extra,
        "",
    ])


def start_munge() -> int | None:
    """Start munged (key created if missing) unless one runs already; its pid if this call
    started it (the caller stops it again), None if someone else's munged answers."""
    key = Path("/etc/munge/munge.key")
    if not key.is_file():
        _run(["mungekey", "--create", "--keyfile", str(key)])
        shutil.chown(key, "munge", "munge")
        key.chmod(0o400)
    run = Path("/run/munge")
    run.mkdir(parents=True, exist_ok=True)
    shutil.chown(run, "munge", "munge")
    for d in (Path("/var/lib/munge"), Path("/var/log/munge")):
        d.mkdir(parents=True, exist_ok=True)
        shutil.chown(d, "munge", "munge")
    pidfile = run / "munged.pid"
    if pidfile.is_file() and pid_alive(int(pidfile.read_text().split()[0])):
        return None  # someone else's munged: use it, never stop it
    _run(["runuser", "-u", "munge", "--", "munged", "--force"])
    pid = None
    for _ in range(50):
        if pidfile.is_file():
            pid = int(pidfile.read_text().split()[0])
            break
        time.sleep(0.1)
    _run(["munge", "-n"])  # proves the daemon answers
    return pid


@dataclass
class LocalSlurm:
    """Start and stop the one-node cluster; ``jobcomp`` is the finished-jobs record.

    ``extra_conf`` lines are appended to slurm.conf (the failure test uses a bad one).
    Only a munged this object started is stopped again; the original slurm.conf, if any,
    is put back.
    """

    root: Path = ROOT
    log_dir: Path = LOG_DIR
    extra_conf: tuple[str, ...] = ()
    munged_pid: int | None = None
    started: bool = False
    conf_backup: str | None = field(default=None, repr=False)

    @property
    def jobcomp(self) -> Path:
        return self.log_dir / "jobcomp.txt"

    def _log_tail(self) -> str:
        parts = []
        for name in ("slurmctld.log", "slurmd.log"):
            path = self.log_dir / name
            if path.is_file():
                parts.append(f"--- {path} ---\n" + "\n".join(path.read_text().splitlines()[-15:]))
        return "\n".join(parts)

    def _start_munge(self) -> None:
        self.munged_pid = start_munge()

    def start(self, timeout: float = 60.0) -> None:
        """Install if needed, configure, start munged, slurmctld and slurmd, wait for idle."""
        ensure_installed()
        if os.geteuid() != 0:
            raise SlurmUnavailable("starting slurmd needs root")
        self._start_munge()
        for d in (self.root / "state", self.root / "spool", self.log_dir):
            d.mkdir(parents=True, exist_ok=True)
        if self.jobcomp.exists():
            self.jobcomp.unlink()
        CONF.parent.mkdir(parents=True, exist_ok=True)
        if CONF.is_file():
            self.conf_backup = CONF.read_text()
        CONF.write_text(slurm_conf(socket.gethostname().split(".")[0], node_line(),
                                   self.root, self.log_dir, self.extra_conf))
        _run(["slurmctld", "-c"])  # -c: clean start, no jobs from an earlier session
        self.started = True  # from here on stop() must shut the controller down
        _run(["slurmd"])
        deadline = time.monotonic() + timeout
        last = ""
        while time.monotonic() < deadline:
            out = _run(["sinfo", "-h", "-o", "%T"], check=False)
            last = (out.stdout + out.stderr).strip()
            if out.returncode == 0 and last.split() and all(s == "idle" for s in last.split()):
                return
            time.sleep(0.5)
        raise SlurmUnavailable(f"sinfo did not show idle within {timeout:.0f} s (last: {last!r})"
                               f"\n{self._log_tail()}")

    def stop(self) -> None:
        """``scontrol shutdown``, wait for both daemons to exit, then stop our munged."""
        if self.started:
            _run(["scontrol", "shutdown"], check=False)
            for pidfile in (self.root / "slurmctld.pid", self.root / "slurmd.pid"):
                _wait_pidfile_gone(pidfile)
            self.started = False
        if self.munged_pid and pid_alive(self.munged_pid):
            os.kill(self.munged_pid, signal.SIGTERM)
        self.munged_pid = None
        if self.conf_backup is not None:
            CONF.write_text(self.conf_backup)
            self.conf_backup = None



def _wait_pidfile_gone(pidfile: Path, timeout: float = 20.0) -> None:
    if not pidfile.is_file():
        return
    try:
        pid = int(pidfile.read_text().split()[0])
    except (ValueError, IndexError):
        return
    deadline = time.monotonic() + timeout
    while pid_alive(pid) and time.monotonic() < deadline:
        time.sleep(0.2)
    if pid_alive(pid):
        os.kill(pid, signal.SIGKILL)
