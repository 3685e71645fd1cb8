"""The committed granule-growth study (docs/results/granule_growth): its README is the text
its tables give (scripts/granule_growth_results.py --check), every seed's criteria recompute
from the per-frame rows, and the verdict's "k of n seeds" from the seed table."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from ligwf.analysis.granules.growth_study import seed_table, verdict
from scripts.granule_growth_results import (FRAME_FLOW, GROWTH_ROWS, OUT, SEED_VERDICT, SEEDS,
                                            main)

pytestmark = pytest.mark.skipif(not (OUT / SEEDS).exists(),
                                reason="the granule-growth tables are not committed yet")


def _read(name: str) -> pd.DataFrame:
    return pd.read_csv(OUT / name)


def test_readme_is_what_the_tables_say():
    assert main(["--check"]) == 0


def test_seed_criteria_recompute_from_the_frames():
    committed = _read(SEEDS)
    again = seed_table(_read(GROWTH_ROWS), _read(FRAME_FLOW))
    assert list(again["seed"]) == list(committed["seed"])
    for col in committed.columns:
        if col in ("seed", "control"):
            continue
        a, b = again[col].to_numpy(), committed[col].to_numpy()
        if col.startswith("pass_") or col == "flow_matched":
            assert list(a.astype(bool)) == list(b.astype(bool)), col
        else:
            assert np.allclose(a.astype(float), b.astype(float), rtol=1e-4, atol=1e-9,
                               equal_nan=True), col


def test_verdict_counts_the_seeds():
    committed = _read(SEED_VERDICT)
    again = verdict(_read(SEEDS))
    assert list(again["seeds_pass"]) == list(committed["seeds_pass"])
    assert list(again["passes"]) == list(committed["passes"])
