"""The built-in criteria of the verdict's budget, registered in the order "fails first"
and the tables follow (:mod:`ligwf.inference.registry`: what each field means). A reader of
the registry asks :func:`criteria`, which sees these and every plug-in registered since.
"""

from __future__ import annotations

from ligwf.inference.analysis_errors import decide_error, decide_field
from ligwf.inference.deciding import field_plan, profile_plan, signed_plan
from ligwf.inference.profile import decide_profile
from ligwf.inference.registry import (DIFFERENCES, ERROR, PROFILE, RELATIVE, SIGNED, Criterion,
                                      register, registered)
from ligwf.inference.signed import decide_signed

BUILT_IN = (
    Criterion("angle_deg", "angle of repose", "deg", "angle_of_repose", SIGNED,
              decide_signed, signed_plan),
    Criterion("profile_error", "velocity profile", "", "profile_error", PROFILE,
              decide_profile, profile_plan),
    Criterion("rigid_share", "rigid-block frames", "", "rigid_frame_share", SIGNED,
              decide_signed, signed_plan, share=True),
    Criterion("flowing_layer", "flowing layer", "", "flowing_layer_thickness_mean", RELATIVE,
              decide_signed, signed_plan),
    Criterion("gsd_error", "GSD", "", "gsd_error_all", ERROR, decide_error, gated=True),
    Criterion("field_error", "continuum fields", "", "field_error", ERROR, decide_field,
              field_plan),
)
for _criterion in BUILT_IN:
    register(_criterion)


def criteria() -> tuple[Criterion, ...]:
    """Every criterion of the budget: the built-in ones, then the plug-ins registered."""
    return registered()


def signed_columns() -> tuple[str, ...]:
    """The case-table columns the signed criteria read (their runs' noise costs a
    decision, and they are what a sweep without CG1 extrapolates)."""
    return tuple(c.metric for c in criteria() if c.estimate in DIFFERENCES)


def signed_names() -> frozenset[str]:
    """The budget keys of the signed criteria (held to +-budget; the others to <= budget)."""
    return frozenset(c.name for c in criteria() if c.estimate in DIFFERENCES)
