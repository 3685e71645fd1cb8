"""The contact-angle law of the LIGGGHTS 3.8.0 capillary models, and its compensation.

The Debian 3.8.0 release computes the effective angle of a pair in its ``washino`` and
``easo`` cohesion models as ``0.5 * theta_i * theta_j`` (radians) instead of the mean
``0.5 * (theta_i + theta_j)`` (fixed upstream after the release). With 30 deg on both
partners it applies about 7.9 deg. For one particle type an input angle
``a = sqrt(2 theta)`` makes the engine apply ``theta``; ligwf writes that unless the scene
says the engine has the fix (``numerics.contact_angle_compensation: false``).

The law lives with the liquid models (not in :mod:`ligwf.engine`) because every layer that
evaluates a bridge needs the angle the engine applied: the scene's pre-flight
(:mod:`ligwf.scene.timescales`), the renderer (the angle to write) and the granule
analysis (the bridge law of the run). Pure functions, no engine needed.
"""

from __future__ import annotations

import math

from ligwf.liquids.base import InputAngle

#: what the input's comment says when ligwf compensates the contact-angle bug
CONTACT_ANGLE_NOTE = "LIGGGHTS 3.8.0 applies 0.5*a*a rad"


def engine_contact_angle_deg(theta_deg: float, compensate: bool = True) -> float:
    """Contact angle to write into the LIGGGHTS input so the engine applies ``theta_deg``.

    LIGGGHTS 3.8.0 applies ``0.5 * a * a`` (radians) for an input angle ``a`` on both
    partners. Solving ``0.5 a^2 = theta`` gives ``a = sqrt(2 theta)``, which stays within the
    engine's accepted [0, 180] deg for every theta in [0, 180] deg. With ``compensate=False``
    (an engine with the upstream fix) the angle is passed through.
    """
    if not compensate:
        return theta_deg
    return math.degrees(math.sqrt(2.0 * math.radians(theta_deg)))


def engine_effective_angle_rad(theta_in_deg_i: float, theta_in_deg_j: float | None = None,
                               product_bug: bool = True) -> float:
    """Effective angle (radians) the engine applies for input angles of two partners."""
    a = math.radians(theta_in_deg_i)
    b = math.radians(theta_in_deg_j if theta_in_deg_j is not None else theta_in_deg_i)
    return 0.5 * a * b if product_bug else 0.5 * (a + b)


def input_angle(theta_deg: float, compensate: bool) -> InputAngle:
    """The angle a liquid model writes for a scene angle ``theta_deg``, with its note."""
    return InputAngle(engine_contact_angle_deg(theta_deg, compensate),
                      CONTACT_ANGLE_NOTE if compensate else "")


def applied_contact_angle_rad(theta_deg: float, compensated: bool,
                              product_bug: bool = True) -> float:
    """The angle (rad) the engine applied in a run whose scene angle is ``theta_deg``:
    the scene's when ligwf compensated (or the engine has the fix), else 0.5 theta^2."""
    if compensated or not product_bug:
        return math.radians(theta_deg)
    return engine_effective_angle_rad(theta_deg, product_bug=True)
