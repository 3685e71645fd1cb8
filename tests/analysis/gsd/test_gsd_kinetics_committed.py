"""ligwf.analysis.gsd.kinetics.kinetics_summary on the committed kinetics table of
docs/results/gsd_cg: the same numbers as the committed summary, one block per
:class:`~ligwf.study.condition.Condition`, named as the condition names itself today (the
committed control was analysed when a sweep group was named by its JSON)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from helpers import ROOT
from ligwf.analysis.gsd.kinetics import kinetics_summary
from ligwf.scene.settings import AnalysisSettings
from ligwf.study import layout
from ligwf.study.condition import Condition

ANALYSIS = ROOT / "docs" / "results" / "gsd_cg" / layout.ANALYSIS_DIR


def _read(name: str) -> pd.DataFrame:
    return pd.read_csv(ANALYSIS / name, keep_default_na=False, na_values=[""])


@pytest.mark.slow      # the committed summary's 300 rows, each bootstrapped again: ~11 s
def test_the_summary_recomputes_from_the_committed_kinetics():
    settings = json.loads((ANALYSIS / layout.ANALYSIS_RECORD).read_text())["settings"]
    again = kinetics_summary(_read(layout.KINETICS_TABLE),
                             AnalysisSettings(bootstrap=settings["bootstrap"], seed=settings["seed"]))
    committed = _read(layout.KINETICS_SUMMARY_TABLE)
    assert list(again.columns) == list(committed.columns) and len(again) == len(committed) == 300
    numbers = [c for c in committed.columns if committed[c].dtype.kind == "f"]
    np.testing.assert_allclose(again[numbers].to_numpy(float), committed[numbers].to_numpy(float),
                               rtol=1e-5, equal_nan=True)
    names = {Condition(g, cg, r).name for g, cg, r
             in committed[["group", "cg", "rule"]].itertuples(index=False)}
    assert set(again["condition"]) == names
    assert "cg1 cohesionless control" in names
