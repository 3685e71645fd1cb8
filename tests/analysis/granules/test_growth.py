"""ligwf.analysis.granules.growth: the pieces that decide whether a granule grows, survives and
is more than a wall layer, on arrays whose answer is known by hand."""

from __future__ import annotations

import numpy as np
import pytest

from ligwf.analysis.granules.growth import (GrowthSettings, big_labels, hac_slope, survival,
                                            track, volume_d50_particles, wall_shares)
from ligwf.errors import ConfigError


def test_big_labels_splits_small_granules_into_singletons():
    labels = np.array([0, 0, 0, 1, 1, 2])
    out = big_labels(labels, 3)
    assert list(out[:3]) == [0, 0, 0]
    assert len(set(out[3:])) == 3 and all(out[3:] < 0)


def test_survival_counts_only_pairs_of_big_granules():
    # t: a granule of 4 (rows 0-3) and one of 2 (rows 4-5, below min size 3)
    t = np.array([0, 0, 0, 0, 1, 1, 2])
    # u: rows 0,1 still together, 2,3 together elsewhere: 2 of the 6 pairs survive
    u = np.array([5, 5, 6, 6, 1, 1, 2])
    assert survival(t, u, 3) == pytest.approx(2 / 6)
    assert survival(t, t, 3) == 1.0
    assert survival(t, np.arange(7), 3) == 0.0
    assert np.isnan(survival(np.arange(7), t, 3))


def test_track_classifies_accretion_erosion_breakage_coalescence():
    n = 40
    a = np.arange(n) + 100                  # singletons by default
    b = np.arange(n) + 200
    a[0:10] = 1                             # granule 1: rows 0-9
    b[0:12] = 7                             # ... continues as 7 with rows 10, 11 accreted
    a[12:24] = 2                            # granule 2: rows 12-23
    b[12:18], b[18:24] = 8, 9               # ... breaks in two
    a[24:30], a[30:36] = 3, 4               # granules 3 and 4 (6 each)
    b[24:36] = 10                           # ... coalesce
    ev = track(a, b, 5)
    assert ev.continued == 1
    assert ev.broke == 1 and ev.coalesced == 1
    assert ev.born == 0 and ev.died == 0
    assert ev.accreted == 2                 # rows 10, 11 joined 7
    assert ev.eroded == 0
    # granule 1 dissolves: a death and its members eroded
    ev2 = track(a, np.arange(n) + 300, 5)
    assert ev2.died == 4 and ev2.eroded == 0 and ev2.dispersed == 10 + 12 + 6 + 6


def test_volume_d50_in_particles():
    labels = np.array([0] * 8 + [1] * 2 + [2])   # granules of 8 and 2, one singleton
    vol = np.ones(11)
    # 10 particles in granules: the median particle sits in the 8-granule
    assert volume_d50_particles(labels, vol, 2) == 8.0
    assert np.isnan(volume_d50_particles(np.arange(5), np.ones(5), 2))


def test_wall_shares_against_the_bed():
    # drum axis y, radius 1: rows 0-1 at the wall (r = 0.95), rows 2-3 inside (r = 0.2)
    pos = np.array([[0.95, 0, 0], [0, 0.3, 0.95], [0.2, 0, 0], [0, 0, 0.2]])
    vol = np.ones(4)
    labels = np.array([0, 0, 1, 2])           # the granule is at the wall
    g, bed = wall_shares(pos, vol, labels, 1, 1.0, 0.1, 2)
    assert g == 1.0 and bed == 0.5
    g, bed = wall_shares(pos, vol, np.array([0, 1, 2, 2]), 1, 1.0, 0.1, 2)
    assert g == 0.0


def test_hac_slope_recovers_a_trend_and_widens_for_correlated_noise():
    rng = np.random.default_rng(3)
    t = np.linspace(0, 10, 100)
    y = 0.02 * t + rng.normal(0, 0.01, 100)
    s = hac_slope(t, y, lag=1)
    assert s.low < 0.02 < s.high and s.low > 0
    # no trend, AR(1) noise with phi 0.9: the HAC interval is wider than the white-noise one
    e = np.zeros(100)
    for k in range(1, 100):
        e[k] = 0.9 * e[k - 1] + rng.normal(0, 0.01)
    narrow, wide = hac_slope(t, e, lag=0), hac_slope(t, e, lag=10)
    assert wide.high - wide.low > 1.5 * (narrow.high - narrow.low)
    assert np.isnan(hac_slope(t[:2], y[:2], 1).slope)


def test_hac_slope_covers_a_null_slope_about_95_percent():
    """Coverage on the data it is used on: overlapping-window shares are AR-like."""
    rng = np.random.default_rng(7)
    t = np.arange(90) * 0.1
    hits = 0
    trials = 300
    for _ in range(trials):
        e = np.zeros(90)
        for k in range(1, 90):
            e[k] = 0.6 * e[k - 1] + rng.normal(0, 0.01)
        s = hac_slope(t, e, lag=6)
        hits += s.low <= 0.0 <= s.high
    assert 0.85 <= hits / trials <= 0.99


@pytest.mark.parametrize("field, value", [("hold_time", 0.0), ("cadence", float("nan")),
                                          ("stride", -1.0), ("cadence", 1.0)])
def test_settings_refuse_bad_times(field, value):
    with pytest.raises(ConfigError, match=field):
        GrowthSettings(**{field: value})
