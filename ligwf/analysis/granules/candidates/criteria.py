"""What a candidate definition gives on a case's frames (:func:`run_spec`) and the
acceptance criteria (a)-(e) it is measured against (:func:`measure`): (a) no percolating
granule and no granule holding the bed, (b) d50 robust to each threshold moved by 20 %,
(c) the GSD unchanged when the periodic slice is tiled, (d) d50 following the process
series, (e) d50 the same at CG level n as at CG1."""

from __future__ import annotations

import math
import time
import zlib
from dataclasses import dataclass

import numpy as np

from ligwf.analysis.granules.candidates.frames import Case
from ligwf.analysis.granules.candidates.specs import Evaluator, Spec


def frame_metrics(labels, perc, vprim):
    """largest share (volume), any percolating granule, d50 (m, granules >= 2), mean size
    (particles) of granules >= 2, and the volumes of the granules >= 2 (m^3)."""
    members = np.bincount(labels)
    vol = np.bincount(labels, weights=vprim)
    flag = np.zeros(len(members), bool)
    np.logical_or.at(flag, labels, perc)
    big = members >= 2
    largest = vol.max() / vol.sum()
    anyperc = bool(np.any(flag & big))
    return largest, anyperc, d50_of(vol[big]), float(members[big].mean()) if big.any() else 1.0, vol[big]


def d50_of(vols, cut=0.0):
    """Volume-weighted median volume-equivalent diameter (m) of the granules >= cut (m^3)."""
    v = np.sort(vols[vols >= cut])
    if len(v) == 0:
        return float("nan")
    cum = np.cumsum(v) / v.sum()
    return float(np.cbrt(6.0 * v[min(np.searchsorted(cum, 0.5 - 1e-12), len(v) - 1)] / math.pi))


def boot_band(x, nboot, rng, conf=0.95):
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    if len(x) == 0:
        return float("nan"), float("nan"), float("nan")
    draws = x[rng.integers(len(x), size=(nboot, len(x)))].mean(axis=1)
    a = 50 * (1 - conf)
    return float(x.mean()), float(np.percentile(draws, a)), float(np.percentile(draws, 100 - a))


EDGES_PER_DECADE = 5


def gsd_rows(vols_per_frame, vp):
    """Volume-weighted GSD per frame on decade-aligned log bins of granule volume."""
    lo = math.floor(math.log10(vp) * EDGES_PER_DECADE - 0.5) + 0.5
    edges = 10.0 ** (np.arange(lo, lo + 8 * EDGES_PER_DECADE + 1) / EDGES_PER_DECADE)
    rows = []
    for v in vols_per_frame:
        idx = np.clip(np.searchsorted(edges, v, side="right") - 1, 0, len(edges) - 2)
        h = np.bincount(idx, weights=v, minlength=len(edges) - 1)
        rows.append(h / h.sum() if h.sum() > 0 else h)
    return np.array(rows)


def run_spec(ev: Evaluator, spec: Spec, frames=None, tiles=1):
    """Per steady frame (or ``frames``) of the evaluator's case, tiled ``tiles`` times:
    :func:`frame_metrics` and the time (s) the bonds and partition took."""
    frames = ev.case.steady if frames is None else frames
    out = {"largest": [], "perc": [], "d50": [], "mean_size": [], "vols": [], "time": []}
    for idx in frames:
        t0 = time.perf_counter()
        res = ev.partition(idx, spec, tiles)
        dt = time.perf_counter() - t0
        if res is None:
            continue
        labels, perc, n, vprim = res
        lg, pc, d50, ms, vols = frame_metrics(labels, perc, vprim)
        for k, v in zip(("largest", "perc", "d50", "mean_size", "vols", "time"),
                        (lg, pc, d50, ms, vols, dt)):
            out[k].append(v)
    return out



@dataclass(frozen=True)
class Measurement:
    """How the criteria are measured: ``boot`` bootstrap draws, the slice tiled ``tiles``
    times for (c), community methods on tiled frames using every ``community_stride``-th
    steady frame."""

    boot: int = 1000
    tiles: tuple[int, ...] = (2, 4)
    community_stride: int = 2


def common_cut(cases: list[Case]) -> float:
    """The common size cut of (e): granules of >= 2 particles of the coarsest level (m^3)."""
    return 2.0 * max(float(c.frames[0].vprim.max()) for c in cases)


def measure(spec: Spec, evaluators: dict[int, Evaluator], base: Case, series: list[Case],
            cgs: list[Case], cut: float, how: Measurement) -> dict:
    """The criteria (a)-(e) of ``spec``: on ``base`` (a)-(c), on the process ``series`` (d)
    and on its CG-n twin ``cgs`` (e); ``evaluators`` by ``id(case)``. One generator per
    candidate: its bands do not depend on which others run."""
    ev = evaluators
    rng = np.random.default_rng([12345, zlib.crc32(spec.name.encode())])
    comm = spec.part != "cc"
    r = {"spec": spec}
    res = run_spec(ev[id(base)], spec)
    r["perc_frac"] = float(np.mean(res["perc"]))
    r["largest"] = float(np.mean(res["largest"]))
    r["d50"] = boot_band(res["d50"], how.boot, rng)
    r["mean_size"] = float(np.mean(res["mean_size"]))
    r["t_frame"] = float(np.median(res["time"]))
    r["a"] = (1 - r["perc_frac"]) >= 0.9 and r["largest"] < 0.10
    # (b) sensitivity
    ratios = []
    for label, p in spec.perturbations():
        rp_ = run_spec(ev[id(base)], p)
        d = np.nanmean(rp_["d50"]) if np.isfinite(rp_["d50"]).any() else float("nan")
        ratios.append((label, d / r["d50"][0]))
    r["sens"] = ratios
    worst = max((max(x, 1 / x) for _, x in ratios if math.isfinite(x) and x > 0), default=float("nan"))
    r["b_worst"] = worst
    r["b"] = bool(math.isfinite(worst) and worst < 1.5) if ratios else None
    # (c) tiling
    frames = base.steady[::how.community_stride] if comm else base.steady
    ref = run_spec(ev[id(base)], spec, frames=frames)
    vp = float(base.frames[0].vprim.min())
    g1 = gsd_rows(ref["vols"], vp)
    draws = g1[rng.integers(len(g1), size=(how.boot, len(g1)))].mean(axis=1)
    blo, bhi = np.percentile(draws, 2.5, axis=0), np.percentile(draws, 97.5, axis=0)
    d1 = boot_band(ref["d50"], how.boot, rng)
    tiles = {}
    for m in how.tiles:
        t = run_spec(ev[id(base)], spec, frames=frames, tiles=m)
        gm = gsd_rows(t["vols"], vp).mean(axis=0)
        dev = np.abs(gm - g1.mean(axis=0))
        half = 0.5 * (bhi - blo)
        with np.errstate(divide="ignore", invalid="ignore"):
            q = np.where(dev > 1e-9, dev / half, 0.0)
        outside = float(np.nanmax(q))        # GSD change / half band, worst bin
        tiles[m] = (float(np.nanmean(t["d50"])), float(outside), float(np.mean(t["mean_size"])),
                    float(np.mean(t["largest"])))
    r["tiles"] = tiles
    r["d50_1x"] = d1
    r["c"] = all(v[1] <= 1.0 for v in tiles.values())

    # (d) process response, (e) CG
    def summary(c):
        rr = run_spec(ev[id(c)], spec)
        return (boot_band(rr["d50"], how.boot, rng), float(np.mean(rr["largest"])),
                float(np.mean(rr["perc"])),
                boot_band([d50_of(v, cut) for v in rr["vols"]], how.boot, rng))

    dser = [summary(c) for c in series]
    r["series"] = dser
    if len(dser) >= 3:
        m = [x[0] for x in dser]
        up = all(m[k][1] > m[k - 1][2] for k in range(1, len(m)))
        down = all(m[k][2] < m[k - 1][1] for k in range(1, len(m)))
        r["d"] = up or down
    else:
        r["d"] = None
    dcg = [summary(c) for c in cgs]
    r["cg"] = dcg
    if dcg and len(dcg) == len(dser):
        r["cg_ratio_plain"] = [c[0][0] / s[0][0] for c, s in zip(dcg, dser)]
        q = [c[3][0] / s[3][0] for c, s in zip(dcg, dser)]
        r["cg_ratio"] = q
        # CG-neutral: the CGn/CG1 d50 ratio within a factor 1.5 at every condition, both
        # with each level's own >= 2 particle cut and with the common cut
        r["e"] = all(math.isfinite(x) and 1 / 1.5 < x < 1.5 for x in q + r["cg_ratio_plain"])
    else:
        r["cg_ratio"], r["e"] = [], None
    return r
