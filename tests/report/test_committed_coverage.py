"""docs/results/ladder/coverage.txt, the coverage benchmark the verdict's statistics rest on
(benchmarks/bench_coverage.py, its command on the first line): every coverage cell of every
interval the report shows lies in [0.92, 0.99], at least 400 studies a cell, and the whole
sequential procedure (--until-decided) decides wrongly at most 5 % of the time. A
regenerated file that breaks any of these fails here."""

from __future__ import annotations

import re

from tests.helpers import ROOT

TEXT = (ROOT / "docs" / "results" / "ladder" / "coverage.txt").read_text()


def test_it_was_made_by_the_benchmark_with_enough_studies():
    first = TEXT.splitlines()[0]
    assert first.startswith("# .venv/bin/python benchmarks/bench_coverage.py")
    trials = int(re.search(r"trials per cell: (\d+)", TEXT).group(1))
    seq = int(re.search(r"(\d+) null studies a cell", TEXT).group(1))
    assert trials >= 400 and seq >= 400


def test_every_interval_covers_within_its_band():
    kinds = re.findall(r"^(\w+): coverage ([\d.]+)-([\d.]+), (\d+) of (\d+) cells in", TEXT,
                       re.M)
    assert {k for k, *_ in kinds} == {"value", "diff", "tost", "norm"}
    for kind, lo, hi, inside, cells in kinds:
        assert int(inside) == int(cells) >= 100, kind
        assert 0.92 <= float(lo) <= float(hi) <= 0.99, kind
    # and the cell table says the same as the summary lines
    rows = re.findall(r"^ +\d +\d+ +[\d.]+ +[\d.]+ \| +([\d.]+) +([\d.]+) +([\d.]+) +([\d.]+) \|",
                      TEXT, re.M)
    assert len(rows) >= 100
    assert all(0.92 <= float(v) <= 0.99 for row in rows for v in row)


def test_the_sequential_procedure_errs_at_most_five_percent():
    worst = float(re.search(r"sequential: final decisions wrong at most ([\d.]+)", TEXT).group(1))
    assert worst <= 0.05
    wrong = re.findall(r"^ +\d +\d+ +[\d.]+ +[\d.]+ \| +([\d.]+) +([\d.]+) \| +[\d.]+$", TEXT, re.M)
    assert len(wrong) >= 16 and max(float(v) for row in wrong for v in row) == worst


def test_single_look_wrong_pass_re_measured_is_not_above_five_percent():
    """The largest of 108 wrong-pass shares of 400 trials sits ~2.5 Monte Carlo SE above
    its truth by chance: every cell above 0.05 was measured again on >= 10,000 fresh null
    studies, and none is shown above 0.05 (lower 95 % Clopper-Pearson bound)."""
    m = re.search(r"wrong pass re-measured on (\d+) fresh null studies per cell where it came "
                  r"out above 0.05 \((\d+) cells\)", TEXT)
    assert m and int(m.group(1)) >= 10000
    first = [float(v) for v in re.findall(r"^ +\d +\d+ +[\d.]+ +[\d.]+ \| +[\d.]+ +[\d.]+ +"
                                          r"[\d.]+ +[\d.]+ \| +([\d.]+) ", TEXT, re.M)]
    rows = re.findall(r"\| first ([\d.]+) \| Welch ([\d.]+) \[([\d.]+), ([\d.]+)\]", TEXT)
    assert len(rows) == int(m.group(2)) == sum(v > 0.05 for v in first)
    assert all(float(lo) <= 0.05 for _, _, lo, _ in rows)
    worst = float(re.search(r"the largest lower 95 % bound is ([\d.]+)", TEXT).group(1))
    assert worst == max(float(lo) for _, _, lo, _ in rows) <= 0.05
