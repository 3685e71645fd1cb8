"""ligwf.analysis.gsd.definition_cases on real engine output (``tests/data/cg3_slice``,
analysed here): the steady granules it identifies again under the study's own definition are
the ones ``ligwf analyse`` wrote, and its per-case numbers are those of the frames."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from helpers import ROOT
from ligwf.analysis.gsd import bins as gsdmod
from ligwf.analysis.gsd.definition_cases import (DEFINITION_COLUMNS, DEFINITIONS,
                                                 definition_table, steady_granules)
from ligwf.cli.main import main
from ligwf.study import layout
from ligwf.study.study import Study

DATA = ROOT / "tests" / "data" / "cg3_slice"


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The committed CG3 slice, analysed (its granules with the study's definition)."""
    path = tmp_path_factory.mktemp("defs") / "study"
    shutil.copytree(DATA, path)
    record = json.loads((path / "study.json").read_text())
    record["analysis"].update(bootstrap=50, sensitivity_frames=0)
    (path / "study.json").write_text(json.dumps(record))
    assert main(["analyse", str(path), "--no-vtu"]) == 0
    return Study.open(path)


def test_the_steady_granules_are_the_ones_the_analysis_wrote(study):
    again, cases = steady_granules(study, study.analysis)
    written = pd.read_parquet(study.analysis_dir / layout.GRANULES_TABLE)
    steady_from = pd.read_csv(study.analysis_dir / layout.FLOW_TABLE)["steady_from_step"].iloc[0]
    written = written[written["step"] >= steady_from]
    assert [c.case_id for c in cases] == ["cg3-weber-r0"]
    assert sorted(again["step"].unique()) == sorted(written["step"].unique()) and len(again) > 0
    for col in ("members", "volume", "percolating"):
        np.testing.assert_array_equal(np.sort(again[col].to_numpy()),
                                      np.sort(written[col].to_numpy()))


def test_the_per_case_numbers_are_those_of_its_frames(study):
    g, cases = steady_granules(study, DEFINITIONS["components lab 30 (source)"])
    table = definition_table(g, cases)
    assert list(table.columns) == DEFINITION_COLUMNS and len(table) == 1
    row = table.iloc[0]
    frames = [fr for _, fr in g.groupby("step")]
    stats = [gsdmod.frame_stats(fr["volume"].to_numpy(), fr["members"].to_numpy(),
                                fr["percolating"].to_numpy(bool), 2) for fr in frames]
    assert row["frames"] == len(frames) == 2
    assert row["granules"] == np.mean([s["granules"] for s in stats])
    assert row["d50_mm"] == pytest.approx(1e3 * np.nanmean([s["d50"] for s in stats]))
    assert row["percolating_frames"] == np.mean([fr["percolating"].any() for fr in frames])
    share = [fr["volume"].max() / fr["volume"].sum() for fr in frames]
    assert (row["largest_share"], row["largest_share_max"]) == (np.mean(share), max(share))
    assert 0 < row["largest_share"] <= row["largest_share_max"] <= 1
