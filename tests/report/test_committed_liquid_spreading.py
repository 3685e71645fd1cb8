"""docs/results/liquid_spreading (issue 47 item 2): the README and the derived tables are
what the committed case table gives (the script's --check), each case's spreading time is
what its committed series gives, and the registered verdicts read from the tables."""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd
import pytest

from ligwf.analysis.flow.spreading import time_to_share
from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "liquid_spreading"
sys.path.insert(0, str(ROOT / "scripts"))
from liquid_spreading_results import main  # noqa: E402


def test_readme_and_derived_tables_are_the_committed_cases():
    assert main(["--check"]) == 0


def test_each_spreading_time_is_its_series():
    series = pd.read_csv(HERE / "series.csv")
    cases = pd.read_csv(HERE / "cases.csv")
    assert len(cases) == 9 and sorted(cases.cg.value_counts()) == [3, 3, 3]
    for _, c in cases.iterrows():
        s = series[series.case_id == c.case_id].sort_values("revolutions")
        t, censored = time_to_share(s.revolutions, s.dry_content_share)
        assert t == pytest.approx(c.t_spread_rev, rel=1e-4) and censored == c.censored


def test_registered_verdicts_read_from_the_tables():
    cases = pd.read_csv(HERE / "cases.csv")
    levels = pd.read_csv(HERE / "levels.csv").set_index("cg")
    hyp = pd.read_csv(HERE / "hypotheses.csv")
    cg1 = cases[cases.cg == 1].t_spread_rev
    # the registered null: the largest CG1 seed-to-seed ratio below 2
    assert cg1.max() / cg1.min() < 2
    for cg in (2.0, 3.0):
        lv = cases[cases.cg == cg].t_spread_rev
        ratio = np.exp(np.log(cg1).mean() - np.log(lv).mean())
        assert levels.loc[cg, "rate_ratio"] == pytest.approx(ratio, rel=1e-4)
    met = {(r.hypothesis, r.cg): bool(r.met) for _, r in hyp.iterrows()}
    for cg in (2.0, 3.0):
        lo, hi = levels.loc[cg, ["rate_ratio_low", "rate_ratio_high"]]
        assert met[("H1 faster", cg)] == (lo > 1)
        assert met[("H2 n^2", cg)] == (lo <= cg ** 2 <= hi)
    assert met[("null CG1 vs CG1", 1.0)]
    readme = (HERE / "README.md").read_text()
    assert "No level's interval lies above 1" in readme
    assert "outside the interval at CG2 (4)" in readme


def test_the_scaling_guide_quotes_the_committed_levels():
    from ligwf.api.results_folder import number
    guide = (ROOT / "docs" / "guide" / "scaling.md").read_text()
    levels = pd.read_csv(HERE / "levels.csv")
    for _, r in levels.iterrows():
        quoted = (f"{number(r.rate_ratio)}x [{number(r.rate_ratio_low)}, "
                  f"{number(r.rate_ratio_high)}] at We-CG{r.cg:g}")
        assert quoted in " ".join(guide.split()), quoted
