"""The scene's liquid block: the binder liquid, its bridge model and where it starts.

Fields of ``scene.liquid`` (:class:`Liquid`, :class:`WetGranules`), checked when the scene
is built: the placement, the model's own limits (``ligwf.liquids``' ``validate``) and the
model's own settings. Those are keys of the same ``liquid:`` block that only one model
has (washino's ``bridge_volume_fraction``, ...): the model declares them as a frozen class
(its ``settings_type``), this block validates them with it, refusing each in one line
(field, value, allowed range) like its own fields, and carries them as one opaque value,
``Liquid.settings``, to scaling and on to the model's law. A key of another model's
settings is refused (left at null it is ignored, as older scene records write it).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import (AfterValidator, Field, SerializerFunctionWrapHandler, ValidationError,
                      model_serializer, model_validator)
from pydantic.json_schema import SkipJsonSchema
from pydantic_core import InitErrorDetails, PydanticCustomError

from ligwf import liquids
from ligwf.liquids.base import MAX_LIQUID_CONTENT, PENDULAR_REASON, LiquidSettings
from ligwf.scene.messages import range_note
from ligwf.scene.values import Frozen, scalar_problem, zero_or_at_least



def refusal(field: str, value: Any, reason: str) -> InitErrorDetails:
    """One line of a refusal of ``liquid.<field>`` (``field = value: reason``)."""
    return InitErrorDetails(type=PydanticCustomError("liquid_setting", "{reason}",
                                                     {"reason": reason}),
                            loc=(field,), input=value)


def check_liquid_model(name: str) -> str:
    """Refuse a name no liquid model is registered under (the error lists the allowed)."""
    liquids.get(name)
    return name


class WetGranules(Frozen):
    """Pre-formed wet granules in a dry bed (``liquid.placement: granules``): after the
    fill, every particle is dried and those whose centres lie in one of ``count`` spheres
    of ``radius`` get ``liquid_content``; the spheres sit in the settled bed (half-way
    between its free surface and the shell, spread across it, in the middle of the slice).
    The granule size is physical (m), the same at every CG level. The engine moves liquid
    to dry partners when a bridge ruptures, so the granules also wet the bed around them
    (accretion) -- measured in docs/results/granule_definitions.md."""

    count: int = Field(3, ge=1, le=100, description="wet spheres")
    radius: float = Field(gt=0.0, le=1.0, description="m, radius of each wet sphere")
    liquid_content: float = Field(
        0.05, ge=1e-5, le=MAX_LIQUID_CONTENT, description="liquid volume / solid volume "
        "inside the spheres", json_schema_extra={"bound_reason": PENDULAR_REASON})


class Liquid(Frozen):
    """The binder liquid and its bridge model (a name of :mod:`ligwf.liquids`' registry).

    ``liquid_content`` is the liquid volume as a FRACTION of each particle's solid volume
    (LIGGGHTS' ``surfaceLiquidContentInitial``; the engine source uses a fraction although
    its docs say %). Model-specific limits are the model's own (``validate``).
    """

    model: Annotated[str, AfterValidator(check_liquid_model)] = Field(
        "none", description="liquid-bridge model (ligwf.liquids: none is a dry bed)")
    surface_tension: Annotated[float, zero_or_at_least(1e-6, 1e4, "N/m")] = Field(
        0.072, ge=0.0, le=1e4, description="N/m (0: no cohesion)")
    contact_angle_deg: float = Field(30.0, ge=0.0, le=180.0, description="degrees")
    viscosity: Annotated[float, zero_or_at_least(1e-9, 1e6, "Pa s")] = Field(
        1e-3, ge=0.0, le=1e6, description="Pa s (0: no viscous force)")
    liquid_content: float = Field(
        0.02, ge=1e-5, le=MAX_LIQUID_CONTENT, description="liquid volume / solid volume",
        json_schema_extra={"bound_reason": PENDULAR_REASON})
    min_separation_ratio: float = Field(
        1.01, gt=0.0, le=10.0, description="minSeparationDistanceRatio: the surface gap over "
        "R* = r_i r_j / (r_i + r_j) below which the engine's viscous force stops growing "
        "(normal 6 pi mu R* v_n / max(s, gap / R*)); >= 1: Stokes drag / s at every bridged "
        "gap, lubrication off (the default); a few 1e-2: lubrication (Shi & McCarthy 2008); "
        "0: the engine divides by zero. Unchanged by CG scaling",
        json_schema_extra={"bound_reason": "the engine divides the viscous force by it (0 "
                           "gives nan, then an internal error); above 10 it is Stokes drag "
                           "divided by more than 10, a viscous force switched off"})
    max_separation_ratio: float = Field(1.1, ge=1.0, le=10.0,
                                        description="maxSeparationDistanceRatio: centre "
                                        "distance over r_i + r_j at which the engine cuts a "
                                        "bridge")
    placement: Literal["uniform", "granules"] = Field(
        "uniform", description="uniform: every particle starts with liquid_content; "
        "granules: a dry bed with pre-formed wet granules (wet_granules)")
    wet_granules: WetGranules | None = Field(None, description="the wet granules of "
                                             "placement: granules")
    settings: SkipJsonSchema[LiquidSettings] = Field(
        default_factory=LiquidSettings, exclude=True, description="the model's own settings "
        "(its settings_type), given as keys of this block")

    @model_validator(mode="before")
    @classmethod
    def _own_settings(cls, data: Any) -> Any:
        """Validate the model's own keys with its settings class into ``settings``."""
        if not isinstance(data, dict) or isinstance(data.get("settings"), LiquidSettings):
            return data
        data, problems = dict(data), []
        if "settings" in data:          # given as its keys, never as a mapping of its own
            problems.append(InitErrorDetails(type="extra_forbidden", loc=("settings",),
                                             input=data.pop("settings")))
        name = data.get("model", cls.model_fields["model"].default)
        law = liquids.get(name) if name in liquids.names() else None  # else: model refuses
        own_type = law.settings_type if law is not None else LiquidSettings
        own, owners = {}, liquids.setting_owners()
        for key in [k for k in data if k not in cls.model_fields]:
            if key in own_type.model_fields:
                own[key] = data.pop(key)
                item = scalar_problem(own[key], own_type.model_fields[key].annotation)
                if item is not None:
                    problems.append(refusal(key, own[key], str(item) + range_note(
                        own_type, (key,), str(item), "value_error")))
            elif key in owners:
                value = data.pop(key)
                if value is not None and law is not None:
                    problems.append(refusal(key, value, (
                        f"liquid model {name!r} has no such setting (only "
                        f"{', '.join(owners[key])} has it); leave it unset")))
        if not problems:
            try:
                data["settings"] = own_type.model_validate(own)
            except ValidationError as exc:
                problems = [refusal(e["loc"][0], e["input"], e["msg"] + range_note(
                    own_type, e["loc"], e["msg"], e["type"])) for e in exc.errors()]
        if problems:
            raise ValidationError.from_exception_data(cls.__name__, problems)
        return data

    @model_serializer(mode="wrap")
    def _flat(self, handler: SerializerFunctionWrapHandler, info: Any) -> dict[str, Any]:
        """The block as the workflow writes it: the model's own keys beside the others."""
        return {**handler(self), **self.settings.model_dump(mode=info.mode)}

    @property
    def start_content(self) -> float:
        """The largest liquid content a particle starts with (placed granules included)."""
        if self.placement == "granules" and self.wet_granules is not None:
            return max(self.liquid_content, self.wet_granules.liquid_content)
        return self.liquid_content

    @property
    def changed_fields(self) -> frozenset[str]:
        """The keys set to a value other than their default (a scene record writes every
        key: read back, those at their defaults are still unchanged)."""
        return frozenset(k for k in self.model_fields_set
                         if getattr(self, k) != type(self).model_fields[k].get_default(
                             call_default_factory=True))

    @property
    def wet(self) -> bool:
        return liquids.get(self.model).wet

    @model_validator(mode="after")
    def _placement(self) -> "Liquid":
        if self.placement == "granules" and self.wet_granules is None:
            raise ValueError("placement granules needs wet_granules: {count, radius, "
                             "liquid_content}")
        if self.placement == "granules" and not liquids.get(self.model).wet:
            raise ValueError(f"placement granules with liquid.model {self.model!r} (a dry "
                             "bed): the wet granules would be dropped; choose a wet model "
                             f"({', '.join(n for n in liquids.names() if liquids.get(n).wet)})")
        if self.placement == "uniform" and self.wet_granules is not None:
            raise ValueError("wet_granules is set but placement is uniform (set placement: "
                             "granules, or drop wet_granules)")
        return self

    @model_validator(mode="after")
    def _model_limits(self) -> "Liquid":
        problems = liquids.get(self.model).validate(self)
        if problems:
            raise ValueError("; ".join(problems))
        own = self.settings.problems(self)
        if own:
            raise ValidationError.from_exception_data(
                type(self).__name__, [refusal(*problem) for problem in own])
        return self
