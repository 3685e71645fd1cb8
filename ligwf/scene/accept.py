"""What "accurate enough" means for a study: the ``accept:`` block of a workflow.

A CG level (with its scaling rule) is accepted when every criterion of this block holds
for it against the CG1 cases of its sweep group (:mod:`ligwf.report.verdict` decides,
from the report's condition table). Each tolerance is in the unit of its metric; ``null``
leaves a criterion out of the budget. The defaults are what a demanding DEM user would
ask of a coarse-grained drum before trusting it in place of the original:

- ``angle_deg`` 1 deg: the dynamic angle of repose, the first thing a drum study is
  checked against, measured to about a degree in experiments;
- ``profile_error`` 0.10: relative L2 difference of the velocity profile along the depth
  of the bed (normalised depth), 10 %;
- ``rigid_share`` 0.05: the share of steady frames in which the bed turns as one rigid
  block (Bond scaling's failure mode: CG1 has none), at most 5 percentage points above
  CG1's;
- ``flowing_layer`` 0.15: the mean flowing-layer thickness within 15 % of CG1's;
- ``gsd_error`` 0.20: relative L1 difference of the volume-weighted granule size
  distribution over all its bins (``gsd_error_all``, no size limit); counted only where
  the granules beat their cohesionless control (otherwise the sizes measure the bed's
  tiling, not granules);
- ``field_error`` 0.10: the error of the coarse-grained continuum fields on the drum
  cross-section against CG1's (relative; "not measured" when the study has none).

The signed criteria (angle, rigid-block share, flowing layer) are held to +-tolerance
on the difference CG-n - CG1 by two one-sided tests; the CG1 noise floor never widens a
tolerance (it is reported as its own statement: is the difference distinguishable from
CG1 seed noise).
"""

from __future__ import annotations

from typing import Any

from pydantic import Field, ValidationError

from ligwf.errors import ConfigError
from ligwf.scene.messages import format_validation_error
from ligwf.scene.values import Frozen


class AcceptSettings(Frozen):
    """The error budget a CG level must meet (tolerances in each metric's unit; None: the
    criterion is not part of the budget)."""

    angle_deg: float | None = Field(
        1.0, ge=0.0, le=90.0, description="the angle of repose CG-n - CG1 within "
        "+-this, deg (two one-sided tests on the difference of run means)")
    profile_error: float | None = Field(
        0.10, ge=0.0, le=10.0, description="largest relative L2 error of the velocity "
        "profile against CG1 (noise-corrected; its upper bound within this)")
    rigid_share: float | None = Field(
        0.05, ge=0.0, le=1.0, description="the share of steady frames moving as a "
        "rigid block, CG-n - CG1, within +-this (a share of frames)")
    flowing_layer: float | None = Field(
        0.15, ge=0.0, le=10.0, description="the flowing-layer thickness CG-n / CG1 - 1 "
        "within +-this (relative)")
    gsd_error: float | None = Field(
        0.20, ge=0.0, le=10.0, description="largest relative L1 error of the volume-"
        "weighted GSD over all bins; assessed only where the granules beat their "
        "cohesionless control")
    field_error: float | None = Field(
        0.10, ge=0.0, le=10.0, description="largest error of the continuum fields on the "
        "drum cross-section against CG1 (not measured when the study has no field error)")


def build_accept_settings(data: Any, prefix: str = "accept") -> AcceptSettings:
    """Validate a mapping (the workflow block or the stored record) or raise ConfigError
    with the field, the value and the allowed range (``None``: the defaults)."""
    if data is None:
        return AcceptSettings()
    if not isinstance(data, dict):
        raise ConfigError(f"{prefix} = {data!r}: must be a mapping of tolerances "
                          "(angle_deg: 1.0, profile_error: 0.1, ...)")
    try:
        return AcceptSettings.model_validate(data)
    except ValidationError as exc:
        raise ConfigError("invalid accept block:\n"
                          + format_validation_error(exc, AcceptSettings, prefix)) from None
