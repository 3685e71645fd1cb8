"""Does a granule definition beat its null control? The pre-registered criteria, as code.

The criteria (docs/results/granule_definitions.md, "Pre-registered pass criteria") compare
the control measures of a wet bed (:func:`ligwf.analysis.granules.control_run.summarise`, one row)
with those of its cohesionless twin (the same scene with surface tension and viscosity /
1000). :func:`verdict` returns each criterion with its numbers and one sentence a report
can print: a definition that fails any of them finds a tiling or a plug, not granules, and
no granule size limit or GSD error is then a finding.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: the wet bed must hold at least this share of its volume in granules of >= 10 particles
MIN_SHARE = 0.02
#: the twin may hold at most this fraction of the wet bed's share
MAX_TWIN_SHARE_RATIO = 0.2
#: pair persistence after a quarter revolution: at least this, and this many times the twin's
MIN_PERSISTENCE = 0.5
MIN_PERSISTENCE_RATIO = 2.0
#: the twin "has granules" above this share (else its persistence is not compared)
TWIN_HAS_GRANULES = 0.01
#: member pairs separate at most this fraction as fast as non-members
MAX_COMOVE_RATIO = 0.5
#: adjusted Rand index across seeds and contact orders
MIN_ARI = 0.95
#: share of steady frames with a percolating granule
MAX_PERCOLATING = 0.1


@dataclass(frozen=True)
class Criterion:
    name: str
    passed: bool
    detail: str


def _num(row, key: str) -> float:
    v = row.get(key, float("nan"))
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


def criteria(wet: dict, twin: dict) -> list[Criterion]:
    """Each pre-registered criterion of ``wet`` against ``twin`` (summary rows as dicts)."""
    out = []
    s_w, s_t = _num(wet, "share_10"), _num(twin, "share_10")
    out.append(Criterion("granules exist", s_w >= MIN_SHARE,
                         f"share of the bed in granules of >= 10 particles {s_w:.3g} "
                         f"(needs >= {MIN_SHARE:g})"))
    # at 0 / 0 nothing was beaten: a wet bed without granules cannot beat its twin
    out.append(Criterion("beats the twin", s_w > 0 and s_t <= MAX_TWIN_SHARE_RATIO * s_w,
                         f"twin {s_t:.3g} against wet {s_w:.3g} (needs <= "
                         f"{MAX_TWIN_SHARE_RATIO:g} x wet, and granules in the wet bed)"))
    p_w, p_t = _num(wet, "persist_quarter"), _num(twin, "persist_quarter")
    twin_has = s_t > TWIN_HAS_GRANULES and math.isfinite(p_t)
    ok = p_w >= MIN_PERSISTENCE and (not twin_has or p_w >= MIN_PERSISTENCE_RATIO * p_t)
    out.append(Criterion("survives", ok,
                         f"pair persistence after a quarter revolution {p_w:.3g} (twin "
                         f"{p_t:.3g}{'' if twin_has else ', no granules to compare'}; needs "
                         f">= {MIN_PERSISTENCE:g} and >= {MIN_PERSISTENCE_RATIO:g} x twin)"))
    c = _num(wet, "comove_ratio")
    out.append(Criterion("moves together", c <= MAX_COMOVE_RATIO,
                         f"member / non-member separation over a quarter revolution after "
                         f"the window {c:.3g} (needs <= "
                         f"{MAX_COMOVE_RATIO:g})"))
    # reproducibility is a criterion only where the definition is stochastic (an optimiser
    # seed, ``ari_seed``): the ARI of a deterministic definition is 1 by construction
    if math.isfinite(_num(wet, "ari_seed")):
        aris = [v for v in (_num(wet, "ari_seed"), _num(wet, "ari_order")) if math.isfinite(v)]
        a = min(aris)
        out.append(Criterion("reproducible", a >= MIN_ARI,
                             f"adjusted Rand index across seeds and contact orders {a:.3g} "
                             f"(needs >= {MIN_ARI:g})"))
    f = _num(wet, "percolating_frames")
    out.append(Criterion("no bed-spanning granule", f <= MAX_PERCOLATING,
                         f"frames with a percolating granule {f:.3g} (needs <= "
                         f"{MAX_PERCOLATING:g})"))
    return out


def verdict(wet: dict, twin: dict, definition: str,
            control: str = "cohesionless") -> tuple[bool, str]:
    """(passed, one sentence) for ``definition`` on this wet bed and its twin; ``control``
    names the twin's kind (cohesionless, flow_matched) in the sentence."""
    checks = criteria(wet, twin)
    failed = [c for c in checks if not c.passed]
    if not failed:
        return True, (f"granules ({definition}) beat the {control} control on every "
                      "pre-registered criterion: sizes and GSD errors below are findings")
    names = "; ".join(f"{c.name}: {c.detail}" for c in failed)
    return False, (f"granules ({definition}) do NOT beat the {control} control ({names}), "
                   "so they are not shown to be granules (bodies that move together and "
                   "survive, absent without cohesion): no size limit or GSD error below is a "
                   "finding")
