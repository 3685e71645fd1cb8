"""Control twins of a wet case: the same bed without its cohesion (pure).

A granule or CG signal is only believed beside a control that should not have it
(``sweep.controls``). ``cohesionless``: the case's scene with surface tension and viscosity
/ :data:`COHESIONLESS_FACTOR`; ``flow_matched``: that twin with the particle friction and
rolling friction of :class:`FlowMatch`, so that it also flows like the wet bed
(``ligwf calibrate-control`` finds them, :mod:`ligwf.pipeline.calibrate`).
"""

from __future__ import annotations

from typing import Any

from pydantic import Field

from ligwf.errors import ConfigError
from ligwf.scene.model import Scene
from ligwf.scene.values import Frozen

#: factor on surface tension and viscosity of a cohesionless twin
COHESIONLESS_FACTOR = 1e-3


class FlowMatch(Frozen):
    """The non-cohesive knobs of a flow-matched control twin (``sweep.controls:
    [flow_matched]``): the cohesionless twin with these particle properties, chosen so that
    the dry bed flows like the wet one (``ligwf calibrate-control`` measures candidates)."""

    friction: float = Field(ge=0.0, le=10.0, description="sliding friction coefficient of "
                            "the twin's particles")
    rolling_friction: float = Field(0.0, ge=0.0, le=10.0, description="rolling friction "
                                    "coefficient of the twin's particles (model cdt)")


def control_scene(scene: Scene, control: str, flow_match: FlowMatch | None = None) -> Scene:
    """The scene of a control twin: ``cohesionless`` keeps everything (seeds, liquid
    content, contact dumps) but divides surface tension and viscosity by 1000, so bridges
    still form and are dumped, but hold nothing: the bed flows like a dry one
    (LIGGGHTS_NOTES: 32.2 deg against 32.3 dry and 40.2 wet on the demo bed).
    ``flow_matched`` is that twin with the particle friction and rolling friction of
    ``flow_match``: friction and rolling resistance raise a dry bed's angle towards the wet
    bed's without adding cohesion (a wet bed that slumps is not matched by them:
    LIGGGHTS_NOTES, 2026-12-02)."""
    if control not in ("cohesionless", "flow_matched"):
        raise ConfigError(f"sweep.controls: {control!r}: allowed: cohesionless, flow_matched")
    liquid = scene.liquid.model_copy(update={
        "surface_tension": scene.liquid.surface_tension * COHESIONLESS_FACTOR,
        "viscosity": scene.liquid.viscosity * COHESIONLESS_FACTOR})
    update: dict[str, Any] = {"liquid": liquid}
    if control == "flow_matched":
        if flow_match is None:
            raise ConfigError("sweep.controls: flow_matched needs sweep.flow_match")
        update["particles"] = scene.particles.model_copy(update={
            "friction": flow_match.friction, "rolling_friction": flow_match.rolling_friction})
    return scene.model_copy(update=update)
