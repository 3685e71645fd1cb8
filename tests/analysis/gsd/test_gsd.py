"""ligwf.analysis.gsd.bins: bins, distributions, percentiles, bootstrap bands, CG comparison."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from types import SimpleNamespace

from ligwf.analysis.gsd import bins as gsd
from ligwf.analysis.gsd.tables import gsd_tables
from ligwf.scene.settings import AnalysisSettings

V1 = math.pi / 6 * 0.001**3      # one 1 mm primary particle, m^3


def test_log_edges_cover_and_align():
    e = gsd.log_edges(V1, 3e-6, 5)
    assert e[0] <= V1 < e[1] and e[-1] > 3e-6
    np.testing.assert_allclose(np.diff(np.log10(e)), 0.2)
    # decade aligned: a bin centre at 1e-9
    assert np.any(np.isclose(np.sqrt(e[:-1] * e[1:]), 1e-9))


def test_histogram_and_percentiles():
    v = np.array([V1] * 11 + [89 * V1])
    edges = gsd.log_edges(v.min(), v.max(), 5)
    num, vol = gsd.histogram(v, edges)
    assert num.sum() == pytest.approx(1) and vol.sum() == pytest.approx(1)
    assert num[0] == pytest.approx(11 / 12) and vol[0] == pytest.approx(0.11)
    d10, d50, d90 = gsd.percentile_diameters(v)
    assert d10 == pytest.approx(0.001)                     # 11% of the volume is singletons
    assert d50 == d90 == pytest.approx(0.001 * 89 ** (1 / 3))


def test_bootstrap_band_deterministic_and_covers_mean():
    rng = np.random.default_rng(0)
    rows = rng.uniform(size=(12, 4))
    reps = np.repeat([0, 1, 2], 4)
    a = gsd.bootstrap_means(rows, reps, 300, np.random.default_rng(7))
    b = gsd.bootstrap_means(rows, reps, 300, np.random.default_rng(7))
    np.testing.assert_array_equal(a, b)
    lo, hi = gsd.band(a, 0.95)
    assert np.all(lo <= rows.mean(0)) and np.all(rows.mean(0) <= hi) and np.all(lo < hi)
    # a single frame has no spread
    lo1, hi1 = gsd.band(gsd.bootstrap_means(rows[:1], reps[:1], 50, rng), 0.95)
    np.testing.assert_array_equal(lo1, hi1)


def test_side_errors_and_limit():
    ref = np.array([0.5, 0.3, 0.2, 0.0])
    cg = np.array([0.2, 0.4, 0.2, 0.2])
    below = gsd.below_limit(np.array([1.0, 10, 100, 1000, 10000]), 50.0)
    assert below.tolist() == [True, True, False, False]
    eb, ea = gsd.side_errors(cg, ref, below)
    assert eb == pytest.approx(0.4 / 0.8) and ea == pytest.approx(0.2 / 0.2)
    rel = gsd.relative_error(cg, ref)
    assert rel[0] == pytest.approx(-0.6) and math.isnan(rel[3])


def _case(case_id, cg, rule, replica):
    return SimpleNamespace(case_id=case_id, cg=cg, rule=rule, replica=replica, group="{}")


def _table(case, frames, sizes_in_primaries, percolating=()):
    """Granules of physical volume s * V1 (the same at every CG level: CG-neutral)."""
    rows = []
    for f in range(frames):
        for k, s in enumerate(list(sizes_in_primaries) + list(percolating)):
            vol = s * V1
            rows.append({"case_id": case.case_id, "cg": case.cg, "rule": case.rule,
                         "replica": case.replica, "frame": f, "step": 100 * f, "time": 0.0,
                         "granule": k, "members": max(1, round(s / case.cg**3)),
                         "volume": vol, "primary_volume": vol / case.cg**3,
                         "percolating": k >= len(sizes_in_primaries)})
    return pd.DataFrame(rows)


def test_located_limit():
    edges = np.array([1.0, 10, 100, 1000, 10000])
    ref = np.array([0.2, 0.3, 0.3, 0.2])
    # CG-n off by 50 % in the two smallest bins, within 10 % above: limit at the third bin
    cg = np.array([0.1, 0.45, 0.28, 0.19])
    assert gsd.located_limit(edges, cg, ref, 0.15) == 100.0
    assert gsd.located_limit(edges, ref, ref, 0.15) == 1.0            # all within: first bin
    assert math.isnan(gsd.located_limit(edges, ref * [1, 1, 1, 2], ref, 0.15))  # top bin off
    # a bin with < 1 % of the reference volume does not move the limit
    ref2 = np.array([0.005, 0.395, 0.4, 0.2])
    assert gsd.located_limit(edges, ref2 * [5, 1, 1, 1], ref2, 0.15) == 10.0
    rows = gsd.located_limit(edges, np.stack([cg, ref]), np.stack([ref, ref]), 0.15)
    assert rows.tolist() == [100.0, 1.0]


def test_cg_comparison_identical_gsd_has_zero_error():
    """CG2 granules with the same physical volumes as CG1: error 0 everywhere, the limit
    at the smallest bin; single particles and percolating granules stay out of the GSD
    and the percolating ones are reported on their own."""
    sizes = [1, 1, 16, 16, 16, 32, 64, 200, 800]
    sizes2 = [64, 200, 800]                  # replica b lacks the small granules
    c1, c2a, c2b = _case("cg1", 1.0, "none", 0), _case("a", 2.0, "weber", 0), _case("b", 2.0, "weber", 1)
    table = pd.concat([_table(c1, 3, sizes, percolating=[5000]), _table(c2a, 3, sizes[2:]),
                       _table(c2b, 2, sizes2)])
    settings = AnalysisSettings(bootstrap=200)
    # replica b differs: without it the comparison is exact
    dist, summary = gsd_tables(table[table.case_id != "b"], [c1, c2a, c2b], settings)
    s = summary.set_index("condition")
    row = s.loc["cg2-weber"]
    assert row["error_above_lower"] == 0 == row["error_all"] and row["error_band"] == 0.15
    assert row["lower_limit"] == pytest.approx(dist["v_lo"].min())
    assert row["reference"] == "cg1"
    assert s.loc["cg1", "percolating_frames"] == 1 and row["percolating_frames"] == 0
    total = sum(sizes) + 5000
    assert s.loc["cg1", "percolating_share"] == pytest.approx(5000 / total)
    assert s.loc["cg1", "granule_share"] == pytest.approx((total - 5000 - 2) / total)
    d = dist[dist.condition == "cg2-weber"]
    assert np.nanmax(np.abs(d["rel_error"])) == 0
    assert dist["v_hi"].max() < 5000 * V1 and dist["v_lo"].min() > V1     # left out
    # with replica b the small sizes are missing: the limit moves up, the error below grows
    dist, summary = gsd_tables(table, [c1, c2a, c2b], settings)
    row = summary.set_index("condition").loc["cg2-weber"]
    assert row["error_below_lower"] > 0.05 and row["replicas"] == 2 and row["frames"] == 5
    assert row["lower_limit"] > 32 * V1
    assert row["lower_limit_lo"] <= row["lower_limit"] <= row["lower_limit_hi"]
    assert row["error_below_lower_lo"] <= row["error_below_lower"] <= row["error_below_lower_hi"]
    assert row["error_all_lo"] <= row["error_all"] <= row["error_all_hi"]
    for cond, d in dist.groupby("condition"):
        assert d["volume_fraction"].sum() == pytest.approx(1)
        assert d["number_fraction"].sum() == pytest.approx(1)


def test_no_lower_limit_is_stated_not_silently_below():
    """CG2 granules all in other bins than CG1's: no lower limit is located (nan), every
    bin is below it (``below_lower_limit``), the error below it is the whole GSD's
    (``error_all``) and the error above it is nan (no bin there) -- the names say which
    limit, and the nan case reads as "all bins", not as some finite limit's "below"."""
    c1, c2 = _case("cg1", 1.0, "none", 0), _case("a", 2.0, "weber", 0)
    table = pd.concat([_table(c1, 3, [16, 16, 20]), _table(c2, 3, [800, 900])])
    dist, summary = gsd_tables(table, [c1, c2], AnalysisSettings(bootstrap=50))
    row = summary.set_index("condition").loc["cg2-weber"]
    assert math.isnan(row["lower_limit"])
    assert row["error_below_lower"] == pytest.approx(row["error_all"]) == pytest.approx(2.0)
    assert math.isnan(row["error_above_lower"])
    assert dist[dist.condition == "cg2-weber"]["below_lower_limit"].all()


def test_primary_volume_convention_bins_volume_over_n3():
    """gsd_volume: primary (the source study): CG-n granule volumes are divided by n^3, so
    a CG2 table whose physical volumes equal CG1's comes out 8x smaller; the physical
    convention compares them as they are."""
    sizes = [16, 16, 32, 64, 200]
    c1, c2 = _case("cg1", 1.0, "none", 0), _case("a", 2.0, "weber", 0)
    table = pd.concat([_table(c1, 2, sizes), _table(c2, 2, sizes)])
    physical = AnalysisSettings(bootstrap=50)
    primary = AnalysisSettings(bootstrap=50, gsd_volume="primary")
    _, s_phys = gsd_tables(table, [c1, c2], physical)
    _, s_prim = gsd_tables(table, [c1, c2], primary)
    phys, prim = s_phys.set_index("condition"), s_prim.set_index("condition")
    assert phys.loc["cg2-weber", "d50"] == pytest.approx(phys.loc["cg1", "d50"])
    assert prim.loc["cg2-weber", "d50"] == pytest.approx(prim.loc["cg1", "d50"] / 2)
    assert prim.loc["cg1", "d50"] == pytest.approx(phys.loc["cg1", "d50"])
    with pytest.raises(ValueError, match="gsd_volume"):
        AnalysisSettings(gsd_volume="mass")


def test_bands_respect_frame_autocorrelation():
    """An AR(1) frame series (correlation 0.8 from frame to frame): the block bootstrap's
    95 % band is wider than a band that treats frames as independent, and its half-width
    is not below the within-run standard error (autocorrelation counted). Measured: 0.84x
    of +-1.96 standard errors (moving blocks of 2 tau under-resample slow drifts a little)."""
    from ligwf.analysis.records.intervals import within_run_se

    rng = np.random.default_rng(11)
    x = np.zeros(400)
    for k in range(1, len(x)):
        x[k] = 0.8 * x[k - 1] + rng.normal()
    rows = x[:, None]
    reps = np.zeros(len(x), dtype=int)
    lo, hi = gsd.band(gsd.bootstrap_means(rows, reps, 2000, np.random.default_rng(1)), 0.95)
    assert gsd.block_lengths(rows, reps)[0] >= 5
    iid = x[np.random.default_rng(2).integers(len(x), size=(2000, len(x)))].mean(axis=1)
    iid_lo, iid_hi = np.percentile(iid, [2.5, 97.5])
    assert hi[0] - lo[0] > 1.5 * (iid_hi - iid_lo)
    assert hi[0] - lo[0] >= 0.75 * 2 * 1.96 * within_run_se(x)
