"""Study-level analysis settings: the ``analysis:`` block of a workflow.

They decide what the post-processing computes (start-up cut, bond criterion, GSD binning
and bootstrap), so they belong to the study, not to a command line: they are validated
with the workflow, stored in the study folder, and every post-processing path (``ligwf
study``, ``ligwf analyse`` / ``report``, the Slurm analysis job) reads them from there.
A case folder without a study (run by hand) gets the defaults.

(The scene-level ``scene.analysis.contact_dumps``, once also called ``granules``, is
different: it switches the contact dumps on in the LIGGGHTS input, so it is part of the
scene and of its hash.)
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, ValidationError, field_validator

from ligwf.errors import ConfigError
from ligwf.scene.messages import format_validation_error
from ligwf.scene.values import Frozen


#: largest seed: numpy's legacy generator (the compiled CPM optimiser's) takes 32 bits
MAX_SEED = 2**32 - 1


class AnalysisSettings(Frozen):
    """What the analysis of a study uses.

    The granule definition (``granules`` and the fields after it) defaults to ``held``:
    connected components of the liquid bridges present in every frame of
    [t, t + hold_time], hold_time 1 s (half a revolution at the regime map's 30 rpm). Of the
    candidates measured against a cohesionless twin (docs/results/granule_definitions.md)
    it is the only one whose granules respond to cohesion and not to mere contact: on the
    demo scene 28 % of the wet bed and none of the twin's, members moving together,
    deterministic. It does not pass every criterion (its granules wrap around a short
    periodic slice, and few survive a quarter revolution), and ``ligwf check`` says so.
    ``granules: communities`` (CPM communities of the rupture-work weighted bridge network,
    the earlier default) tiles a twin without cohesion as it tiles a wet bed;
    ``granules: components`` with ``max_velocity_angle: 30`` reproduces the source study
    (one bed-spanning cluster in a dense wet bed).
    """

    steady_after: float | Literal["auto"] = Field(
        "auto", description="start-up left out of the flow metrics and the GSD alike: auto "
        "(default: from the bed's measured spin-up, ligwf.analysis.flow.steady) or a fraction of "
        "the production time")
    granules: Literal["communities", "components", "held"] = Field(
        "held", description="granules are components of the bridges that held through "
        "hold_time (held, default: a body that stays together; the only definition that beat "
        "a cohesionless control), CPM communities of the bond graph, or its connected "
        "components (the source study)")
    hold_time: float = Field(
        1.0, gt=0.0, le=1e3, allow_inf_nan=False, description="granules: held: a bridge "
        "counts when it is present in every frame of [t, t + hold_time], s (a physical time: "
        "the same at every CG level; about half a revolution: the default 1 s is that at 30 "
        "rpm, the regime map's drum)")
    min_bridge_force: float = Field(
        0.0, ge=0.0, allow_inf_nan=False, description="a liquid bond needs a bridge force "
        "above this, N (0: any unbroken bridge; NOT CG-neutral when > 0)")
    min_relative_force: float = Field(
        0.0, ge=0.0, allow_inf_nan=False, description="a liquid bond needs F / (2 pi R* "
        "gamma cos theta) above this (the force over that of a touching bridge of the same "
        "pair: dimensionless, CG-neutral under every rule)")
    max_velocity_angle: float = Field(
        180.0, ge=0.0, le=180.0, description="a liquid bond needs the partners' velocities "
        "within this angle, deg (180: no angle test)")
    velocity_frame: Literal["lab", "drum", "flow"] = Field(
        "lab", description="velocities of the angle test: as dumped (lab), relative to the "
        "drum's rigid rotation (drum), or minus the local mean flow (flow)")
    flow_radius: float = Field(
        3.0, ge=0.1, le=50.0, description="radius of the local mean flow of velocity_frame "
        "flow, in mean particle diameters of the case")
    resolution: float = Field(
        0.002, ge=1e-9, le=100.0, allow_inf_nan=False, description="CPM resolution of "
        "the communities (edge weight w n^2, node weight n^3 at CG level n; the default "
        "0.002 is for the energy weight, the force weight's scale is ~3-5x larger: 0.01-0.02)")
    community_weight: Literal["energy", "force"] = Field(
        "energy", description="CPM edge weight w: the bridge's rupture work over F0 R* "
        "(energy, default: grows with the bridge volume, so granules respond to the liquid "
        "content) or its force over that of a touching bridge (force: the touching force does "
        "not depend on the liquid volume)")
    community_seed: int = Field(0, ge=0, le=MAX_SEED, description="seed of the CPM "
                                "optimiser's node order (the compiled optimiser seeds "
                                "numpy's generator, which takes [0, 2**32 - 1])")
    gsd_volume: Literal["physical", "primary"] = Field(
        "physical", description="granule volume the GSD bins: physical (a CG-neutral "
        "definition such as the CPM communities gives CG-n granules of CG1 size) or primary "
        "= volume / n^3 (the source study's estimate of the original GSD from CG-n components)")
    bins_per_decade: int = Field(5, ge=1, le=100, description="GSD bins per decade of volume")
    min_particles: int = Field(
        2, ge=1, description="granules with fewer particles are left out of the GSD and "
        "the kinetics (single particles are not granules)")
    error_band: float = Field(
        0.15, ge=1e-3, le=10.0, description="relative per-bin GSD error of CG-n against CG1 "
        "that locates the size limit")
    bootstrap: int = Field(1000, ge=1, le=1_000_000, description="bootstrap draws of the "
                           "GSD confidence bands")
    seed: int = Field(12345, ge=0, le=MAX_SEED, description="seed of the bootstrap draws")
    field_kernel: float = Field(
        2.0, ge=0.5, le=50.0, allow_inf_nan=False, description="standard deviation of the "
        "Gaussian kernel of the cross-section fields (solid fraction, velocity, granular "
        "temperature), in CG1 mean particle diameters: a physical length, the same at every "
        "CG level (ligwf.analysis.flow.fields)")
    surface_strip: float | None = Field(
        None, ge=0.0, le=1.0, allow_inf_nan=False, description="width of the strips the "
        "angle of repose's surface fit takes its points from, m: the angle's resolution. "
        "None: twice the largest mean particle diameter of the study's cases (its coarsest "
        "CG level), the same physical width at every level, so a CG-n - CG1 difference "
        "carries no difference of resolution; 0: twice each case's own diameter (the rule "
        "before 2026-12-07, whose resolution moved with the CG level)")
    sensitivity_frames: int = Field(
        4, ge=0, le=1000, description="steady frames of one case re-analysed with each "
        "threshold moved x0.8 / x1.25 (0: no sensitivity table)")


    @field_validator("steady_after", mode="before")
    @classmethod
    def _steady_after(cls, value):
        """``auto`` or a fraction in [0, 1) (one message with the allowed range)."""
        if value == "auto":
            return value
        if isinstance(value, str):
            raise ValueError("must be auto or a fraction of the production time in the "
                             "allowed range [0, 1), a number without quotes")
        try:
            fraction = float(value)
        except (TypeError, ValueError):
            fraction = float("nan")
        if isinstance(value, bool) or not 0.0 <= fraction < 1.0:
            raise ValueError("must be auto or a fraction of the production time in the "
                             "allowed range [0, 1)")
        return fraction

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
