"""Neighbour skin from the physics of the scene (pure).

LIGGGHTS keeps, per particle, the partners within ``cutoff + skin`` and rebuilds the lists
as soon as any particle has moved half a skin since the last build (ligwf renders
``neigh_modify delay 0``, the default ``every 1 check yes``). Two facts follow:

* **The skin does not have to cover the liquid bridges.** Both wet models enlarge the
  engine's contact distance factor to 1.1 x ``maxSeparationDistanceRatio``, which widens
  the neighbour and ghost cut-offs by itself (``shared/LIGGGHTS_NOTES.md``); the skin only
  has to cover the displacement between two rebuilds.
* **Any skin gives the same forces; it only sets the cost.** A thick skin makes every pair
  loop walk more candidates, a thin one rebuilds more often. Measured on the we_vs_bo drum
  (18 mm, 30 rpm, one rank, production): from 0.5 to 0.15 smallest diameters the CG1 step
  cost fell 7.3 -> 6.6 ms and the CG3 step 0.375 -> 0.350 ms (5.5 instead of 9.3 candidate
  neighbours a particle); at 0.1 d CG3 became slower again (rebuilds every ~35 steps).
  Both optima sat at a rebuild every ~50 steps, whence :data:`REBUILD_STEPS`.

So the skin is the distance the fastest particle travels in :data:`REBUILD_STEPS` steps,
twice (a rebuild comes at half a skin): ``skin = 2 x REBUILD_STEPS x v x dt``. In the turning
drum ``v`` is :data:`TURN_SPEED_FACTOR` x the wall speed omega R (the fastest particles of the
flowing layer ran at 1.2-1.8 x omega R in those runs); while the bed is filled it is the speed
of a drop across the drum, sqrt(2 g D). Both are clamped to
[:data:`SKIN_MIN_RATIO`, :data:`SKIN_MAX_RATIO`] x the smallest diameter: the engine's check
keeps any skin correct, the bounds only keep the cost sane when the estimate is off (a drum
turning very slowly, a very fast one). Since dt grows like the CG factor, so does the skin:
the ratio skin / d is the same at every CG level of a study.
"""

from __future__ import annotations

import math

from ligwf.scene.model import GRAVITY

#: Steps between two neighbour-list rebuilds the skin aims at (measured optimum, above).
REBUILD_STEPS = 50
#: Fastest particle speed in the turning drum / the drum's wall speed omega R.
TURN_SPEED_FACTOR = 2.0
#: Bounds of the skin, in smallest diameters (0.5 was ligwf's fixed skin before).
SKIN_MIN_RATIO = 0.05
SKIN_MAX_RATIO = 0.5


def skin_for_speed(speed: float, dt: float, d_min: float) -> float:
    """Skin (m) such that a particle at ``speed`` (m/s) needs :data:`REBUILD_STEPS` steps of
    ``dt`` (s) to move half of it, clamped to the bounds in units of ``d_min`` (m)."""
    raw = 2.0 * REBUILD_STEPS * speed * dt
    return min(max(raw, SKIN_MIN_RATIO * d_min), SKIN_MAX_RATIO * d_min)


def turning_skin(omega: float, drum_radius: float, dt: float, d_min: float) -> float:
    """Skin of the settle and production phases: fastest particles at
    :data:`TURN_SPEED_FACTOR` x the wall speed ``omega`` (rad/s) x ``drum_radius`` (m)."""
    return skin_for_speed(TURN_SPEED_FACTOR * omega * drum_radius, dt, d_min)


def fill_skin(drum_diameter: float, dt: float, d_min: float) -> float:
    """Skin of the fill phase: particles inserted in the drum drop across it, at most
    sqrt(2 g D) (m/s)."""
    return skin_for_speed(math.sqrt(2.0 * GRAVITY * drum_diameter), dt, d_min)
