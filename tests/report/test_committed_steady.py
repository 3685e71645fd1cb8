"""docs/results/steady: the README is the text scripts/kept_results.py renders from the
committed bench outputs (bench_steady.txt, bench_steady_hybrid.txt, the extension runs) and
the long check's tables, and its numbers and hypotheses are those files' (read here with the
bench's own readers, the hypotheses recomputed from the cells)."""

from __future__ import annotations

import math
import re

import pandas as pd

from benchmarks.bench_steady import read_cells, read_extension_cells
from scripts import kept_results
from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "steady"


def _rows(name: str = "bench_steady.txt") -> list[dict]:
    """The cells of a committed bench_steady run."""
    text = (HERE / name).read_text()
    assert text.startswith("# ") and "bench_steady" in text.splitlines()[0]
    rows = read_cells(text)
    assert len(rows) == 24
    return rows


def test_readme_is_what_its_files_give():
    assert kept_results.main(["--check"]) == 0
    assert kept_results.STEADY.check() == []


def test_readme_numbers_are_the_benchmark():
    rows = _rows()
    text = " ".join((HERE / "README.md").read_text().split())
    still = [r for r in rows if not r["startup"]]

    def span(key, frames):
        sub = [r[key] for r in still if r["frames"] == frames]
        return f"{min(sub):.2f}-{max(sub):.2f}"

    assert (f"in {span('current', 40)} of runs at 40 frames, {span('current', 80)} at 80 and "
            f"{span('current', 160)} at 160") in text
    assert (f"MSER-5 caps {span('mser', 40)} of runs at 40 frames, {span('mser', 80)} at 80 "
            f"and {span('mser', 160)} at 160") in text
    bias = max(max(abs(r["current_bias"]), abs(r["mser_bias"])) for r in rows)
    assert f"at most {bias:.2f} standard errors" in text
    # the hypotheses as the file states them, and growth with length in every cell
    verdicts = (HERE / "bench_steady.txt").read_text()
    for h in ("H1", "H2"):
        assert re.search(rf"^{h} .*: does not hold$", verdicts, re.M)
        assert f"**{h} does not hold**" in text
    for i in range(0, len(rows), 3):
        cell = rows[i:i + 3]
        if not cell[0]["startup"]:
            assert [r["frames"] for r in cell] == [40, 80, 160]
            assert cell[2]["current"] > cell[0]["current"]
    low = [r["current"] for r in still if r["frames"] == 160 and r["current"] < 0.25]
    assert len(low) == 1 and f"caps {low[0]:.2f} at 160 frames" in text


def test_the_new_rule_and_the_long_check_numbers_are_their_files():
    assert "--seed 20261207" in (HERE / "bench_steady_hybrid.txt").read_text().splitlines()[0]
    rows = _rows("bench_steady_hybrid.txt")
    text = " ".join((HERE / "README.md").read_text().split())
    still = [r for r in rows if not r["startup"] and r["frames"] >= 80]
    worst = max(r["current"] for r in still)
    bias = max(abs(r["current_bias"]) for r in rows)
    met = worst <= 0.20 and bias <= 0.25

    def span(frames):
        sub = [r["current"] for r in still if r["frames"] == frames]
        return f"{min(sub):.2f}-{max(sub):.2f}"

    assert (f"caps at most {worst:.2f} of runs in the cells of 80 and 160 frames "
            f"({span(80)} at 80, {span(160)} at 160)") in text
    assert f"at most {bias:.2f} standard errors in every cell" in text
    assert f"**the registered criterion is {'met' if met else 'not met'}.**" in text
    capped = [int((pd.read_csv(HERE / f"long_cases_{k}.csv")["steady_fraction"] >= 0.45).sum())
              for k in ("band", "mser")]
    assert f"in {capped[0]} of 24 runs with the band and in {capped[1]} of 24" in text
    decided = []
    for k in ("band", "mser"):
        v = pd.read_csv(HERE / f"long_verdict_{k}.csv")
        v = v[v["state"] != "not assessed"]
        decided.append((int(v["state"].isin(["pass", "fail"]).sum()), len(v)))
    assert (f"decides {decided[0][0]} of {decided[0][1]} assessed criteria with the band and "
            f"{decided[1][0]} of {decided[1][1]} with the new rule") in text
    check = pd.read_csv(HERE / "long_prediction_check_mser.csv")
    ext = check[check["kind"] == "extension"]
    assert (f"holds in {int(ext['within_30_percent'].sum())} of "
            f"{int(ext['measured_over_predicted'].notna().sum())} rows with a ratio") in text


#: registered 2026-12-07 in the README before the run (commit 9913c9d)
EXT_REGISTERED = {"still_capped": 0.05, "median": 0.25, "bias": 0.25}


def _extension_rows(name: str = "bench_steady_extension.txt", seed: int = 20261208
                    ) -> tuple[list[dict], str]:
    """The cells of a committed ``bench_steady --extension`` run, and the file's text."""
    text = (HERE / name).read_text()
    first = text.splitlines()[0]
    assert first.startswith("# ") and "bench_steady --extension" in first
    assert f"--trials 20000 --seed {seed}" in first
    rows = read_extension_cells(text)
    assert [(r["phi"], r["tau"]) for r in rows] == [(phi, tau) for phi in (0.5, 0.8)
                                                    for tau in (12, 16, 24)]
    assert all(r["trials"] == 20000 for r in rows)
    return rows, text


def _result_is_its_file(rows: list[dict], verdicts: str, text: str, said: str = "") -> list[dict]:
    """An extension run's result as the README says it (``text``), read from its file's
    cells: each hypothesis met or not (the file's verdict line recomputed from its table,
    and the README's ``**H-extN is [not] met<said>``), the share capped before, how many
    runs were extended and how many of them are still capped, the median and late
    truncation, the bias, and the phi-0.8 cells beside. Returns the registered (phi 0.5)
    cells."""
    reg = [r for r in rows if r["phi"] == 0.5]
    beside = [r for r in rows if r["phi"] == 0.8]

    def span(cells, key, fmt=".3f"):
        values = sorted(float(r[key]) for r in cells)
        return f"{values[0]:{fmt}}-{values[-1]:{fmt}}"

    def each(key):
        return ", ".join(r[key] for r in reg[:-1]) + f" and {reg[-1][key]}"

    met = {
        "H-ext1": all(float(r["after"]) <= EXT_REGISTERED["still_capped"] for r in reg),
        "H-ext2": all(float(r["median"]) <= EXT_REGISTERED["median"] for r in reg),
        "H-ext3": all(abs(float(r["bias"])) <= EXT_REGISTERED["bias"] for r in reg),
    }
    for h, ok in met.items():
        # the file's verdict line, recomputed from its table, and the README's, as registered
        assert re.search(rf"^{h} .*: {'met' if ok else 'not met'}$", verdicts, re.M)
        assert f"**{h} is {'met' if ok else 'not met'}{said}" in text
    assert f"starts at the cap in {span(reg, 'before')} of runs" in text
    assert (f"extended ({min(r['extended'] for r in reg)}-{max(r['extended'] for r in reg)} "
            f"a cell), the window still starts at the cap in {each('after')}") in text
    assert f"is {each('median')} of the new production" in text
    assert f"later than 0.25 in {each('late')} of the extended runs" in text
    bias = sorted(float(r["bias"]) for r in reg)
    assert f"off by {bias[0]:.2f} to {bias[-1]:.2f} standard errors" in text
    assert (f"still at the cap after the extension {span(beside, 'after')}, median truncation "
            f"{span(beside, 'median', '.4f')}") in text
    return reg


def test_the_extension_rule_numbers_are_their_file():
    from benchmarks import bench_steady

    # the thresholds the bench applies are the registered ones
    assert (bench_steady.EXT_STILL_CAPPED, bench_steady.EXT_MEDIAN, bench_steady.EXT_BIAS) == (
        EXT_REGISTERED["still_capped"], EXT_REGISTERED["median"], EXT_REGISTERED["bias"])
    rows, verdicts = _extension_rows()
    text = " ".join((HERE / "README.md").read_text().split())
    reg = _result_is_its_file(rows, verdicts, text)
    # the sentences around them: which cells fail, by how much, and the registered precision
    tau16, tau24 = reg[1], reg[2]
    excess = float(tau16["after"]) - EXT_REGISTERED["still_capped"]
    precision = 1.96 * math.sqrt(0.05 * 0.95 / min(r["extended"] for r in reg))
    assert f"at tau 16 by {excess:.3f}" in text and excess < round(precision, 3) == 0.007
    assert float(tau24["after"]) >= 2 * EXT_REGISTERED["still_capped"]
    assert f"{float(tau24['after']):.1f}" == "0.1" and "a tenth of the doubled runs" in text
    assert float(tau24["late"]) > 0.5 and "most start later than a quarter" in text
    failing = [r["tau"] for r in reg if float(r["median"]) > EXT_REGISTERED["median"]]
    assert failing == [24] and "**H-ext2 is not met** (tau 24)" in text


def test_the_tripling_rule_numbers_are_their_file():
    """The second registered run (README: registered at a929c29, before its run): the rule
    the planner uses now, a capped run's truncation taken as 3/4 of its production."""
    from ligwf.analysis.records import steady_window

    assert steady_window.CAPPED_TRUNCATION == 0.75
    rows, verdicts = _extension_rows("bench_steady_extension_2.txt", 20261209)
    assert "a capped run's truncation taken as 0.75 of its production" in verdicts
    text = " ".join((HERE / "README.md").read_text().split())
    assert "registered in README.md at a929c29" in verdicts.splitlines()[0]
    section = text[text.index("`bench_steady_extension_2.txt`"):]
    _result_is_its_file(rows, verdicts, section, " by the tripling rule**")
