"""Study-level analysis settings: the ``analysis:`` block of a workflow.

They decide what the post-processing computes (start-up cut, bond criterion, GSD binning
and bootstrap), so they belong to the study, not to a command line: they are validated
with the workflow, stored in the study folder, and every post-processing path (``ligwf
study``, ``ligwf analyse`` / ``report``, the Slurm analysis job) reads them from there.
A case folder without a study (run by hand) gets the defaults.

(The scene-level ``scene.analysis.granules`` is different: it switches the contact dumps
on in the LIGGGHTS input, so it is part of the scene and of its hash.)
"""

from __future__ import annotations

from typing import Any

from pydantic import Field, ValidationError

from ligwf.errors import ConfigError
from ligwf.scene.messages import format_validation_error
from ligwf.scene.model import _Frozen


class AnalysisSettings(_Frozen):
    """What the analysis of a study uses (defaults: the values ligwf always used)."""

    steady_after: float = Field(
        0.25, ge=0.0, lt=1.0, description="fraction of the production time left out as "
        "start-up, for the flow metrics and the GSD alike")
    min_bridge_force: float = Field(
        0.0, ge=0.0, allow_inf_nan=False, description="a liquid bond needs a bridge force "
        "above this, N (0: any unbroken bridge; CG-neutral)")
    max_velocity_angle: float = Field(
        30.0, ge=0.0, le=180.0, description="a liquid bond needs the partners' velocities "
        "within this angle, deg")
    bins_per_decade: int = Field(5, ge=1, le=100, description="GSD bins per decade of volume")
    min_particles: int = Field(
        10, ge=1, description="CG granules with fewer particles are below the size limit")
    bootstrap: int = Field(1000, ge=1, le=1_000_000, description="bootstrap draws of the "
                           "GSD confidence bands")
    seed: int = Field(12345, ge=0, description="seed of the bootstrap draws")


def build_analysis_settings(data: Any, prefix: str = "analysis") -> AnalysisSettings:
    """Validate a mapping (workflow block or stored record) or raise ConfigError with the
    field, the value and the allowed range."""
    if data is None:
        return AnalysisSettings()
    if not isinstance(data, dict):
        raise ConfigError(f"{prefix} = {data!r}: must be a mapping of analysis settings")
    try:
        return AnalysisSettings.model_validate(data)
    except ValidationError as exc:
        raise ConfigError("invalid analysis settings:\n"
                          + format_validation_error(exc, AnalysisSettings, prefix)) from None
