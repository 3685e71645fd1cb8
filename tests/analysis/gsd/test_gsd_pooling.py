"""ligwf.analysis.gsd.pooling: disjoint replica pools, the source study's upper size limit,
and the pooling table on synthetic granule tables with a known answer."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import pytest

from ligwf.analysis.gsd import bins as gsd
from ligwf.analysis.gsd.pooling import pooling_summary, pooling_table, pools, upper_limit
from ligwf.scene.settings import AnalysisSettings


@dataclass(frozen=True)
class Case:
    case_id: str
    cg: float
    rule: str
    replica: int
    group: str = "{}"


def test_pools_are_disjoint_and_in_order():
    assert pools([3, 0, 1, 2, 4, 5, 6, 7], 4) == [(0, 1, 2, 3), (4, 5, 6, 7)]
    assert pools(range(5), 2) == [(0, 1), (2, 3)]
    assert pools([0], 2) == []
    with pytest.raises(ValueError, match="k = 0"):
        pools([0, 1], 0)


def test_upper_limit_is_where_the_error_first_leaves_the_band():
    edges = np.array([1.0, 2.0, 4.0, 8.0, 16.0])
    ref = np.array([0.4, 0.3, 0.2, 0.1])
    assert upper_limit(edges, ref * [1.0, 1.1, 1.5, 1.0], ref, 0.15) == 4.0   # bin 2 leaves
    assert upper_limit(edges, ref, ref, 0.15) == 16.0                          # never leaves
    assert np.isnan(upper_limit(edges, ref * [2.0, 1, 1, 1], ref, 0.15))       # first bin out
    # a bin too sparse to count (< 1 % of the CG1 volume) does not stop the search
    ref2 = np.array([0.5, 0.495, 0.005, 0.0])
    assert upper_limit(edges, ref2 * [1.0, 1.0, 3.0, 1.0], ref2, 0.15) == 4.0
    # the lower limit of ligwf.analysis.gsd.bins is the mirror image
    assert gsd.located_limit(edges, ref * [1.5, 1.0, 1.0, 1.0], ref, 0.15) == 2.0


def table(rng, cases, shift_of):
    """Granule table: per case 30 frames of 300 granules, log-normal volumes; ``shift_of``
    moves a case's granules above 1.5e-8 m^3 (~4.5 % of the volume) up (a CG error above
    a size, small enough that the renormalised small bins stay within 15 %)."""
    rows = []
    for c in cases:
        for step in range(30):
            v = np.exp(rng.normal(0.0, 1.0, 300)) * 1e-9
            v = np.where(v > 1.5e-8, v * shift_of(c), v)
            for g, vol in enumerate(v):
                rows.append({"case_id": c.case_id, "step": step, "granule": g, "members": 5,
                             "percolating": False, "volume": vol, "primary_volume": vol})
    return pd.DataFrame(rows)


def test_pooling_table_rows_and_known_answer():
    rng = np.random.default_rng(0)
    cases = [Case(f"cg1-none-r{r}", 1.0, "none", r) for r in range(2)] + \
            [Case(f"cg2-weber-r{r}", 2.0, "weber", r) for r in range(8)]
    g = table(rng, cases, lambda c: 3.0 if c.cg == 2 else 1.0)
    t = pooling_table(g, cases, AnalysisSettings(bootstrap=50), ks=(1, 2, 4))
    cg2 = t[t.cg == 2]
    assert sorted(cg2.groupby("k").size().items()) == [(1, 8), (2, 4), (4, 2)]
    assert set(cg2[cg2.k == 4]["pool"]) == {"0+1+2+3", "4+5+6+7"}
    floor = t[t.rule == "noise floor"]
    assert len(floor) == 2 and set(floor["pool"]) == {"0", "1"}
    # CG2 is right for small granules and wrong above 1.5e-8 m^3: an upper limit near it,
    # small errors below, large above
    # (single replicas: noisy, the median is there; pools of 4: every one)
    k4, k1 = cg2[cg2.k == 4]["upper_limit"], cg2[cg2.k == 1]["upper_limit"]
    assert ((k4 <= 3e-8) & (k4 >= 5e-9)).all() and 5e-9 <= k1.median() <= 3e-8
    assert (cg2["error_above_upper"] > 0.3).all()
    assert (cg2[cg2.k == 4]["error_below_upper"] < 0.15).all()
    # CG1 against itself also leaves the band somewhere (sparse large bins: the noise
    # floor of the "above" error is far from 0), but CG2's error above is larger
    assert floor["upper_limit"].notna().all()
    assert cg2[cg2.k == 4]["error_above_upper"].mean() > floor["error_above_upper"].mean()
    ok = t["error_above_upper"].notna()
    assert (t.loc[ok, "error_above_upper_lo"] <= t.loc[ok, "error_above_upper_hi"]).all()
    s = pooling_summary(t)
    row = s[(s.rule == "weber") & (s.k == 4)].iloc[0]
    assert row["pools"] == 2 and row["error_above_upper_min"] > 0.3


def test_empty_table():
    assert pooling_table(pd.DataFrame(), [], AnalysisSettings()).empty
