"""docs/results/layer_resolution (issue 44 item 1): the README and levels.csv are what the
committed per-run table gives (the script's --check), and what the README says of them."""

from __future__ import annotations

import sys

import pandas as pd

from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "layer_resolution"
sys.path.insert(0, str(ROOT / "scripts"))
from layer_resolution import main  # noqa: E402


def test_readme_and_levels_are_the_committed_runs():
    assert main(["--check"]) == 0


def test_every_coarser_level_moves_less_from_the_finest_today():
    lv = pd.read_csv(HERE / "levels.csv")
    frames = pd.read_csv(HERE / "frames.csv")
    assert set(lv.study) == {"liquid_spreading", "paper_scale_cg"}
    assert (frames.frames > 0).all() and frames.today_mm.notna().all()
    coarse = lv[lv.cg > lv.reference_cg]
    assert len(coarse) == 4
    assert (coarse.today_minus_finest_mm.abs() < coarse.former_minus_finest_mm.abs()).all()
    # the former estimator read every coarser level thicker than its finest
    assert (coarse.former_minus_finest_mm > 1.0).all()
    text = " ".join((HERE / "README.md").read_text().split())
    assert f"In {len(coarse)} of {len(coarse)} coarser levels" in text


def test_the_scaling_guide_quotes_the_committed_range():
    from ligwf.api.results_folder import number
    lv = pd.read_csv(HERE / "levels.csv")
    coarse = lv[lv.cg > lv.reference_cg].former_minus_finest_mm
    quoted = f"{number(coarse.min(), 2)}-{number(coarse.max(), 2)} mm thicker"
    guide = " ".join((ROOT / "docs" / "guide" / "scaling.md").read_text().split())
    assert quoted in guide, quoted
