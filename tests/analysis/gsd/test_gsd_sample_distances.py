"""ligwf.analysis.gsd.sample_distances: the bin-free distances on distributions whose
distances are known, and the verdicts and flow table recomputed from the committed tables
of docs/results/gsd_cg (written by scripts/gsd_cg_claim.py)."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from helpers import ROOT
from ligwf.analysis.gsd import sample_distances as sd
from scripts.gsd_cg_claim import DISTANCES, FLOW, GROUP

FOLDER = ROOT / "docs" / "results" / "gsd_cg"


def _main_cases() -> list[sd.SampleCase]:
    record = json.loads((FOLDER / "analysis" / "analysis.json").read_text())
    return sd.sample_cases(record["cases"], GROUP)


def test_a_distribution_is_at_distance_zero_from_itself():
    log_edges = np.linspace(-9, -6, 61)
    cdf = np.cumsum(np.exp(-np.linspace(-3, 3, 60) ** 2))
    w1, ks, *ratios = sd.distances(cdf, cdf, log_edges)[0]
    assert w1 == 0 and ks == 0 and ratios == [1.0, 1.0, 1.0]


def test_a_decade_shift_is_one_decade_of_w1_and_its_cube_root_in_diameter():
    log_edges = np.linspace(-9, -5, 81)             # 20 bins per decade
    mass = np.zeros(80)
    mass[10:30] = 1 / 20                           # volume fractions: the CDF ends at 1
    shifted = np.roll(mass, 20)                     # every granule ten times the volume
    w1, ks, *ratios = sd.distances(np.cumsum(shifted), np.cumsum(mass), log_edges)[0]
    assert w1 == pytest.approx(1.0) and ks == pytest.approx(1.0)
    assert ratios == pytest.approx([10 ** (1 / 3)] * 3)


def test_the_diameter_of_an_empty_distribution_is_nan():
    assert np.isnan(sd.diameter_at(np.zeros((1, 4)), np.arange(5.0), 0.5)).all()


def test_the_samples_of_the_committed_study_are_the_floor_then_the_pools():
    names = [s[0] for s in sd.samples([c for c in _main_cases() if not c.is_twin])]
    committed = pd.read_csv(FOLDER / FLOW)["sample"]
    main = [s for s in committed if "x K=" not in s and not s.startswith("twin")]
    assert names == main


def test_the_committed_verdicts_are_what_the_committed_distances_give():
    committed = pd.read_csv(FOLDER / DISTANCES)
    reading = [c for c in committed if c.endswith(("_floor", "_verdict"))]
    assert len(reading) == 2 * len(sd.DIST_NAMES)
    for volume, table in committed.groupby("volume", sort=False):
        again = sd.verdicts(table.drop(columns=reading))
        for name in sd.DIST_NAMES:
            assert list(again[f"{name}_verdict"]) == list(table[f"{name}_verdict"]), (volume, name)
            assert again[f"{name}_floor"].to_numpy() == pytest.approx(
                table[f"{name}_floor"].to_numpy(), rel=2e-5, abs=1e-5)


def test_the_committed_flow_rows_of_the_main_study_are_what_its_flow_table_gives():
    flow = pd.read_csv(FOLDER / "analysis" / "flow.csv")
    again = sd.flow_table(flow, _main_cases())
    committed = pd.read_csv(FOLDER / FLOW).set_index("sample")
    assert len(again) == 17
    for _, row in again.iterrows():
        want = committed.loc[row["sample"]]
        assert (row["condition"], row["k"]) == (want["condition"], want["k"])
        for col in sd.FLOW_METRICS:
            for c in (col, f"{col}_error"):
                assert math.isclose(row[c], want[c], rel_tol=1e-5, abs_tol=1e-9), (row["sample"], c)
