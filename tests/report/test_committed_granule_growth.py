"""The committed granule-growth study (docs/results/granule_growth): its README is the text
its tables give, every seed's criteria recompute from the per-frame rows, and the verdict's
"k of n seeds" from the seed table."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from ligwf.analysis.granules.growth_study import seed_table, verdict
from scripts.granule_growth_results import readme

OUT = Path(__file__).resolve().parents[2] / "docs" / "results" / "granule_growth"

pytestmark = pytest.mark.skipif(not (OUT / "seeds.csv").exists(),
                                reason="the granule-growth tables are not committed yet")


def _read(name: str) -> pd.DataFrame:
    return pd.read_csv(OUT / name)


def test_readme_is_what_the_tables_say():
    cal = _read("calibration.csv") if (OUT / "calibration.csv").exists() else None
    text = readme(_read("seeds.csv"), _read("controls_verdict.csv"), _read("cadence.csv"),
                  _read("cases.csv"), cal)
    assert (OUT / "README.md").read_text() == text


def test_seed_criteria_recompute_from_the_frames():
    committed = _read("seeds.csv")
    again = seed_table(_read("growth_rows.csv"), _read("flow.csv"))
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
    committed = _read("controls_verdict.csv")
    again = verdict(_read("seeds.csv"))
    assert list(again["seeds_pass"]) == list(committed["seeds_pass"])
    assert list(again["passes"]) == list(committed["passes"])
