"""Where the engine is and how to launch it: site settings, never hard-coded paths.

The LIGGGHTS executable and the MPI launcher come from environment variables
(``LIGWF_LIGGGHTS``, ``LIGWF_MPIRUN``, ``LIGWF_MPIRUN_ARGS``), else from a site file
(``$LIGWF_SITE`` or ``~/.config/ligwf/site.yaml``, keys ``liggghts``, ``mpirun``,
``mpirun_args``), else ``liggghts`` and ``mpirun`` on the PATH. OpenMPI refuses to run as
root unless told so: ``--allow-run-as-root`` is added only when running as root.
"""

from __future__ import annotations

import os
import shlex
import shutil
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ligwf.errors import ConfigError, EngineNotFound
from ligwf.yamlio import read_yaml_mapping


def _site_file() -> Path:
    env = os.environ.get("LIGWF_SITE")
    if env:
        return Path(env)
    return Path(os.environ.get("XDG_CONFIG_HOME", Path.home() / ".config")) / "ligwf" / "site.yaml"


#: what a site file may set (anything else is a typo that would be ignored silently)
SITE_KEYS = ("liggghts", "mpirun", "mpirun_args", "libliggghts", "slurm")


def load_site() -> dict:
    """The site YAML as a mapping ({} when there is none); unknown keys are refused."""
    path = _site_file()
    site = read_yaml_mapping(path, "site file") if path.exists() else {}
    unknown = sorted(set(site) - set(SITE_KEYS))
    if unknown:
        raise ConfigError(f"site file {path}: unknown key(s) {', '.join(unknown)} (typo?; "
                          f"allowed: {', '.join(SITE_KEYS)})")
    for key in ("liggghts", "mpirun", "libliggghts"):
        if key in site and (not isinstance(site[key], str) or not site[key].strip()):
            raise ConfigError(f"site file {path}: {key} = {site[key]!r}: must be a program "
                              "or file name")
    args = site.get("mpirun_args")
    if args is not None and not isinstance(args, str) and not (
            isinstance(args, list) and all(isinstance(a, (str, int, float)) and
                                           not isinstance(a, bool) for a in args)):
        raise ConfigError(f"site file {path}: mpirun_args is a {type(args).__name__} "
                          "(or holds one): must be a string or a list of arguments")
    return site


def _setting(site: dict, key: str) -> str:
    """``LIGWF_<KEY>``, else the site file's ``key``, else the program name ``key``."""
    return str(os.environ.get(f"LIGWF_{key.upper()}", site.get(key, key)))


@dataclass(frozen=True)
class EngineConfig:
    """How to start LIGGGHTS on this site."""

    liggghts: str = "liggghts"
    mpirun: str = "mpirun"
    mpirun_args: tuple[str, ...] = field(default_factory=tuple)

    @classmethod
    def from_site(cls) -> "EngineConfig":
        site = load_site()
        if "LIGWF_MPIRUN_ARGS" in os.environ:
            args, where = os.environ["LIGWF_MPIRUN_ARGS"], "LIGWF_MPIRUN_ARGS"
        else:
            args, where = site.get("mpirun_args", ""), f"site file {_site_file()}: mpirun_args"
        if isinstance(args, list):
            args = " ".join(map(str, args))
        try:
            words = tuple(shlex.split(str(args)))
        except ValueError as exc:     # an unclosed quote: "No closing quotation"
            raise ConfigError(f"{where} = {str(args)!r}: not a valid argument list "
                              f"({str(exc).lower()}); quote as in a shell") from None
        return cls(liggghts=_setting(site, "liggghts"), mpirun=_setting(site, "mpirun"),
                   mpirun_args=words)

    def liggghts_path(self) -> str:
        path = shutil.which(self.liggghts)
        if not path:
            raise EngineNotFound(f"LIGGGHTS executable {self.liggghts!r} not found; install the "
                                 "Debian package liggghts or set LIGWF_LIGGGHTS")
        return path

    def mpirun_path(self) -> str:
        path = shutil.which(self.mpirun)
        if not path:
            raise EngineNotFound(f"MPI launcher {self.mpirun!r} not found; install openmpi-bin "
                                 "or set LIGWF_MPIRUN")
        return path

    def mpirun_prefix(self, nprocs: int) -> list[str]:
        """``mpirun -np N`` (+ --allow-run-as-root for root, + site arguments); ``srun
        --ntasks=N`` when the launcher is Slurm's srun."""
        if nprocs < 1:
            raise ConfigError(f"np = {nprocs}: need at least 1 MPI process (allowed range [1, inf))")
        cmd = [self.mpirun_path()]
        if Path(cmd[0]).name == "srun":
            # inside a Slurm allocation (ligwf slurm, launcher "srun --mpi=pmix"): srun has
            # its own rank option and no root switch
            return cmd + list(self.mpirun_args) + [f"--ntasks={nprocs}"]
        if os.geteuid() == 0:
            cmd.append("--allow-run-as-root")
        cmd += list(self.mpirun_args) + ["-np", str(nprocs)]
        return cmd

    def command(self, input_name: str, nprocs: int, log_name: str = "log.liggghts",
                extra: Sequence[str] = ()) -> list[str]:
        """Full command line running ``input_name`` in the case folder on ``nprocs`` ranks;
        ``extra``: further LIGGGHTS arguments (e.g. ``-var`` settings)."""
        return self.mpirun_prefix(nprocs) + [self.liggghts_path(), "-in", input_name,
                                             "-log", log_name, *extra]

    def version_line(self) -> str:
        """First output line of ``liggghts -h`` (which exits 1 by design)."""
        out = subprocess.run([self.liggghts_path(), "-h"], capture_output=True, text=True,
                             timeout=60, stdin=subprocess.DEVNULL)
        for line in (out.stdout + out.stderr).splitlines():
            if line.strip():
                return line.strip()
        raise EngineNotFound(f"{self.liggghts} -h printed nothing; is it LIGGGHTS?")
