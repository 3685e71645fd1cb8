"""Granule analysis at scale (#24): the faster kernels give the same numbers, bit for bit.

* the Louvain's stay-proof (nodes proven to stay are not re-visited) and its linear-time
  aggregation order leave the partition identical to the plain-Python reference, which
  visits every node every pass, on real engine frames tiled 4x (more passes, more
  proofs);
* the rupture-work table of touching pairs returns the same bits as integrating each
  pair alone;
* the presence runs of ``granules: held`` give the same held bridges as intersecting the
  window's key sets.
"""

from __future__ import annotations

import numpy as np
import pytest

from helpers import tiled
from ligwf.analysis.cpm_numba import _stable_key_order
from ligwf.analysis.granules.bonds import BondCriterion, bonded_contacts
from ligwf.analysis.granules.bridge_law import relative_energy
from ligwf.analysis.granules.communities import cpm_labels, cpm_labels_reference
from ligwf.analysis.granules.definitions import cpm_weights
from ligwf.analysis.granules.persistent import Frame, bridge_keys, held_through, presence_run
from wetdump import wet_case_frames


@pytest.mark.parametrize("k", [1, 2, 7, 300])
def test_stable_key_order_is_mergesort_argsort(k):
    rng = np.random.default_rng(k)
    keys = rng.integers(0, k * k, size=4000)
    np.testing.assert_array_equal(_stable_key_order(keys, k), np.argsort(keys, kind="mergesort"))
    np.testing.assert_array_equal(_stable_key_order(keys[:0], k), np.zeros(0, np.int64))


def test_presence_runs_equal_window_intersections():
    """Random bridge sets over 12 frames, windows of 1-5 frames: the same held set."""
    rng = np.random.default_rng(3)
    frames = [np.unique(rng.integers(0, 400, size=300)) for _ in range(12)]
    runs, prev = [], None
    for f in frames:
        runs.append(presence_run(f, prev, runs[-1] if runs else None))
        prev = f
    for span in range(5):
        for k in range(len(frames) - span):
            held = frames[k + span][runs[k + span] >= span + 1]
            np.testing.assert_array_equal(held, held_through(frames[k:k + span + 1]))


@pytest.fixture(scope="module")
def real(engine, tmp_path_factory):
    case, facts, frames = wet_case_frames(engine, tmp_path_factory)
    return case.scaled, facts, frames


@pytest.mark.engine
def test_louvain_with_stay_proofs_equals_reference_on_tiled_real_frames(real):
    scaled, facts, frames = real
    for p, c in frames[-3:]:
        pt, ct = tiled(p, c, 4, scaled.drum.length)
        i, j, w, nw = cpm_weights(pt, ct, facts.liquid, scaled.cg)
        for gamma in (0.001, 0.002, 0.004):
            np.testing.assert_array_equal(cpm_labels(len(pt), i, j, w, nw, gamma, seed=1),
                                          cpm_labels_reference(len(pt), i, j, w, nw, gamma,
                                                               seed=1))


@pytest.mark.engine
def test_rupture_work_table_returns_the_bits_of_each_pair_alone(real):
    """Tiled 4x, every touching pair of a copy has equals in the other copies."""
    scaled, facts, frames = real
    p, c = tiled(*frames[-1], 4, scaled.drum.length)
    i, j, _, rows = bonded_contacts(p, c, facts.liquid, BondCriterion(0.0, 180.0),
                                    with_rows=True)
    gap = -c.delta[rows]
    assert np.sum(gap <= 0) > 10
    batch = relative_energy(p, i, j, gap, facts.liquid)
    alone = np.array([relative_energy(p, i[k:k + 1], j[k:k + 1], gap[k:k + 1], facts.liquid)[0]
                      for k in range(len(i))])
    np.testing.assert_array_equal(batch.view(np.int64), alone.view(np.int64))


@pytest.mark.engine
def test_presence_runs_on_real_bridges(real):
    scaled, facts, frames = real
    keys = [bridge_keys(Frame(p, c), facts.liquid) for p, c in frames]
    runs = [presence_run(keys[0], None, None)]
    for k in range(1, len(keys)):
        runs.append(presence_run(keys[k], keys[k - 1], runs[-1]))
    for span in (1, 3):
        for k in range(len(keys) - span):
            np.testing.assert_array_equal(keys[k + span][runs[k + span] >= span + 1],
                                          held_through(keys[k:k + span + 1]))
