"""Where the engine is and how to launch it: site settings, never hard-coded paths.

The LIGGGHTS executable and the MPI launcher come from environment variables
(``LIGWF_LIGGGHTS``, ``LIGWF_MPIRUN``, ``LIGWF_MPIRUN_ARGS``), else from a site file
(``$LIGWF_SITE`` or ``~/.config/ligwf/site.yaml``, keys ``liggghts``, ``mpirun``,
``mpirun_args``), else ``liggghts`` and ``mpirun`` on the PATH. OpenMPI refuses to run as
root unless told so: ``--allow-run-as-root`` is added only when running as root.

One setting names the engine for every launch path: the ``--np`` path runs the executable,
the ensemble path loads the shared library THAT executable links to (found with ``ldd``,
so ``LD_LIBRARY_PATH`` and the executable's RUNPATH count as they do for the executable).
:meth:`EngineConfig.identify` resolves both and the version line before anything is written
(:class:`EngineIdentity`); the old separate library setting (``LIGWF_LIBLIGGGHTS``, site key
``libliggghts``) is refused, so no run silently uses another engine than the one named.
"""

from __future__ import annotations

import functools
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ligwf.errors import ConfigError, EngineNotFound
from ligwf.study.layout import ENGINE_LOG
from ligwf.yamlio import read_yaml_mapping


def _site_file() -> Path:
    env = os.environ.get("LIGWF_SITE")
    if env:
        return Path(env)
    return Path(os.environ.get("XDG_CONFIG_HOME", Path.home() / ".config")) / "ligwf" / "site.yaml"


#: what a site file may set (anything else is a typo that would be ignored silently)
SITE_KEYS = ("liggghts", "mpirun", "mpirun_args", "slurm")

#: the retired separate library setting: refused, it could name another engine than ``liggghts``
RETIRED_LIBRARY = ("the library is the one the liggghts executable links to (LIGWF_LIGGGHTS / "
                   "site key liggghts names both); remove it")


def load_site() -> dict:
    """The site YAML as a mapping ({} when there is none); unknown keys are refused."""
    path = _site_file()
    site = read_yaml_mapping(path, "site file") if path.exists() else {}
    if "libliggghts" in site:
        raise ConfigError(f"site file {path}: libliggghts = {site['libliggghts']!r} is no "
                          f"longer read: {RETIRED_LIBRARY}")
    unknown = sorted(set(site) - set(SITE_KEYS))
    if unknown:
        raise ConfigError(f"site file {path}: unknown key(s) {', '.join(unknown)} (typo?; "
                          f"allowed: {', '.join(SITE_KEYS)})")
    for key in ("liggghts", "mpirun"):
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
        if "LIGWF_LIBLIGGGHTS" in os.environ:
            raise ConfigError(f"LIGWF_LIBLIGGGHTS = {os.environ['LIGWF_LIBLIGGGHTS']!r} is no "
                              f"longer read: {RETIRED_LIBRARY}")
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

    def command(self, input_name: str, nprocs: int, log_name: str = ENGINE_LOG,
                extra: Sequence[str] = ()) -> list[str]:
        """Full command line running ``input_name`` in the case folder on ``nprocs`` ranks;
        ``extra``: further LIGGGHTS arguments (e.g. ``-var`` settings)."""
        return self.mpirun_prefix(nprocs) + [self.liggghts_path(), "-in", input_name,
                                             "-log", log_name, *extra]

    def identify(self) -> "EngineIdentity":
        """The engine every launch path runs: executable, the library it links to (the
        ensembles load that one) and its version line. EngineNotFound, naming the setting,
        when any of them cannot be found or loaded (before a caller writes anything)."""
        return _identify(self.liggghts_path(), os.environ.get("LD_LIBRARY_PATH", ""))


@dataclass(frozen=True)
class EngineIdentity:
    """Which engine runs: the executable (``--np`` path), the shared library it links to
    (loaded by the ensemble path) and the version line of ``liggghts -h``. Recorded in
    every manifest and printed by ``ligwf check`` / ``run``."""

    executable: str
    library: str
    version: str

    def describe(self) -> str:
        """One line for the terminal."""
        return f"engine: {self.version} -- {self.executable}, library {self.library}"

    def to_dict(self) -> dict[str, str]:
        return {"executable": self.executable, "library": self.library, "version": self.version}

    @classmethod
    def from_dict(cls, data: dict) -> "EngineIdentity":
        return cls(str(data["executable"]), str(data["library"]), str(data["version"]))


_LDD_RE = re.compile(r"^\s*(libliggghts[^\s]*)\s*=>\s*(.*?)\s*(\(0x[0-9a-f]+\))?\s*$")


def linked_library(executable: str) -> str:
    """The libliggghts file the dynamic loader gives ``executable`` (``ldd``, resolved to
    the real file). EngineNotFound when it has none (a static build or a wrapper script:
    the ensembles could only load another engine) or the loader cannot find it."""
    try:
        with open(executable, "rb") as fh:
            elf = fh.read(4) == b"\x7fELF"
    except OSError as exc:
        raise EngineNotFound(f"LIGGGHTS executable {executable} cannot be read: "
                             f"{exc.strerror}") from None
    if not elf:
        raise EngineNotFound(f"LIGGGHTS executable {executable} is not a program file (a "
                             "wrapper script?): ligwf cannot tell which libliggghts its "
                             "ensembles must load; set LIGWF_LIGGGHTS to the executable itself")
    try:
        out = subprocess.run(["ldd", executable], capture_output=True, text=True, timeout=60,
                             stdin=subprocess.DEVNULL)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise EngineNotFound(f"cannot run ldd on the LIGGGHTS executable {executable} ({exc}); "
                             "install libc-bin") from None
    if out.returncode:
        said = (out.stderr.strip().splitlines() or ["nothing said"])[-1]
        raise EngineNotFound(f"LIGGGHTS executable {executable} cannot be loaded (ldd exit "
                             f"{out.returncode}: {said}): a library it needs is missing or "
                             "damaged (LD_LIBRARY_PATH?)")
    for line in out.stdout.splitlines():
        m = _LDD_RE.match(line)
        if m:
            where = m.group(2)
            if not where or where == "not found":
                raise EngineNotFound(f"LIGGGHTS executable {executable} links to {m.group(1)}, "
                                     "which the dynamic loader cannot find (LD_LIBRARY_PATH?)")
            return os.path.realpath(where)
    raise EngineNotFound(f"LIGGGHTS executable {executable} does not link to a libliggghts "
                         "shared library (a static build or a wrapper script?): ligwf's "
                         "ensembles load the engine as that library; set LIGWF_LIGGGHTS to an "
                         "executable built with the shared library (the Debian package is)")


#: run in a fresh interpreter: loads the library the ensembles will load, checks its C API
_LOAD_PROBE = ("import ctypes, sys\nlib = ctypes.CDLL(sys.argv[1])\n"
               "for name in ('lammps_open', 'lammps_file', 'lammps_command', 'lammps_close'):\n"
               "    getattr(lib, name)\n")


def _check_loadable(library: str, executable: str) -> None:
    """Load ``library`` in a separate process (as an ensemble rank will) and look up the
    LAMMPS C API; EngineNotFound with the loader's own words when it cannot."""
    try:
        out = subprocess.run([sys.executable, "-I", "-c", _LOAD_PROBE, library],
                             capture_output=True, text=True, timeout=120,
                             stdin=subprocess.DEVNULL)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise EngineNotFound(f"cannot load {library} (of {executable}): {exc}") from None
    if out.returncode:
        last = (out.stderr.strip().splitlines() or ["no message"])[-1]
        raise EngineNotFound(f"library {library} of LIGGGHTS executable {executable} cannot be "
                             f"loaded as the engine: {last}")


def _version_line(executable: str) -> str:
    """(``-log none`` and a throw-away working folder: ``liggghts -h`` alone writes a
    log.liggghts into the current folder)"""
    try:
        with tempfile.TemporaryDirectory(prefix="ligwf-version-") as scratch:
            out = subprocess.run([executable, "-log", "none", "-h"], capture_output=True,
                                 text=True, timeout=60, stdin=subprocess.DEVNULL,
                                 errors="replace", cwd=scratch)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise EngineNotFound(f"LIGGGHTS executable {executable} cannot be started: "
                             f"{exc}") from None
    for line in (out.stdout + out.stderr).splitlines():
        if line.strip():
            if not line.strip().startswith("LIGGGHTS"):
                break
            return line.strip()
    raise EngineNotFound(f"{executable} -h does not print a LIGGGHTS version line; is it "
                         "LIGGGHTS?")


@functools.lru_cache(maxsize=8)
def _identify(executable: str, ld_library_path: str) -> EngineIdentity:
    """(cached per executable and loader path: a planned run identifies once per phase)"""
    library = linked_library(executable)
    _check_loadable(library, executable)
    return EngineIdentity(executable, library, _version_line(executable))
