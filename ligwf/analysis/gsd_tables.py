"""GSD tables of a study: per condition (sweep group, CG level, rule; replicas pooled)
the binned number- and volume-weighted GSD with bootstrap bands, and for CG > 1 the
comparison with the CG1 reference of the same group (see :mod:`ligwf.analysis.gsd`).

Input is the granule table of the frames to use (the runner passes the steady window of
every case); output is what ``gsd.csv`` and ``gsd_summary.csv`` hold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol, Sequence

import numpy as np
import pandas as pd

from ligwf.analysis import gsd as gsdmod


class CaseLike(Protocol):
    """What the GSD tables need of a case (:class:`ligwf.study.case.CaseFolder` has it)."""

    case_id: str
    cg: float
    rule: str
    replica: int
    group: str


@dataclass(frozen=True)
class Condition:
    """Cases pooled for a GSD: same group, CG level and rule (replicas together)."""

    group: str
    cg: float
    rule: str

    @property
    def name(self) -> str:
        tag = f"cg{self.cg:g}" + ("" if self.cg == 1 else f"-{self.rule}")
        return tag if self.group in ("{}", "") else f"{tag} {self.group}"


#: Columns of ``gsd.csv`` (one row per condition and volume bin).
GSD_COLUMNS = ["condition", "group", "cg", "rule", "replicas", "frames", "bin", "v_lo", "v_hi",
               "v_mid", "number_fraction", "number_lo", "number_hi", "volume_fraction",
               "volume_lo", "volume_hi", "ref_volume_fraction", "rel_error", "rel_error_lo",
               "rel_error_hi", "below_limit"]
#: Columns of ``gsd_summary.csv`` (one row per condition).
SUMMARY_COLUMNS = ["condition", "group", "cg", "rule", "replicas", "frames",
                   *[f"{q}{s}" for q in ("d10", "d50", "d90", "largest_fraction")
                     for s in ("", "_lo", "_hi")],
                   "size_limit", "min_particles", "reference",
                   *[f"error_{side}{s}" for side in ("below", "above") for s in ("", "_lo", "_hi")]]


def gsd_tables(granules: pd.DataFrame, cases: Sequence[CaseLike],
               settings: gsdmod.GsdSettings) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``gsd.csv`` and ``gsd_summary.csv`` contents from the granule table of the frames
    to use (tables with their columns and no row when there is none: a steady window
    without frames is a result, and the files keep their header)."""
    if granules.empty:
        return pd.DataFrame(columns=GSD_COLUMNS), pd.DataFrame(columns=SUMMARY_COLUMNS)
    g = granules
    edges = gsdmod.log_edges(float(g["primary_volume"].min()), float(g["primary_volume"].max()),
                             settings.bins_per_decade)
    rng = np.random.default_rng(settings.seed)
    replica_of = {c.case_id: c.replica for c in cases}
    cond_of = {c.case_id: Condition(c.group, c.cg, c.rule) for c in cases}
    per_cond: dict[Condition, dict[str, Any]] = {}
    for (case_id, step), fr in g.groupby(["case_id", "step"], sort=True):
        cond = cond_of[case_id]
        v = fr["primary_volume"].to_numpy()
        num, vol = gsdmod.histogram(v, edges)
        d = per_cond.setdefault(cond, {"num": [], "vol": [], "rep": [], "pct": [], "largest": [],
                                       "ppv": []})
        d["num"].append(num)
        d["vol"].append(vol)
        d["rep"].append(replica_of[case_id])
        d["pct"].append(gsdmod.percentile_diameters(v))
        d["largest"].append(v.max() / v.sum())
        d["ppv"].append(v.sum() / fr["members"].sum())   # mean particle primary volume
    rows, summary = [], []
    conds = sorted(per_cond, key=lambda c: (c.group, c.cg, c.rule))
    ref_of = {c.group: c for c in conds if c.cg == 1}
    lo_hi = settings.confidence
    for cond in conds:
        d = per_cond[cond]
        rep = np.asarray(d["rep"])
        num, vol = np.asarray(d["num"]), np.asarray(d["vol"])
        scalars = np.column_stack([np.asarray(d["pct"]), np.asarray(d["largest"])])
        num_lo, num_hi = gsdmod.band(gsdmod.bootstrap_means(num, rep, settings.n_boot, rng), lo_hi)
        vol_draws = gsdmod.bootstrap_means(vol, rep, settings.n_boot, rng)
        vol_lo, vol_hi = gsdmod.band(vol_draws, lo_hi)
        sc_lo, sc_hi = gsdmod.band(gsdmod.bootstrap_means(scalars, rep, settings.n_boot, rng), lo_hi)
        mean_vol = vol.mean(axis=0)
        limit = gsdmod.size_limit(float(np.mean(d["ppv"])), settings.min_particles)
        below = gsdmod.below_limit(edges, limit)
        ref = ref_of.get(cond.group) if cond.cg != 1 else None
        nan = np.full(len(edges) - 1, np.nan)
        rel = rel_lo = rel_hi = ref_vol = nan
        err = {"error_below": math.nan, "error_below_lo": math.nan, "error_below_hi": math.nan,
               "error_above": math.nan, "error_above_lo": math.nan, "error_above_hi": math.nan}
        if ref is not None:
            r = per_cond[ref]
            ref_vol = np.asarray(r["vol"]).mean(axis=0)
            ref_draws = gsdmod.bootstrap_means(np.asarray(r["vol"]), np.asarray(r["rep"]),
                                               settings.n_boot, rng)
            rel = gsdmod.relative_error(mean_vol, ref_vol)
            rel_lo, rel_hi = gsdmod.band(gsdmod.relative_error(vol_draws, ref_draws), lo_hi)
            eb, ea = gsdmod.side_errors(mean_vol, ref_vol, below)
            eb_d, ea_d = gsdmod.side_errors(vol_draws, ref_draws, below)
            (eb_lo, ea_lo), (eb_hi, ea_hi) = (gsdmod.band(np.column_stack([eb_d, ea_d]), lo_hi))
            err = {"error_below": float(eb), "error_below_lo": float(eb_lo),
                   "error_below_hi": float(eb_hi), "error_above": float(ea),
                   "error_above_lo": float(ea_lo), "error_above_hi": float(ea_hi)}
        n_reps = len(np.unique(rep))
        for b in range(len(edges) - 1):
            rows.append({"condition": cond.name, "group": cond.group, "cg": cond.cg,
                         "rule": cond.rule, "replicas": n_reps, "frames": len(rep), "bin": b,
                         "v_lo": edges[b], "v_hi": edges[b + 1],
                         "v_mid": math.sqrt(edges[b] * edges[b + 1]),
                         "number_fraction": num.mean(axis=0)[b], "number_lo": num_lo[b],
                         "number_hi": num_hi[b], "volume_fraction": mean_vol[b],
                         "volume_lo": vol_lo[b], "volume_hi": vol_hi[b],
                         "ref_volume_fraction": ref_vol[b], "rel_error": rel[b],
                         "rel_error_lo": rel_lo[b], "rel_error_hi": rel_hi[b],
                         "below_limit": bool(below[b])})
        means = scalars.mean(axis=0)
        summary.append({"condition": cond.name, "group": cond.group, "cg": cond.cg,
                        "rule": cond.rule, "replicas": n_reps, "frames": len(rep),
                        "d10": means[0], "d10_lo": sc_lo[0], "d10_hi": sc_hi[0],
                        "d50": means[1], "d50_lo": sc_lo[1], "d50_hi": sc_hi[1],
                        "d90": means[2], "d90_lo": sc_lo[2], "d90_hi": sc_hi[2],
                        "largest_fraction": means[3], "largest_fraction_lo": sc_lo[3],
                        "largest_fraction_hi": sc_hi[3],
                        "size_limit": limit, "min_particles": settings.min_particles,
                        "reference": ref.name if ref is not None else "", **err})
    return pd.DataFrame(rows, columns=GSD_COLUMNS), pd.DataFrame(summary, columns=SUMMARY_COLUMNS)
