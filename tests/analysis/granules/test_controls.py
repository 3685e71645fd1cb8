"""The control measures (ligwf.analysis.granules.controls) against slow obvious pair enumerations."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ligwf.analysis.granules.controls import (adjusted_rand_index, bed_share, comovement, granule_count,
                                     pair_persistence, volume_d50)


def _pair_sets(labels):
    return {(a, b) for a, b in itertools.combinations(range(len(labels)), 2)
            if labels[a] == labels[b]}


def _ari_reference(a, b):
    """ARI from the four pair counts (Hubert & Arabie), every pair enumerated."""
    n = len(a)
    pairs = n * (n - 1) / 2
    sa, sb = _pair_sets(a), _pair_sets(b)
    both = len(sa & sb)
    expected = len(sa) * len(sb) / pairs
    maximum = 0.5 * (len(sa) + len(sb))
    return 1.0 if maximum == expected else (both - expected) / (maximum - expected)


def test_ari_hand_value_and_label_names():
    assert adjusted_rand_index([0, 0, 0, 1, 1, 1], [0, 0, 1, 1, 2, 2]) == pytest.approx(0.8 / 3.3)
    assert adjusted_rand_index([0, 0, 1, 1, 2], [7, 7, 3, 3, 9]) == 1.0


@pytest.mark.parametrize("seed", range(5))
def test_ari_and_persistence_match_pair_enumeration(seed):
    rng = np.random.default_rng(seed)
    a = rng.integers(0, 6, 40)
    b = np.where(rng.random(40) < 0.7, a, rng.integers(0, 6, 40))
    assert adjusted_rand_index(a, b) == pytest.approx(_ari_reference(a, b), abs=1e-12)
    sa, sb = _pair_sets(a), _pair_sets(b)
    assert pair_persistence(a, b) == pytest.approx(len(sa & sb) / len(sa), abs=1e-12)


def test_random_relabelling_has_ari_near_zero():
    rng = np.random.default_rng(3)
    a = rng.integers(0, 20, 4000)
    assert abs(adjusted_rand_index(a, rng.permutation(a))) < 0.02


def test_persistence_of_singletons_is_undefined():
    assert np.isnan(pair_persistence(np.arange(5), np.zeros(5, int)))


def test_share_count_and_d50():
    labels = np.array([0] * 10 + [1] * 3 + list(range(2, 7)))
    vol = np.ones(len(labels))
    assert bed_share(labels, vol, 10) == pytest.approx(10 / 18)
    assert bed_share(labels, vol, 2) == pytest.approx(13 / 18)
    assert granule_count(labels, 2) == 2
    # volume-weighted median of granules >= 2: the 10-volume granule holds 10/13 of it
    assert volume_d50(labels, vol, 2) == pytest.approx((6 * 10 / np.pi) ** (1 / 3))


def test_comovement_separates_rigid_granules_from_a_diffusing_bed():
    """Members of rigidly moving clusters keep their distances; a bed whose particles
    jitter independently does not: ratio ~0 for the clusters, ~1 for a random tiling."""
    rng = np.random.default_rng(7)
    d = 1e-3
    centres = rng.uniform(0, 30 * d, (40, 3))
    offsets = rng.normal(0, 0.8 * d, (40, 12, 3))
    pos = (centres[:, None, :] + offsets).reshape(-1, 3)
    labels = np.repeat(np.arange(40), 12)
    shift = rng.normal(0, 0.5 * d, (40, 3))
    moved = pos + np.repeat(shift, 12, axis=0)         # each cluster translates rigidly
    rigid = comovement(labels, pos, moved, d, None, 0.0)
    assert rigid.ratio < 0.05
    jitter = pos + rng.normal(0, 0.3 * d, pos.shape)    # every particle on its own
    tiled = comovement(labels, pos, jitter, d, None, 0.0)
    assert 0.8 < tiled.ratio < 1.25


def test_comovement_uses_the_nearest_periodic_image():
    """A pair straddling the periodic boundary is at its short distance, and a translation
    across the boundary does not change it."""
    d, length = 1e-3, 10e-3
    pos = np.array([[0.0, 0.2e-3, 0.0], [0.0, 9.9e-3, 0.0], [5e-3, 5e-3, 5e-3], [5.5e-3, 5e-3, 5e-3]])
    moved = pos.copy()
    moved[:, 1] = np.mod(pos[:, 1] + 0.5e-3, length)
    moved[3, 0] += 0.5e-3                                # the non-member pair moves apart
    cm = comovement(np.array([0, 0, 1, 2]), pos, moved, d, 1, length)
    assert cm.member_pairs == 1 and cm.member_growth == pytest.approx(0.0, abs=1e-9)
    assert cm.nonmember_growth == pytest.approx(0.5e-3, rel=1e-6)
