"""How placed liquid spreads through a dry bed: per production frame (pure).

LIGGGHTS moves liquid only when a bridge ruptures (the bridge's liquid is pooled and split
between the two particles by volume), so liquid placed in a dry bed (``liquid.placement:
granules``) reaches the dry particles by a walk over contacts whose step is one particle
diameter. At equal shear the walk's step is n times longer at CG-n and its rate per
particle the same: about n^2 times faster spreading in physical space, which no CG rule
corrects (docs/results/liquid_spreading).

Two series per frame, both over the particles that were dry at the first production frame
(content below :data:`DRY_FRACTION` of the placed content):

* ``dry_content_share``: their mean liquid content over the mean content of all particles
  (0 at the start, 1 when the liquid is uniform; a ratio, so the number of wet particles a
  level happens to place does not enter);
* ``dry_wet_share``: the share of them carrying any liquid (content > :data:`WET`).

:func:`time_to_share` reads the time at which the first series reaches a level
(revolutions, linear interpolation between frames), or says it was never reached.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: particles below this fraction of the placed content at the first frame count as dry
DRY_FRACTION = 1e-3
#: a particle with more liquid than this (volume / solid volume) carries liquid
WET = 1e-5
#: the registered level of ``dry_content_share`` whose time is the spreading time
#: (docs/results/liquid_spreading/criterion.md)
SPREAD_LEVEL = 0.25


@dataclass(frozen=True)
class SpreadSeries:
    """The two series of a case's production frames (see the module docstring)."""

    revolutions: tuple[float, ...]       # since the first production frame
    dry_content_share: tuple[float, ...]
    dry_wet_share: tuple[float, ...]
    dry_particles: int                   # particles dry at the first frame
    particles: int


def spread_series(frames, placed_content: float, period: float) -> SpreadSeries | None:
    """The spreading of a case from its production ``frames`` (ParticleFrame, sorted by
    id, in time order), the placed liquid content and the rotation period (s); None when
    the frames carry no liquid column, no particle starts dry, or none starts wet."""
    if not frames or placed_content <= 0.0 or frames[0].liquid_content is None:
        return None
    first = frames[0]
    dry_ids = first.ids[first.liquid_content < DRY_FRACTION * placed_content]
    if len(dry_ids) == 0 or len(dry_ids) == len(first.ids):
        return None
    t0 = first.time
    revs, share, wet = [], [], []
    for f in frames:
        if f.liquid_content is None:
            continue
        volume = f.volumes
        liquid = f.liquid_content * volume
        total = liquid.sum() / volume.sum()
        dry = np.isin(f.ids, dry_ids, assume_unique=True)
        if not dry.any():
            continue
        dry_mean = liquid[dry].sum() / volume[dry].sum()
        revs.append(float((f.time - t0) / period))
        share.append(float(dry_mean / total) if total > 0 else math.nan)
        wet.append(float(np.mean(f.liquid_content[dry] > WET)))
    return SpreadSeries(tuple(revs), tuple(share), tuple(wet), int(len(dry_ids)),
                        int(len(first.ids)))


def time_to_share(revolutions, share, level: float = SPREAD_LEVEL) -> tuple[float, bool]:
    """(revolutions at which ``share`` first reaches ``level``, linearly interpolated
    between frames; censored): when it never does, the last frame's revolutions and True."""
    r = np.asarray(revolutions, float)
    s = np.asarray(share, float)
    ok = np.isfinite(s)
    r, s = r[ok], s[ok]
    if len(r) == 0:
        return math.nan, True
    above = np.flatnonzero(s >= level)
    if len(above) == 0:
        return float(r[-1]), True
    k = int(above[0])
    if k == 0:
        return float(r[0]), False
    r0, r1, s0, s1 = r[k - 1], r[k], s[k - 1], s[k]
    return float(r0 + (level - s0) * (r1 - r0) / (s1 - s0)), False
