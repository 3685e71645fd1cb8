"""docs/results/prediction_check: the README's counts of predictions that hold (measured
half-width within +-30 % of the planner's prediction) are those of the committed table."""

from __future__ import annotations

import re

import pandas as pd
import pytest

from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "prediction_check"


def test_readme_counts_are_the_tables():
    table = pd.read_csv(HERE / "demo.csv")
    text = (HERE / "README.md").read_text()
    for kind, label in (("replicas", "Replicas"), ("extension", "Extension")):
        sub = table[table["kind"] == kind]
        ok = int(sub["within_30_percent"].sum())
        ratios = sub["measured_over_predicted"]
        m = re.search(rf"{label}: .*?holds in (\d+) of (\d+) rows \(measured / predicted "
                      rf"([\d.]+)-([\d.]+)\)", text, re.S)
        assert m, label
        assert (int(m.group(1)), int(m.group(2))) == (ok, len(sub))
        assert float(m.group(3)) == round(ratios.min(), 2)
        assert float(m.group(4)) == round(ratios.max(), 2)
        # the flag is what the ratio says
        assert list(sub["within_30_percent"]) == [abs(r - 1) <= 0.3 for r in ratios]


@pytest.mark.parametrize("name, prefix", [("ladder", "Ladder"), ("ladder80", "Ladder80")])
def test_ladder_counts_are_its_table(name, prefix):
    """A ladder's rows (each registered in the README before its check ran): counts over
    the rows with a ratio (a statistic without an interval has none)."""
    table = pd.read_csv(HERE / f"{name}.csv")
    text = (HERE / "README.md").read_text()
    for kind, label in (("replicas", f"{prefix} replicas"), ("extension", f"{prefix} extension")):
        sub = table[table["kind"] == kind]
        ratios = sub["measured_over_predicted"].dropna()
        ok = int(sub["within_30_percent"].sum())
        m = re.search(rf"{label}: .*?holds in (\d+) of (\d+) rows \(measured / predicted "
                      rf"([\d.]+)-([\d.]+)\)", text, re.S)
        assert m, label
        assert (int(m.group(1)), int(m.group(2))) == (ok, len(ratios))
        assert (float(m.group(3)), float(m.group(4))) == (round(ratios.min(), 2),
                                                          round(ratios.max(), 2))
    ext = table[table["kind"] == "extension"]["measured_over_predicted"].dropna()
    assert "Every miss is\n  on the same side" in text and (ext[(ext - 1).abs() > 0.3] < 1).all()


def _bench_rows() -> list[dict]:
    """The cells of the committed bench_prediction.txt."""
    lines = (HERE / "bench_prediction.txt").read_text().splitlines()
    assert lines[0].startswith("# .venv/bin/python benchmarks/bench_prediction.py")
    rows = []
    for line in lines:
        m = re.match(r"^\s*(0\.\d)\s+(\d+)\s+([\d.]+)\s+(\d)\s+([\d.]+) \|\s+([\d.]+)\s+[\d.]+"
                     r"\s+([\d.]+)\s+[\d.]+ \|\s+(\S+)", line)
        if m:
            rows.append({"offset": float(m.group(3)), "startup": float(m.group(5)),
                         "share": float(m.group(6)), "median": float(m.group(7)),
                         "oracle": float(m.group(8)) if m.group(8) != "-" else None})
    assert len(rows) == 72
    return rows


def test_bench_prediction_numbers_in_the_readme_are_the_file():
    rows = _bench_rows()
    text = " ".join((HERE / "README.md").read_text().split())
    still = [r for r in rows if r["startup"] == 0]
    lone = [r for r in still if r["offset"] == 0]
    own = [r for r in still if r["offset"] > 0]
    moving = [r for r in rows if r["startup"] > 0]
    # H1: the oracle's best share; H2: the planner with and without seed offsets
    assert f"in at most {max(r['oracle'] for r in still):.2f} of trials" in text
    assert (f"median ratio is {min(r['median'] for r in lone):.2f}-"
            f"{max(r['median'] for r in lone):.2f}") in text
    gap = max(r["oracle"] - r["share"] for r in lone)
    assert f"falls up to {gap:.2f} below the oracle's" in text
    assert (f"+-30 % in {min(r['share'] for r in own):.2f}-"
            f"{max(r['share'] for r in own):.2f} of trials") in text
    # H3: the start-up transient, without and with seed offsets
    for sub in ([r for r in moving if r["offset"] == 0], [r for r in moving if r["offset"] > 0]):
        assert f"{min(r['median'] for r in sub):.2f}-{max(r['median'] for r in sub):.2f}" in text
    verdicts = (HERE / "bench_prediction.txt").read_text()
    for h, word in (("H1", "holds"), ("H2", "does not hold"), ("H3", "holds")):
        assert re.search(rf"^{h} .*: {word}$", verdicts, re.M), h
        assert f"{h} {word}" in text
