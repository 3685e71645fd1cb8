"""Executors by name: the one place that turns ``local`` or ``slurm`` (``--executor NAME``)
into an :class:`ligwf.scheduler.Executor` (snakemake's executor plugins, picked by name, each
with a settings dataclass of its own).

Each :class:`ExecutorKind` names its frozen settings class, how the site's settings are read
(with command-line overrides), how the settings a study was submitted with are read back
from its folder (a resubmit, a follow-up job, ``cancel`` keep them) and how the executor is
built from settings. Nothing else in ligwf builds an executor by name:
:func:`build_executor` for new work, :func:`study_executor` for a study that already ran
on one. A new scheduler adds one entry to :data:`EXECUTORS` (docs/architecture.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Callable, Mapping

from ligwf.errors import ConfigError
from ligwf.scheduler import Executor

#: the executor that runs the cases on this machine (the default of every command)
LOCAL = "local"


@dataclass(frozen=True)
class ExecutorKind:
    """One executor known by name: ``settings``, its frozen settings class;
    ``site_settings(**overrides)``, the site's settings with the non-None overrides
    applied; ``recorded(study_dir)``, the settings ``study_dir`` was submitted with (the
    site's when it records none); ``build(settings)``, the executor; ``summary``, one line
    for the help."""

    name: str
    settings: type
    site_settings: Callable[..., Any]
    recorded: Callable[[Path], Any]
    build: Callable[[Any], Executor]
    summary: str


def _local_settings(**overrides: Any):
    from ligwf.local import run_settings

    return run_settings(**{k: v for k, v in overrides.items() if v is not None})


def _local(settings) -> Executor:
    from ligwf.local import LocalExecutor

    return LocalExecutor(settings)


def _slurm_settings(**overrides: Any):
    from ligwf.slurm.site import load_slurm_site

    return load_slurm_site().with_overrides(**overrides)


def _slurm_recorded(study_dir: Path):
    from ligwf.slurm.jobs import submitted_site

    return submitted_site(study_dir)


def _slurm(settings) -> Executor:
    from ligwf.slurm.scheduler import SlurmScheduler

    return SlurmScheduler(settings)


def _local_kind() -> ExecutorKind:
    from ligwf.local import RunSettings

    return ExecutorKind(LOCAL, RunSettings, _local_settings, lambda _: _local_settings(),
                        _local, "this machine or allocation, now")


def _slurm_kind() -> ExecutorKind:
    from ligwf.slurm.site import SlurmSite

    return ExecutorKind("slurm", SlurmSite, _slurm_settings, _slurm_recorded, _slurm,
                        "Slurm job arrays and a follow-up job, returning once submitted")


#: name -> how to make its entry (the entries import their executor on use: a local run
#: never loads the Slurm package)
EXECUTORS: Mapping[str, Callable[[], ExecutorKind]] = MappingProxyType(
    {LOCAL: _local_kind, "slurm": _slurm_kind})


def executor_kind(name: str, field: str = "--executor") -> ExecutorKind:
    """The entry named ``name``; ConfigError (one line naming ``field``, the value and the
    names allowed) for any other."""
    make = EXECUTORS.get(name)
    if make is None:
        raise ConfigError(f"{field} = {name!r}: no such executor (allowed: "
                          f"{', '.join(EXECUTORS)})")
    return make()


def build_executor(name: str, settings: Any = None, field: str = "--executor") -> Executor:
    """The executor ``name`` with ``settings`` (an instance of its settings class; None:
    the site's). A settings object of another executor is refused in one line."""
    kind = executor_kind(name, field)
    if settings is None:
        settings = kind.site_settings()
    elif not isinstance(settings, kind.settings):
        raise ConfigError(f"{field} = {name!r}: its settings are {kind.settings.__name__}, "
                          f"got {type(settings).__name__}")
    return kind.build(settings)


def study_executor(name: str, study_dir: Path, field: str = "--executor") -> Executor:
    """The executor ``name`` with the settings ``study_dir`` was submitted with (the
    site's when it records none)."""
    kind = executor_kind(name, field)
    return kind.build(kind.recorded(Path(study_dir)))
