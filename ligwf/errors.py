"""The small error hierarchy every ligwf stage raises from.

Catch :class:`LigwfError` to handle anything ligwf reports on purpose; the children say
which stage refused and why, so the CLI can print one clear line instead of a traceback.
"""

from __future__ import annotations


class LigwfError(Exception):
    """Base of every error ligwf raises deliberately."""


class ConfigError(LigwfError):
    """A workflow, scene or site setting is invalid (raised before anything is written)."""


class RenderError(LigwfError):
    """A LIGGGHTS input could not be rendered (template missing, unsafe value, ...)."""


class EngineNotFound(LigwfError):
    """The LIGGGHTS executable or mpirun configured for this site cannot be found."""


class SimulationFailed(LigwfError):
    """A LIGGGHTS run ended in error or was found unhealthy.

    Carries what a user needs to act on it without opening the log.
    """

    def __init__(self, message: str, *, exit_code: int | None = None, run_dir: str | None = None,
                 first_error: str | None = None, log_tail: str | None = None) -> None:
        super().__init__(message)
        self.exit_code = exit_code
        self.run_dir = run_dir
        self.first_error = first_error
        self.log_tail = log_tail


class SubmitError(LigwfError):
    """A scheduler (Slurm) refused or failed a submission."""


class DumpReadError(LigwfError):
    """A dump file is truncated, empty, corrupt or lacks an array the analysis needs."""
