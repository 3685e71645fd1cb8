"""Slurm site settings: partition, account, wall time, module loads, launcher, ligwf command.

Read like the engine settings (:mod:`ligwf.engine.site`): command-line values win, then
environment variables ``LIGWF_SLURM_*``, then the ``slurm:`` mapping of the site YAML
(``$LIGWF_SITE`` or ``~/.config/ligwf/site.yaml``), then the defaults below::

    slurm:
      partition: compute
      account: proj123
      time: "02:00:00"          # per array task
      ntasks: 4                 # MPI ranks per case (unset: the rank plan decides)
      cores_per_node: 64        # cores of one node: a planned case asks for
                                # --nodes = ceil(ranks / cores_per_node); unset: Slurm places
      max_concurrent: 8         # the %K of --array=0-M%K
      modules: [openmpi/4.1, liggghts/3.8.0]
      setup: ["source /opt/ligwf/venv/bin/activate"]
      launcher: srun --mpi=pmix # how the engine starts inside the allocation; unset = the
                                # engine settings (LIGWF_MPIRUN / site 'mpirun', default mpirun)
      ligwf: /opt/ligwf/venv/bin/ligwf
      sbatch_args: ["--mem-per-cpu=2G"]
      analysis_time: "00:30:00"

Every value ends up in a batch script, so each is checked against a narrow pattern here:
a newline or ``;`` in a partition name must be a clear error, not a shell command.
"""

from __future__ import annotations

import os
import re
import shlex
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Mapping

from ligwf.engine.site import load_site
from ligwf.errors import ConfigError

_NAME = re.compile(r"^[A-Za-z0-9_.,+-]+$")
_MODULE = re.compile(r"^[A-Za-z0-9_./+-]+$")
#: Slurm --time: M, M:S, H:M:S, D-H, D-H:M, D-H:M:S (read by ligwf.slurm.walltime)
SLURM_TIME = re.compile(r"^(\d+|\d+:\d{1,2}|\d+:\d{1,2}:\d{1,2}|\d+-\d{1,2}(:\d{1,2}){0,2})$")
_UNSAFE = re.compile(r"[\n\r\x00]")
#: longest wall time accepted (a longer one is a typo: Slurm sites cap far below a year)
MAX_TIME_DAYS = 365


def slurm_time_problem(value: str) -> str | None:
    """Why ``value`` is not a Slurm ``--time`` ligwf accepts (None: it is): the forms of
    :data:`SLURM_TIME`, seconds and minutes after a colon below 60, hours after a day
    count below 24, at most :data:`MAX_TIME_DAYS` days in all."""
    forms = "minutes, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS"
    if not SLURM_TIME.match(value):
        return f"not a Slurm time ({forms})"
    days, _, clock = value.rpartition("-")
    parts = [int(p) for p in clock.split(":")]
    if days:                                    # D-H, D-H:M, D-H:M:S
        limits = [24, 60, 60][:len(parts)]
    else:                                       # M, M:S, H:M:S: the first field is open
        limits = [None, 60, 60][3 - len(parts):] if len(parts) > 1 else [None]
    for part, limit in zip(parts, limits):
        if limit is not None and part >= limit:
            return f"a field is {part}, allowed range [0, {limit - 1}] ({forms})"
    units = [3600, 60, 1] if days or len(parts) == 3 else [60, 1] if len(parts) == 2 else [60]
    total = int(days or 0) * 86400 + sum(p * u for p, u in zip(parts, units))
    if total > MAX_TIME_DAYS * 86400:
        return f"longer than {MAX_TIME_DAYS} days (allowed up to {MAX_TIME_DAYS}-00:00:00)"
    return None

ENV_PREFIX = "LIGWF_SLURM_"
KEYS = ("partition", "account", "time", "ntasks", "max_concurrent", "modules", "setup",
        "launcher", "ligwf", "sbatch_args", "analysis_time", "cores_per_node")


def default_ligwf_command() -> str:
    """The ``ligwf`` next to the running interpreter (the venv the user submitted from).

    Batch jobs start with a login-like environment where ``ligwf`` may not be on the PATH
    or may be another installation, so the script calls it by absolute path.
    """
    candidate = Path(sys.executable).parent / "ligwf"
    return str(candidate) if candidate.is_file() else "ligwf"


@dataclass(frozen=True)
class SlurmSite:
    """Resolved Slurm settings for one submission (validated, safe to put in a script)."""

    partition: str | None = None
    account: str | None = None
    time: str | None = None
    ntasks: int = 1
    max_concurrent: int | None = None
    modules: tuple[str, ...] = ()
    setup: tuple[str, ...] = ()
    launcher: str | None = None
    ligwf: str = "ligwf"
    sbatch_args: tuple[str, ...] = ()
    analysis_time: str | None = None
    cores_per_node: int | None = None   # None: unknown, no --nodes in the scripts

    def __post_init__(self) -> None:
        for key in ("partition", "account"):
            value = getattr(self, key)
            if value is not None and not _NAME.match(value):
                raise ConfigError(f"slurm {key} = {value!r}: only letters, digits and _.,+- "
                                  "are allowed")
        for key in ("time", "analysis_time"):
            value = getattr(self, key)
            why = slurm_time_problem(value) if value is not None else None
            if why is not None:
                raise ConfigError(f"slurm {key} = {value!r}: {why}")
        if self.ntasks < 1:
            raise ConfigError(f"slurm ntasks = {self.ntasks}: allowed range [1, inf)")
        if self.max_concurrent is not None and self.max_concurrent < 1:
            raise ConfigError(f"slurm max_concurrent = {self.max_concurrent}: allowed range "
                              "[1, inf)")
        if self.cores_per_node is not None and self.cores_per_node < 1:
            raise ConfigError(f"slurm cores_per_node = {self.cores_per_node}: allowed range "
                              "[1, inf)")
        for mod in self.modules:
            if not _MODULE.match(mod):
                raise ConfigError(f"slurm module {mod!r}: only letters, digits and _./+- "
                                  "are allowed")
        for key in ("setup", "sbatch_args"):
            for line in getattr(self, key):
                if _UNSAFE.search(line):
                    raise ConfigError(f"slurm {key} entry {line!r}: contains a line break")
        for arg in self.sbatch_args:
            if not arg.startswith("--"):
                raise ConfigError(f"slurm sbatch_args entry {arg!r}: must be a long option "
                                  "such as --mem=4G")
        if self.launcher is not None and (not self.launcher.strip()
                                          or _UNSAFE.search(self.launcher)):
            raise ConfigError(f"slurm launcher = {self.launcher!r}: must be one command line")
        if not self.ligwf.strip() or _UNSAFE.search(self.ligwf):
            raise ConfigError(f"slurm ligwf = {self.ligwf!r}: must be one command line")

    def with_overrides(self, **overrides: Any) -> "SlurmSite":
        """A copy with the non-None overrides (the command-line values) applied."""
        return replace(self, **{k: v for k, v in overrides.items() if v is not None})


def _as_tuple(value: Any, key: str, split_text: bool) -> tuple[str, ...]:
    if value is None:
        return ()
    if isinstance(value, str):
        if split_text:
            return tuple(v for v in re.split(r"[,\s]+", value) if v)
        return (value,)
    if isinstance(value, (list, tuple)):
        return tuple(str(v) for v in value)
    raise ConfigError(f"slurm {key} = {value!r}: expected a list of strings")


def _as_int(value: Any, key: str) -> int | None:
    if value is None or value == "":
        return None
    try:
        return int(value)
    except (TypeError, ValueError):
        raise ConfigError(f"slurm {key} = {value!r}: expected a whole number (allowed "
                          "range [1, inf))") from None


def site_from_mapping(values: Mapping[str, Any]) -> SlurmSite:
    """Build and validate :class:`SlurmSite` from a plain mapping (pure)."""
    unknown = set(values) - set(KEYS)
    if unknown:
        raise ConfigError(f"slurm site settings: unknown key(s) {', '.join(sorted(unknown))} "
                          f"(allowed: {', '.join(KEYS)})")
    kwargs: dict[str, Any] = {}
    for key in ("partition", "account", "time", "launcher", "ligwf", "analysis_time"):
        if values.get(key) not in (None, ""):
            kwargs[key] = str(values[key])
    for key in ("ntasks", "max_concurrent", "cores_per_node"):
        number = _as_int(values.get(key), key)
        if number is not None:
            kwargs[key] = number
    if "modules" in values:
        kwargs["modules"] = _as_tuple(values["modules"], "modules", split_text=True)
    if "setup" in values:
        kwargs["setup"] = _as_tuple(values["setup"], "setup", split_text=False)
    if "sbatch_args" in values:
        raw = values["sbatch_args"]
        try:
            kwargs["sbatch_args"] = (tuple(shlex.split(raw)) if isinstance(raw, str)
                                     else _as_tuple(raw, "sbatch_args", split_text=False))
        except ValueError as exc:     # an unclosed quote: "No closing quotation"
            raise ConfigError(f"slurm sbatch_args = {raw!r}: not a valid argument list "
                              f"({str(exc).lower()}); quote as in a shell") from None
    kwargs.setdefault("ligwf", default_ligwf_command())
    return SlurmSite(**kwargs)


def merged_settings(site_yaml: Mapping[str, Any], environ: Mapping[str, str]) -> dict[str, Any]:
    """The ``slurm:`` block of the site file, overridden by ``LIGWF_SLURM_*`` variables."""
    block = site_yaml.get("slurm") or {}
    if not isinstance(block, dict):
        raise ConfigError("site file: 'slurm' must be a mapping")
    merged: dict[str, Any] = dict(block)
    for key in KEYS:
        env = environ.get(ENV_PREFIX + key.upper())
        if env is not None:
            merged[key] = env
    return merged


def ntasks_configured(environ: Mapping[str, str] | None = None) -> bool:
    """Whether the site file or ``LIGWF_SLURM_NTASKS`` sets ``ntasks``: then, like
    ``--ntasks``, it overrides the rank plan (every case on that many ranks)."""
    env = os.environ if environ is None else environ
    return merged_settings(load_site(), env).get("ntasks") not in (None, "")


def load_slurm_site(environ: Mapping[str, str] | None = None) -> SlurmSite:
    """Site settings from the environment and the site YAML (no command-line values yet)."""
    env = os.environ if environ is None else environ
    return site_from_mapping(merged_settings(load_site(), env))
