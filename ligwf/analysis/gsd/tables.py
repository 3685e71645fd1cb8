"""GSD tables of a study: per condition (sweep group, CG level, rule; replicas pooled)
the binned number- and volume-weighted GSD of the counted granules (>= ``min_particles``
members, not percolating) with bootstrap bands, the percolating (bed-spanning) clusters on
their own (share of the bed, share of frames), and for CG > 1 the comparison with the CG1
reference of the same group with the lower size limit located from the data and its bootstrap
interval (see :mod:`ligwf.analysis.gsd.bins`).

Input is the granule table of the frames to use (the runner passes the steady window of
every case); output is what ``gsd.csv`` and ``gsd_summary.csv`` hold.
"""

from __future__ import annotations

import math
import warnings
from typing import Any, Sequence

import numpy as np
import pandas as pd

from ligwf.analysis.gsd import bins as gsdmod
from ligwf.analysis.records.conditions import CaseLike, Conditions
from ligwf.study.condition import Condition
# the GSD errors name their limit: ligwf.analysis.records.gsd
from ligwf.analysis.records.gsd import GSD_ERRORS, LOWER_LIMIT
from ligwf.scene.settings import AnalysisSettings


#: Columns of ``gsd.csv`` (one row per condition and volume bin).
GSD_COLUMNS = ["condition", "group", "cg", "rule", "replicas", "frames", "bin", "v_lo", "v_hi",
               "v_mid", "number_fraction", "number_lo", "number_hi", "volume_fraction",
               "volume_lo", "volume_hi", "ref_volume_fraction", "rel_error", "rel_error_lo",
               "rel_error_hi", "below_lower_limit"]
#: Columns of ``gsd_summary.csv`` (one row per condition). ``lower_limit`` (m^3) is located
#: from the data (nan: CG-n never enters the error band, or no CG1 reference);
#: ``percolating_share``: mean share of the bed in percolating granules, left out of the
#: GSD; ``percolating_frames``: share of frames holding one; ``granule_share``: mean share
#: of the bed in counted granules.
SUMMARY_COLUMNS = ["condition", "group", "cg", "rule", "replicas", "frames",
                   *[f"{q}{s}" for q in ("d10", "d50", "d90", "largest_fraction")
                     for s in ("", "_lo", "_hi")],
                   "granule_share", "percolating_share", "percolating_frames",
                   *[f"{LOWER_LIMIT}{s}" for s in ("", "_lo", "_hi")], "error_band",
                   "min_particles", "reference",
                   *[f"{e}{s}" for e in GSD_ERRORS for s in ("", "_lo", "_hi")]]
SCALARS = ("d10", "d50", "d90", "largest_granule")


def _per_condition(g: pd.DataFrame, cases: Sequence[CaseLike], edges: np.ndarray,
                   min_particles: int, column: str) -> dict[Condition, dict[str, Any]]:
    """Per condition the per-frame histograms, scalars, shares and replica of each frame."""
    replica_of = {c.case_id: c.replica for c in cases}
    cond_of = {c.case_id: Condition.of(c) for c in cases}
    per_cond: dict[Condition, dict[str, Any]] = {}
    for (case_id, step), fr in g.groupby(["case_id", "step"], sort=True):
        vol, mem, perc = (fr[column].to_numpy(), fr["members"].to_numpy(),
                          fr["percolating"].to_numpy(bool))
        stats = gsdmod.frame_stats(vol, mem, perc, min_particles)
        num, vhist = gsdmod.histogram(vol[gsdmod.counted(mem, perc, min_particles)], edges)
        d = per_cond.setdefault(cond_of[case_id], {k: [] for k in ("num", "vol", "rep", "sc",
                                                                   "share", "perc")})
        d["num"].append(num)
        d["vol"].append(vhist)
        d["rep"].append(replica_of[case_id])
        d["sc"].append([stats[k] for k in SCALARS])
        d["share"].append(stats["granule_share"])
        d["perc"].append(stats["percolating_share"])
    return per_cond


def gsd_tables(granules: pd.DataFrame, cases: Sequence[CaseLike],
               settings: AnalysisSettings) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``gsd.csv`` and ``gsd_summary.csv`` contents from the granule table of the frames
    to use (tables with their columns and no row when there is none: a steady window
    without frames is a result, and the files keep their header)."""
    if granules.empty:
        return pd.DataFrame(columns=GSD_COLUMNS), pd.DataFrame(columns=SUMMARY_COLUMNS)
    g = granules
    use = gsdmod.counted(g["members"], g["percolating"].to_numpy(bool), settings.min_particles)
    col = gsdmod.volume_column(settings)
    v_all = g[col][use] if use.any() else g[col]
    edges = gsdmod.log_edges(float(v_all.min()), float(v_all.max()), settings.bins_per_decade)
    rng = np.random.default_rng(settings.seed)
    per_cond = _per_condition(g, cases, edges, settings.min_particles, col)
    rows, summary = [], []
    conds = sorted(per_cond, key=lambda c: c.key)
    conditions = Conditions.of(cases)
    conf, nb = gsdmod.CONFIDENCE, len(edges) - 1
    for cond in conds:
        d = per_cond[cond]
        rep = np.asarray(d["rep"])
        num, vol, scalars = np.asarray(d["num"]), np.asarray(d["vol"]), np.asarray(d["sc"])
        num_lo, num_hi = gsdmod.band(gsdmod.bootstrap_means(num, rep, settings.bootstrap, rng), conf)
        vol_draws = gsdmod.bootstrap_means(vol, rep, settings.bootstrap, rng)
        vol_lo, vol_hi = gsdmod.band(vol_draws, conf)
        sc_lo, sc_hi = gsdmod.band(gsdmod.bootstrap_means(scalars, rep, settings.bootstrap, rng), conf)
        mean_vol = vol.mean(axis=0)
        refs = [r for r in conditions.references(cond.group) if r in per_cond]
        ref = refs[-1] if refs and not cond.is_reference else None
        rel = rel_lo = rel_hi = ref_vol = np.full(nb, np.nan)
        err = dict.fromkeys([f"{e}{s}" for e in GSD_ERRORS for s in ("", "_lo", "_hi")],
                            math.nan)
        limit = limit_lo = limit_hi = math.nan
        below = np.zeros(nb, dtype=bool)
        if ref is not None:
            r = per_cond[ref]
            ref_vol = np.asarray(r["vol"]).mean(axis=0)
            ref_draws = gsdmod.bootstrap_means(np.asarray(r["vol"]), np.asarray(r["rep"]),
                                               settings.bootstrap, rng)
            rel = gsdmod.relative_error(mean_vol, ref_vol)
            rel_lo, rel_hi = gsdmod.band(gsdmod.relative_error(vol_draws, ref_draws), conf)
            limit = float(gsdmod.located_limit(edges, mean_vol, ref_vol, settings.error_band))
            limit_lo, limit_hi = gsdmod.band(
                gsdmod.located_limit(edges, vol_draws, ref_draws, settings.error_band), conf)
            below = gsdmod.below_limit(edges, limit)
            every = np.ones(nb, dtype=bool)
            values = [*gsdmod.side_errors(mean_vol, ref_vol, below),
                      gsdmod.side_errors(mean_vol, ref_vol, every)[0]]
            draws = [*gsdmod.side_errors(vol_draws, ref_draws, below),
                     gsdmod.side_errors(vol_draws, ref_draws, every)[0]]
            los, his = gsdmod.band(np.column_stack(draws), conf)
            err = {}
            for e, v, lo, hi in zip(GSD_ERRORS, values, los, his):
                err.update({e: float(v), f"{e}_lo": float(lo), f"{e}_hi": float(hi)})
        n_reps = len(np.unique(rep))
        head = {"condition": cond.name, "group": cond.group, "cg": cond.cg, "rule": cond.rule,
                "replicas": n_reps, "frames": len(rep)}
        for b in range(nb):
            rows.append({**head, "bin": b, "v_lo": edges[b], "v_hi": edges[b + 1],
                         "v_mid": math.sqrt(edges[b] * edges[b + 1]),
                         "number_fraction": num.mean(axis=0)[b], "number_lo": num_lo[b],
                         "number_hi": num_hi[b], "volume_fraction": mean_vol[b],
                         "volume_lo": vol_lo[b], "volume_hi": vol_hi[b],
                         "ref_volume_fraction": ref_vol[b], "rel_error": rel[b],
                         "rel_error_lo": rel_lo[b], "rel_error_hi": rel_hi[b],
                         "below_lower_limit": bool(below[b])})
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)     # no granule in any frame
            means = np.nanmean(scalars, axis=0)
        perc = np.asarray(d["perc"])
        summary.append({**head, **{f"{q}{s}": a[k] for k, q in enumerate(
                            ("d10", "d50", "d90", "largest_fraction"))
                            for s, a in (("", means), ("_lo", sc_lo), ("_hi", sc_hi))},
                        "granule_share": float(np.mean(d["share"])),
                        "percolating_share": float(perc.mean()),
                        "percolating_frames": float(np.mean(perc > 0)),
                        LOWER_LIMIT: limit, f"{LOWER_LIMIT}_lo": float(limit_lo),
                        f"{LOWER_LIMIT}_hi": float(limit_hi), "error_band": settings.error_band,
                        "min_particles": settings.min_particles,
                        "reference": ref.name if ref is not None else "", **err})
    return pd.DataFrame(rows, columns=GSD_COLUMNS), pd.DataFrame(summary, columns=SUMMARY_COLUMNS)
