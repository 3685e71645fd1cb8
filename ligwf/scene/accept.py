"""What "accurate enough" means for a study: the ``accept:`` block of a workflow.

A CG level (with its scaling rule) is accepted when every criterion of this block holds
for it against the CG1 cases of its sweep group (:mod:`ligwf.inference.verdict` decides,
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

Each tolerance is the budget key of one criterion of :mod:`ligwf.inference.registry`; a
criterion ligwf does not ship declares its own :class:`Budget`, which this block accepts
once the criterion is registered (:func:`register_budget`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from pydantic import ConfigDict, Field, ValidationError, model_validator

from ligwf.errors import ConfigError
from ligwf.scene.messages import format_validation_error
from ligwf.scene.values import Frozen


@dataclass(frozen=True)
class Budget:
    """The ``accept:`` field of a plug-in criterion: its key, its default tolerance (None:
    out of the budget unless set), the largest tolerance allowed and what it means."""

    key: str
    default: float | None
    upper: float
    description: str


#: the plug-in criteria's fields (the built-in ones are the fields of AcceptSettings)
PLUGIN_BUDGETS: dict[str, Budget] = {}


def register_budget(budget: Budget, remove: bool = False) -> None:
    """Accept a plug-in criterion's tolerance in the block (``remove``: no longer);
    :func:`ligwf.inference.registry.register` calls it."""
    if remove:
        PLUGIN_BUDGETS.pop(budget.key, None)
    elif budget.key in AcceptSettings.model_fields or budget.key in PLUGIN_BUDGETS:
        raise ValueError(f"accept: {budget.key!r} is a budget key already")
    else:
        PLUGIN_BUDGETS[budget.key] = budget


def _tolerance(key: str, value: Any, budget: Budget) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(
            value) or not 0.0 <= value <= budget.upper:
        raise ValueError(f"{key} = {value!r}: must be a number in [0, {budget.upper:g}] "
                         f"or null ({budget.description})")
    return float(value)


class AcceptSettings(Frozen):
    """The error budget a CG level must meet (tolerances in each metric's unit; None: the
    criterion is not part of the budget). A plug-in criterion registered with ligwf.inference.registry
    adds its own key; any other key is refused."""

    model_config = ConfigDict(**{**Frozen.model_config, "extra": "allow"},
                              json_schema_extra={"additionalProperties": False})

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

    @model_validator(mode="before")
    @classmethod
    def _plugin_budgets(cls, data: Any) -> Any:
        """Plug-in tolerances: validated against their Budget, defaults filled in; a key
        that is neither a field nor a registered plug-in's is refused (a typo)."""
        if not isinstance(data, dict):
            return data
        out = dict(data)
        for key, value in data.items():
            if key in cls.model_fields:
                continue
            if key not in PLUGIN_BUDGETS:
                known = ", ".join([*cls.model_fields, *PLUGIN_BUDGETS])
                raise ValueError(f"{key}: unknown key (typo?); the budget keys: {known}")
            out[key] = _tolerance(key, value, PLUGIN_BUDGETS[key])
        for key, budget in PLUGIN_BUDGETS.items():
            out.setdefault(key, budget.default)
        return out

    def tolerance(self, key: str) -> float | None:
        """The tolerance of budget key ``key`` (a field, or a plug-in's; None: not in the
        budget)."""
        if key in type(self).model_fields:
            return getattr(self, key)
        extra = self.model_extra or {}
        if key in extra:
            return extra[key]
        budget = PLUGIN_BUDGETS.get(key)
        return budget.default if budget is not None else None


def build_accept_settings(data: Any, prefix: str = "accept") -> AcceptSettings:
    """Validate a mapping (the workflow block or the stored record) or raise ConfigError
    with the field, the value and the allowed range (``None``: the defaults)."""
    if data is None:
        return AcceptSettings()
    if not isinstance(data, dict):
        raise ConfigError(f"{prefix} = {data!r}: must be a mapping of tolerances "
                          "(angle_deg: 1.0, profile_error: 0.1, ...)")
    unknown = [k for k in data if k not in AcceptSettings.model_fields
               and k not in PLUGIN_BUDGETS]
    if unknown:
        raise ConfigError("invalid accept block:\n" + "\n".join(
            f"{prefix}.{k}: unknown key (typo?)" for k in unknown))
    try:
        return AcceptSettings.model_validate(data)
    except ValidationError as exc:
        raise ConfigError("invalid accept block:\n"
                          + format_validation_error(exc, AcceptSettings, prefix)) from None
