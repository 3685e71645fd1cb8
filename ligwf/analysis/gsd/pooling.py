"""Does pooling CG-n replicas move the GSD size limit? The source study's proposed fix for
the poor large-granule statistics of CG ("sufficient CG particles or ensembles"), measured.

For each CG-n condition with R replicas and each pool size K (R // K disjoint pools of K
replicas, in replica order), the pool's steady frames are compared with the CG1 reference
of the same sweep group (all its replicas pooled): the volume-weighted GSD per bin, the
size limits located from the data with bootstrap intervals, and the relative L1 errors on
either side. Two limits, because the error can leave the band at either end:

* ``upper_limit`` (the source study's): the upper edge of the largest bin up to which every
  used bin is within the band (CG-n good BELOW it; nan when the smallest used bin is
  already outside);
* ``lower_limit`` (:func:`ligwf.analysis.gsd.bins.located_limit`): the lower edge of the
  smallest bin from which on every used bin is within the band (CG-n good ABOVE it: a CG
  level cannot resolve granules smaller than a few of its own particles).

"Used" bins hold >= :data:`ligwf.analysis.gsd.bins.MIN_BIN_SHARE` of the CG1 granule volume.
The same comparison of one CG1 replica against the others (K = 1, rule ``noise floor``)
gives the errors CG1 makes against itself: a CG error within them is not a CG error.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import pandas as pd

from ligwf.analysis.gsd import bins as gsdmod
from ligwf.scene.settings import AnalysisSettings
from ligwf.analysis.records.conditions import CaseLike, Conditions

#: Columns of the pooling table (one row per condition, pool size and pool).
POOLING_COLUMNS = ["condition", "group", "cg", "rule", "k", "pool", "replicas", "frames",
                   *[f"{q}{s}" for q in ("upper_limit", "lower_limit")
                     for s in ("", "_lo", "_hi")],
                   *[f"error_{side}_{lim}{s}" for lim in ("upper", "lower")
                     for side in ("below", "above") for s in ("", "_lo", "_hi")],
                   "error_band"]


def pools(replicas: Sequence[int], k: int) -> list[tuple[int, ...]]:
    """``len(replicas) // k`` disjoint pools of ``k`` replicas, in sorted replica order."""
    if k < 1:
        raise ValueError(f"pool size k = {k}: must be >= 1")
    reps = sorted(set(replicas))
    return [tuple(reps[p * k:(p + 1) * k]) for p in range(len(reps) // k)]


def upper_limit(edges: np.ndarray, cg: np.ndarray, ref: np.ndarray, error_band: float,
                min_share: float = gsdmod.MIN_BIN_SHARE) -> np.ndarray:
    """The source study's limit (m^3), per row of ``cg`` / ``ref`` (volume-weighted GSDs,
    (..., bins)): the upper edge of the largest bin up to which every used bin has
    |cg - ref| <= ``error_band`` x ref; nan when the smallest used bin is outside."""
    misses = gsdmod.band_misses(cg, ref, error_band, min_share)
    out = np.full(len(misses), np.nan)
    for r, (used, bad) in enumerate(misses):
        if len(used) == 0 or bad[0]:
            continue
        last_ok = used[np.flatnonzero(bad)[0] - 1] if bad.any() else used[-1]
        out[r] = edges[last_ok + 1]
    return out if np.ndim(cg) > 1 else out[0]


def _below_upper(edges: np.ndarray, limit: float) -> np.ndarray:
    """Bins whose geometric centre lies below an upper limit (none when it is nan: CG-n
    is outside the band from the smallest used bin on)."""
    if not np.isfinite(limit):
        return np.zeros(len(edges) - 1, dtype=bool)
    return np.sqrt(edges[:-1] * edges[1:]) < limit


def frame_histograms(g: pd.DataFrame, edges: np.ndarray, column: str, min_particles: int,
                 replica_of: dict[str, int]) -> tuple[np.ndarray, np.ndarray]:
    """(per-frame volume-weighted histograms, replica per frame) of a granule table; a frame
    without a counted granule has a row of zeros."""
    hists, reps = [], []
    for (case_id, _), fr in g.groupby(["case_id", "step"], sort=True):
        keep = gsdmod.counted(fr["members"].to_numpy(), fr["percolating"].to_numpy(bool),
                              min_particles)
        hists.append(gsdmod.histogram(fr[column].to_numpy()[keep], edges)[1])
        reps.append(replica_of[case_id])
    return np.asarray(hists, dtype=float).reshape(-1, len(edges) - 1), np.asarray(reps)


def _compare(edges, pool_h, pool_r, ref_h, ref_r, settings: AnalysisSettings,
             rng: np.random.Generator) -> dict[str, float]:
    """Limits and side errors of one pool against its reference, with bootstrap bands."""
    conf, band = gsdmod.CONFIDENCE, settings.error_band
    cg, ref = pool_h.mean(axis=0), ref_h.mean(axis=0)
    cg_d = gsdmod.bootstrap_means(pool_h, pool_r, settings.bootstrap, rng)
    ref_d = gsdmod.bootstrap_means(ref_h, ref_r, settings.bootstrap, rng)
    out: dict[str, float] = {}
    for name, locate, below_of in (
            ("upper", upper_limit, _below_upper),
            ("lower", gsdmod.located_limit, gsdmod.below_limit)):
        limit = float(locate(edges, cg, ref, band))
        lo, hi = gsdmod.band(locate(edges, cg_d, ref_d, band), conf)
        out.update({f"{name}_limit": limit, f"{name}_limit_lo": float(lo),
                    f"{name}_limit_hi": float(hi)})
        below = below_of(edges, limit)
        eb, ea = gsdmod.side_errors(cg, ref, below)
        eb_d, ea_d = gsdmod.side_errors(cg_d, ref_d, below)
        (eb_lo, ea_lo), (eb_hi, ea_hi) = gsdmod.band(np.column_stack([eb_d, ea_d]), conf)
        for side, v, vlo, vhi in (("below", eb, eb_lo, eb_hi), ("above", ea, ea_lo, ea_hi)):
            out.update({f"error_{side}_{name}": float(v), f"error_{side}_{name}_lo": float(vlo),
                        f"error_{side}_{name}_hi": float(vhi)})
    return out


def pooling_table(granules: pd.DataFrame, cases: Sequence[CaseLike],
                  settings: AnalysisSettings, ks: Sequence[int] = (1, 2, 4)) -> pd.DataFrame:
    """One row per CG-n condition, pool size K in ``ks`` (<= its replica count) and pool,
    plus the CG1 noise-floor rows (each CG1 replica against the other CG1 replicas).
    ``granules``: the granule table of the frames to use (the steady window), binned on
    the edges of the whole table (one binning for every pool)."""
    if granules.empty:
        return pd.DataFrame(columns=POOLING_COLUMNS)
    col = gsdmod.volume_column(settings)
    use = gsdmod.counted(granules["members"], granules["percolating"].to_numpy(bool),
                         settings.min_particles)
    v_all = granules[col][use] if use.any() else granules[col]
    edges = gsdmod.log_edges(float(v_all.min()), float(v_all.max()), settings.bins_per_decade)
    replica_of = {c.case_id: c.replica for c in cases}
    conditions = Conditions.of(cases)
    by_id = {c.case_id: c for c in cases}
    by_cond = {cond: [by_id[i] for i in ids] for cond, ids in conditions.cases.items()}
    rng = np.random.default_rng(settings.seed)
    rows = []

    def frames_of(members: list[CaseLike]):
        ids = [c.case_id for c in members]
        return frame_histograms(granules[granules["case_id"].isin(ids)], edges, col,
                            settings.min_particles, replica_of)

    for cond in conditions.sorted():
        refs = [by_id[i] for i in conditions.reference_cases(cond.group)]
        if not refs:
            continue
        members = by_cond[cond]
        head = {"condition": cond.name, "group": cond.group, "cg": cond.cg,
                "error_band": settings.error_band}
        if cond.is_reference:                              # the noise floor
            if len(members) < 2:
                continue
            for c in sorted(members, key=lambda c: c.replica):
                ph, pr = frames_of([c])
                rh, rr = frames_of([o for o in members if o is not c])
                if len(ph) == 0 or len(rh) == 0:
                    continue
                rows.append({**head, "rule": "noise floor", "k": 1, "pool": str(c.replica),
                             "replicas": 1, "frames": len(ph),
                             **_compare(edges, ph, pr, rh, rr, settings, rng)})
            continue
        rh, rr = frames_of(refs)
        for k in ks:
            for pool in pools([c.replica for c in members], k):
                ph, pr = frames_of([c for c in members if c.replica in pool])
                if len(ph) == 0 or len(rh) == 0:
                    continue
                rows.append({**head, "rule": cond.rule, "k": k,
                             "pool": "+".join(map(str, pool)), "replicas": len(pool),
                             "frames": len(ph),
                             **_compare(edges, ph, pr, rh, rr, settings, rng)})
    return pd.DataFrame(rows, columns=POOLING_COLUMNS)


def pooling_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per condition and K: the number of pools and the mean, min and max over pools of
    each limit and error (the spread over pools is the replica-to-replica scatter)."""
    if table.empty:
        return pd.DataFrame()
    values = [c for c in POOLING_COLUMNS[8:] if not c.endswith(("_lo", "_hi"))
              and c != "error_band"]
    out = []
    for (cond, rule, k), t in table.groupby(["condition", "rule", "k"], sort=True):
        row = {"condition": cond, "rule": rule, "k": int(k), "pools": len(t),
               "frames_per_pool": float(t["frames"].mean())}
        for v in values:
            x = t[v].to_numpy(float)
            finite = x[np.isfinite(x)]
            row[f"{v}_mean"] = float(finite.mean()) if len(finite) else math.nan
            row[f"{v}_min"] = float(finite.min()) if len(finite) else math.nan
            row[f"{v}_max"] = float(finite.max()) if len(finite) else math.nan
            row[f"{v}_nan_pools"] = int(len(x) - len(finite))
        out.append(row)
    return pd.DataFrame(out)
