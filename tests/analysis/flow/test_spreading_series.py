"""The spreading series of placed liquid (ligwf.analysis.flow.spreading): on frames whose
liquid is known, the dry particles' share and the spreading time come out as constructed."""

import math
from pathlib import Path

import numpy as np
import pytest

from ligwf.analysis.flow.spreading import (DRY_FRACTION, WET, spread_series,
                                           time_to_share)
from ligwf.analysis.frames.dumps import ParticleFrame


def frame(t, content, radii=None, order=None):
    n = len(content)
    ids = np.arange(1, n + 1)
    radii = np.full(n, 1e-3) if radii is None else np.asarray(radii, float)
    content = np.asarray(content, float)
    if order is not None:                         # dumps are sorted by id; ids may be sparse
        ids = ids[order]
    return ParticleFrame(Path("x.vtu"), 0, t, ids, np.ones(n, np.int32), np.zeros((n, 3)),
                         np.zeros((n, 3)), radii, content)


def test_share_goes_from_zero_to_one_as_the_liquid_evens_out():
    placed = 0.05
    start = [placed, placed, 0, 0, 0, 0, 0, 0]
    half = [0.03, 0.03, 0.01, 0.01, 0.01, 0.01, 0.0, 0.0]      # same total liquid
    even = [0.0125] * 8
    s = spread_series([frame(0.0, start), frame(0.5, half), frame(1.0, even)], placed, 0.5)
    assert s.dry_particles == 6 and s.particles == 8
    assert s.revolutions == (0.0, 1.0, 2.0)
    assert s.dry_content_share[0] == 0.0
    # dry mean 0.04 / 6, overall mean 0.1 / 8
    assert s.dry_content_share[1] == pytest.approx((0.04 / 6) / (0.1 / 8))
    assert s.dry_content_share[2] == pytest.approx(1.0)
    assert s.dry_wet_share == (0.0, 4 / 6, 1.0)


def test_volume_weighted_with_unequal_particles():
    """Content is a fraction of a particle's volume: the shares weight by volume."""
    placed = 0.05
    radii = [2e-3, 1e-3, 1e-3]
    s = spread_series([frame(0.0, [placed, 0, 0], radii),
                       frame(1.0, [0.02, 0.1, 0.0], radii)], placed, 1.0)
    v = np.array(radii) ** 3
    liquid = np.array([0.02, 0.1, 0.0]) * v
    expect = (liquid[1:].sum() / v[1:].sum()) / (liquid.sum() / v.sum())
    assert s.dry_content_share[1] == pytest.approx(expect)


def test_nearly_dry_particles_count_as_dry_and_wet_threshold_is_the_engines():
    placed = 0.05
    tiny = 0.5 * WET                 # below both the dry threshold and the engine's wet one
    assert tiny < DRY_FRACTION * placed
    s = spread_series([frame(0.0, [placed, tiny, 0.0]), frame(1.0, [placed, tiny, 2 * WET])],
                      placed, 1.0)
    assert s.dry_particles == 2
    assert s.dry_wet_share == (0.0, 0.5)     # the tiny one stays below WET, the other is above


@pytest.mark.parametrize("content", [[0.05, 0.05], [0.0, 0.0]])
def test_nothing_to_measure_without_both_wet_and_dry_particles(content):
    assert spread_series([frame(0.0, content)], 0.05, 1.0) is None


def test_no_liquid_column_or_no_frames_gives_none():
    f = frame(0.0, [0.05, 0.0])
    dry = ParticleFrame(f.path, 0, 0.0, f.ids, f.types, f.positions, f.velocities, f.radii,
                        None)
    assert spread_series([dry], 0.05, 1.0) is None
    assert spread_series([], 0.05, 1.0) is None


def test_time_to_share_interpolates_and_censors():
    assert time_to_share([0, 1, 2], [0.0, 0.2, 0.4], 0.25) == (pytest.approx(1.25), False)
    assert time_to_share([0, 1, 2], [0.0, 0.1, 0.2], 0.25) == (2.0, True)
    assert time_to_share([0, 1], [0.3, 0.5], 0.25) == (0.0, False)
    t, censored = time_to_share([], [], 0.25)
    assert math.isnan(t) and censored
    # a nan frame is skipped, not read as a crossing: interpolated across the gap
    assert time_to_share([0, 1, 2], [0.0, math.nan, 0.5], 0.25) == (pytest.approx(1.0), False)
