"""The cores a local run may fill: an option, the Slurm allocation, or the CPU affinity.

Split from :mod:`ligwf.engine.plan` (which re-exports both functions): the one place the
rank planner reads the environment.
"""

from __future__ import annotations

import os
from typing import Mapping

from ligwf.errors import ConfigError


def at_least(field: str, value: object, lowest: int) -> int:
    """``value`` as a whole number >= ``lowest``; ConfigError naming the field otherwise
    (also the rank planner's check of its counts)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < lowest:
        raise ConfigError(f"{field} = {value!r}: must be a whole number (allowed range "
                          f"[{lowest}, inf))")
    return value


def available_cores(explicit: int | None, environ: Mapping[str, str],
                    affinity: int) -> tuple[int, str]:
    """Cores a local run may fill, and where the number came from: ``explicit`` (an
    option), else the tasks of the Slurm allocation this runs in (``SLURM_NTASKS``: the
    ranks ``mpirun`` may start there), else the CPUs this process may run on."""
    if explicit is not None:
        return at_least("--cores", explicit, 1), "--cores"
    if environ.get("SLURM_JOB_ID") and environ.get("SLURM_NTASKS"):
        text = environ["SLURM_NTASKS"]
        try:
            value = int(text)
        except ValueError:
            value = 0
        if value < 1:
            raise ConfigError(f"SLURM_NTASKS = {text!r}: must be a whole number (allowed "
                              "range [1, inf))")
        return value, "SLURM_NTASKS"
    return at_least("CPU affinity", affinity, 1), "CPUs this process may use"


def machine_cores(explicit: int | None = None) -> tuple[int, str]:
    """:func:`available_cores` of this process (reads the environment and CPU affinity)."""
    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:          # not on Linux
        affinity = os.cpu_count() or 1
    return available_cores(explicit, os.environ, affinity)

