"""ligwf.analysis.granules.candidates (the measurement of docs/results/granule_definitions.md)
on real engine output (``tests/data/cg3_slice``): its union-find against the analysis's
compiled components, its frames against the dumps, and ``python -m`` printing the numbers it
printed as ``scripts/measure_granule_definitions.py`` on the same case."""

from __future__ import annotations

import numpy as np
import pytest

from helpers import ROOT
from ligwf.analysis.granules.candidates.__main__ import main
from ligwf.analysis.granules.candidates.frames import load_case, rotation_check
from ligwf.analysis.granules.candidates.graphs import components
from ligwf.analysis.granules.candidates.specs import CANDIDATES, Evaluator
from ligwf.analysis.granules_numba import components_images

CASE = ROOT / "tests" / "data" / "cg3_slice" / "cg3-weber-r0"


@pytest.fixture(scope="module")
def case():
    return load_case(CASE, 0.25)


def _first_seen(labels: np.ndarray) -> np.ndarray:
    """Labels renumbered in order of first member (two partitions compare equal)."""
    _, first, inverse = np.unique(labels, return_index=True, return_inverse=True)
    return np.argsort(np.argsort(first))[inverse]


def test_the_frames_are_the_production_dumps_with_their_bridges(case):
    assert (case.cg, case.rule, case.axis) == (3.0, "weber", 1)
    assert [fr.step for fr in case.frames] == [13618, 20427, 27236] and case.steady == [1, 2]
    for fr in case.frames:
        assert fr.n == 222 and len(fr.i) > 200
        assert np.all(fr.force > 0) and np.all(fr.frel > 0)
        assert np.all(np.abs(fr.dy) <= 0.5 * case.length)
        assert set(fr.cos) >= {"lab", "rot", "flow"}
    # the drum turns with +omega: in its frame the bed is nearly still
    plus, minus = rotation_check(case)
    assert plus < 1 < minus


def test_its_components_are_the_analysis_components_on_real_frames(case):
    for fr in case.frames:
        labels, perc = components(fr.n, fr.i, fr.j, fr.dy, case.length)
        y = fr.pos[:, 1]
        ref, _, wraps, _ = components_images(fr.n, fr.i.astype(np.int64), fr.j.astype(np.int64),
                                             len(fr.i), y, case.length)
        np.testing.assert_array_equal(_first_seen(labels), ref)
        np.testing.assert_array_equal(perc, wraps[ref])
        assert perc.any()                      # the slice is 3 beads long: granules wrap


def test_a_tiled_slice_holds_each_unwrapped_granule_once_per_tile(case):
    spec = next(s for s in CANDIDATES if s.name == "cc rot 10")
    ev = Evaluator(case)
    one = ev.partition(1, spec)
    two = ev.partition(1, spec, tiles=2)
    sizes1 = np.bincount(one[0])[np.unique(one[0])]
    sizes2 = np.bincount(two[0])[np.unique(two[0])]
    kept1 = sorted(sizes1[~np.asarray([one[1][one[0] == g].any() for g in np.unique(one[0])])])
    kept2 = sorted(sizes2[~np.asarray([two[1][two[0] == g].any() for g in np.unique(two[0])])])
    assert two[2] == 2 * one[2] and kept2[: 2 * len(kept1)] == sorted(kept1 * 2)[: len(kept2)]


def test_the_command_prints_what_the_script_printed(capsys):
    assert main(["--base", str(CASE), "--series", str(CASE), "--cg-series", str(CASE),
                 "--only", "cc lab 30", "cc persist k2", "--tiles", "2", "--boot", "50",
                 "--speed-tiles", "1"]) == 0
    out = capsys.readouterr().out
    # measured with scripts/measure_granule_definitions.py before it moved (2026-12-07)
    assert ("| cc lab 30 | 100% | 74.5% | 5.42 [4.78, 6.06] | 1.01 | 6.82 | 5.42 | 1 / 1 | "
            "NO | yes | NO | - | yes |") in out
    assert "- cc persist k2: 1x 6.01 [5.97, 6.06], size 147.2; 2x 7.58" in out
    assert "- cc lab 30: angle x0.8 0.995, angle x1.2 1" in out
