"""Whether a steady window shows a steady state, and how much longer production would.

``steady_after: auto`` (:mod:`ligwf.analysis.flow.steady`) never starts the window later than
:data:`CAP` of the production time. The start is tested, not assumed: a window that starts
at the cap (:func:`at_cap`) means the rule found no steady start in the first half, i.e.
the run is too short to show a steady state (MSER practice: a truncation near n / 2 means
more data are needed). The verdict flags such runs and says how much longer production
would fix it, and the planner sizes extensions by the same rule (:func:`least_extension`):
**production at least 1 / TARGET_SHARE = 4 x the truncation**, so a window whose start was
measured starts by 25 % of production, half the cap. A capped run's truncation is only
known to lie between half its production and all of it; the rule takes the middle of that
range, :data:`CAPPED_TRUNCATION` = 3/4 of production, so a capped run's production at least
triples. (The first rule took the lower end, a doubling: its registered check,
``benchmarks/bench_steady.py --extension --capped-truncation 0.5``, left 0.041-0.103 of
extended synthetic runs still at the cap and a median truncation up to 0.31 of the new
production: H-ext1 and H-ext2 not met; docs/results/steady.) The start is tested again on
the longer run, and a run still at the cap is flagged again.
Pure: numbers in, numbers out.
"""

from __future__ import annotations

import math

#: the window never starts later than this fraction of production
CAP = 0.5
#: a start at or after this fraction counts as at the cap: the cap is frame n // 2, which
#: sits up to a frame or two below 0.5 (benchmarks/bench_steady.py counts the same way)
AT_CAP = 0.45
#: the truncation a planned production keeps to: well below the cap (half of it)
TARGET_SHARE = 0.25
#: the truncation taken for a run whose window starts at the cap, as a fraction of its
#: production: only known to lie in [CAP, 1], the middle of that range is taken
CAPPED_TRUNCATION = 0.75


def at_cap(fraction: float) -> bool:
    """True when a steady window starts at its cap (:data:`AT_CAP` of production or later):
    ``auto`` found no steady start in the first half of the run."""
    return math.isfinite(fraction) and fraction >= AT_CAP


def least_extension(fraction: float, production_time: float,
                    capped_truncation: float = CAPPED_TRUNCATION) -> float:
    """Seconds of production to add to a run whose window starts at ``fraction`` of its
    ``production_time`` (s) so the truncation is at most :data:`TARGET_SHARE` of the new
    production: ``max(0, fraction x P / TARGET_SHARE - P)``; a run at the cap has its
    truncation taken as ``capped_truncation`` x P (:data:`CAPPED_TRUNCATION`: twice its
    production more; 0.5, the first rule's, gives a doubling)."""
    if not (math.isfinite(fraction) and math.isfinite(production_time)) or production_time <= 0:
        return 0.0
    truncation = (max(fraction, capped_truncation) if at_cap(fraction) else fraction) \
        * production_time
    return max(0.0, truncation / TARGET_SHARE - production_time)
