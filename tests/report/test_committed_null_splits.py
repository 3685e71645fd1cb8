"""docs/results/null_splits: the difference intervals of the verdict on real runs split into
two pseudo-conditions of one condition (nothing to find) hold 0 in >= 90 % of the splits at
R = 2, 3 and 4, and the committed splits.txt is what benchmarks/bench_null_splits.py prints
from the committed cases.csv; its README is the one scripts/kept_results.py renders."""

from __future__ import annotations

import contextlib
import io
import re

from benchmarks.bench_null_splits import main
from scripts import kept_results
from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "null_splits"


def test_splits_txt_recomputes_from_the_committed_runs():
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main([str(HERE)]) == 0
    committed = (HERE / "splits.txt").read_text().splitlines()[1:]   # less the command line
    assert out.getvalue().splitlines() == committed


def test_readme_and_splits_are_what_the_folder_declares():
    """scripts/kept_results.py renders the README and recomputes splits.txt (with its
    command line) from the committed runs."""
    assert kept_results.main(["--check"]) == 0
    assert kept_results.NULL_SPLITS.check() == []


def test_the_95_percent_intervals_hold_zero_in_at_least_90_percent_of_splits():
    totals = re.findall(r"R = (\d), 95 % interval: holds 0 in (\d+) of (\d+) splits",
                        (HERE / "splits.txt").read_text())
    assert {int(r) for r, _, _ in totals} == {2, 3, 4}
    for r, k, n in totals:
        assert int(n) >= 200 and int(k) / int(n) >= 0.90, (r, k, n)
