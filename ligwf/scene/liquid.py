"""The scene's liquid block: the binder liquid, its bridge model and where it starts.

Fields of ``scene.liquid`` (:class:`Liquid`, :class:`WetGranules`), checked when the scene
is built: the model's own limits (``ligwf.liquids``' ``validate``), the placement, and
washino's optional settings (``bridge_volume_fraction``, ``max_liquid_content``) against
the liquid the particles start with.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import AfterValidator, Field, model_validator

from ligwf import liquids
from ligwf.scene.values import MAX_LIQUID_CONTENT, PENDULAR_REASON, Frozen, zero_or_at_least



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
    bridge_volume_fraction: float | None = Field(
        None, gt=0.0, le=1.0, description="washino only: share of both particles' surface "
        "liquid that forms a bridge (LIGGGHTS lbVolumeFraction, written with modifyLbVolume "
        "on); unset: the engine default 0.05. A fraction: unchanged by CG scaling")
    max_liquid_content: float | None = Field(
        None, gt=0.0, le=MAX_LIQUID_CONTENT, description="washino only: cap of each "
        "particle's liquid content, liquid volume / solid volume (LIGGGHTS maxLiquidContent, "
        "written with limitLiquidContent on; the engine deletes liquid above it and sets "
        "maxSeparationDistanceRatio itself, so max_separation_ratio must stay unset); unset: "
        "no cap. Unchanged by CG scaling",
        json_schema_extra={"bound_reason": PENDULAR_REASON})

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
    def _cap_above_content(self) -> "Liquid":
        """A cap below the liquid a particle starts with deletes liquid at its first
        contact; and the engine replaces maxSeparationDistanceRatio when capping."""
        cap = self.max_liquid_content
        if cap is None:
            return self
        start = self.liquid_content if self.placement == "uniform" else max(
            self.liquid_content, self.wet_granules.liquid_content)  # type: ignore[union-attr]
        if cap < start:
            raise ValueError(f"max_liquid_content = {cap:g}: below the liquid content the "
                             f"particles start with ({start:g}), the engine would delete the "
                             f"rest at their first contact (allowed range [{start:g}, "
                             f"{MAX_LIQUID_CONTENT:g}])")
        if "max_separation_ratio" in self.model_fields_set:
            raise ValueError(f"max_separation_ratio = {self.max_separation_ratio:g}: with "
                             f"max_liquid_content = {cap:g} the engine sets "
                             "maxSeparationDistanceRatio itself (the rupture gap at the cap); "
                             "leave max_separation_ratio unset")
        return self

    @model_validator(mode="after")
    def _model_limits(self) -> "Liquid":
        problems = liquids.get(self.model).validate(self)
        if problems:
            raise ValueError("; ".join(problems))
        return self
