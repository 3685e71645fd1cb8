"""Numbers quoted in docs/results prose, recomputed from the committed tables beside them
(issue 31: a sentence must not drift from its table). Each entry: the document, the text it
quotes, and the value the tables give."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

RESULTS = Path(__file__).resolve().parents[2] / "docs" / "results"
GSD_CG = RESULTS / "gsd_cg" / "analysis"


def _cg1_percolating_frames() -> float:
    g = pd.read_csv(GSD_CG / "gsd_summary.csv")
    return float(g[(g["group"] == "{}") & (g["cg"] == 1.0)]["percolating_frames"].iloc[0])


def _r1_last13_percolating() -> int:
    f = pd.read_csv(GSD_CG / "frames.csv")
    r1 = f[(f["case_id"] == "cg1-none-r1") & (f["status"] == "ok")].sort_values("step")
    return int(r1.tail(13)["largest_percolates"].sum())


def _held_row() -> pd.Series:
    c = pd.read_csv(GSD_CG / "controls.csv")
    return c[c["definition"].str.startswith("study definition")].iloc[0]


QUOTES = [
    ("gsd_cg/README.md", "`percolating_frames` 0.269", lambda: f"{_cg1_percolating_frames():.3f}",
     "0.269"),
    ("gsd_cg/README.md", "percolates in 6 of its last 13 frames", _r1_last13_percolating, 6),
    ("gsd_cg/README.md", "They cover 18.7 % of the wet CG1 bed",
     lambda: f"{100 * _held_row()['share_10']:.1f}", "18.7"),
    ("gsd_cg/README.md", "Members separate at 0.32", lambda: f"{_held_row()['comove_ratio']:.2f}",
     "0.32"),
    ("granule_definitions.md", "`percolating_frames` 0.269",
     lambda: f"{_cg1_percolating_frames():.3f}", "0.269"),
    ("granule_definitions.md", "held-1 s granules cover\n18.7 %",
     lambda: f"{100 * _held_row()['share_10']:.1f}", "18.7"),
]


@pytest.mark.parametrize("doc, text, value, quoted", QUOTES,
                         ids=[f"{d}:{t[:30]}" for d, t, _, _ in QUOTES])
def test_quoted_number_is_the_tables(doc, text, value, quoted):
    assert text in (RESULTS / doc).read_text(), f"{doc} no longer says {text!r}"
    assert value() == quoted
