"""Granulation kinetics and the sensitivity of the granule definition.

Kinetics: per case and frame (every analysed frame, start-up included: growth is what is
watched) the granule count, d10/d50/d90 (m, volume-equivalent diameters of the counted
granules: >= ``min_particles`` members, not percolating), the largest counted granule and
the bed shares in counted and in percolating granules (:func:`ligwf.analysis.gsd.bins.frame_stats`);
per condition the mean over replicas with a bootstrap band over replicas (zero width with
one replica: the band is the replica spread, not frame noise) and the ratio of CG-n to the
CG1 condition of its group at the nearest time. Volumes are physical, as in the GSD
(:mod:`ligwf.analysis.gsd.bins`: a CG-neutral definition gives CG-n granules of CG1 volume).

Sensitivity: one set of steady frames analysed again under each variant of the definition
(:func:`ligwf.analysis.granules.definitions.variants`: every threshold x0.8 and
x1.25), so a user sees how much granule count, d50 and the largest granule depend on them.
"""

from __future__ import annotations

import warnings
from typing import Sequence

import numpy as np
import pandas as pd

from ligwf.analysis.gsd import bins as gsdmod
from ligwf.analysis.granules.case import GranuleAnalysis, RunFacts
from ligwf.analysis.granules.definitions import variants
from ligwf.analysis.frames.dumps import FrameFiles
from ligwf.analysis.records.conditions import CaseLike
from ligwf.study.condition import REFERENCE_CG, Condition
from ligwf.scene.settings import AnalysisSettings

#: Per-frame quantities (see :func:`ligwf.analysis.gsd.bins.frame_stats`)
QUANTITIES = ("granules", "d10", "d50", "d90", "largest_granule", "granule_share",
              "percolating_share")


def kinetics_table(granules: pd.DataFrame, cases: Sequence[CaseLike],
                   settings: AnalysisSettings) -> pd.DataFrame:
    """One row per case and frame: condition, cg, rule, replica, step, time (s) and
    :data:`QUANTITIES` of the granules of ``settings.min_particles`` or more, from the
    volume the GSD bins (``settings.gsd_volume``: physical, or primary = volume / n^3)."""
    min_particles, volume_column = settings.min_particles, gsdmod.volume_column(settings)
    cond = {c.case_id: Condition.of(c) for c in cases}
    replica = {c.case_id: c.replica for c in cases}
    rows = []
    for (case_id, step), fr in granules.groupby(["case_id", "step"], sort=True):
        stats = gsdmod.frame_stats(fr[volume_column].to_numpy(), fr["members"].to_numpy(),
                                   fr["percolating"].to_numpy(bool), min_particles)
        c = cond[case_id]
        rows.append({"case_id": case_id, "condition": c.name, "group": c.group, "cg": c.cg,
                     "rule": c.rule, "replica": replica[case_id], "step": int(step),
                     "time": float(fr["time"].iloc[0]), **stats})
    return pd.DataFrame(rows, columns=["case_id", "condition", "group", "cg", "rule",
                                       "replica", "step", "time", *QUANTITIES])


def kinetics_summary(kin: pd.DataFrame, settings: AnalysisSettings) -> pd.DataFrame:
    """Per condition and time: mean of each quantity over replicas, its bootstrap band
    (replicas resampled, ``settings.bootstrap`` draws from ``settings.seed``) and, for
    CG > 1, the ratio to the CG1 mean of the group at the nearest time (``<q>_ratio``)."""
    if kin.empty:
        return pd.DataFrame()
    rng = np.random.default_rng(settings.seed)
    out = []
    conditions = {Condition(r.group, float(r.cg), r.rule) for r in kin.itertuples(index=False)}
    for condition in sorted(conditions, key=lambda c: (c.name, *c.key)):
        d = kin[(kin["group"] == condition.group) & (kin["cg"] == condition.cg)
                & (kin["rule"] == condition.rule)]
        times = np.sort(d["time"].unique())
        for t in times:
            at = d[d["time"] == t]
            vals = at[list(QUANTITIES)].to_numpy(float)
            draws = gsdmod.bootstrap_means(vals, at["replica"].to_numpy(), settings.bootstrap,
                                           rng)
            lo, hi = gsdmod.band(draws, gsdmod.CONFIDENCE)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                mean = np.nanmean(vals, axis=0)
            row = {"condition": condition.name, "group": condition.group, "cg": condition.cg,
                   "rule": condition.rule, "time": t, "replicas": len(at)}
            for k, q in enumerate(QUANTITIES):
                row.update({q: mean[k], f"{q}_lo": lo[k], f"{q}_hi": hi[k]})
            out.append(row)
    summary = pd.DataFrame(out)
    for q in QUANTITIES:
        summary[f"{q}_ratio"] = np.nan
    for group, d in summary.groupby("group"):
        ref = d[d["cg"] == REFERENCE_CG].sort_values("time")
        if ref.empty:
            continue
        for idx, row in d[d["cg"] != REFERENCE_CG].iterrows():
            k = int(np.abs(ref["time"].to_numpy() - row["time"]).argmin())
            with np.errstate(divide="ignore", invalid="ignore"):
                for q in QUANTITIES:
                    summary.loc[idx, f"{q}_ratio"] = row[q] / ref[q].to_numpy()[k]
    return summary


def sensitivity_table(facts: RunFacts, frames: list[FrameFiles], settings: AnalysisSettings,
                      implementation: str = "fast") -> pd.DataFrame:
    """Per variant of the settings' granule definition (first: ``as set: <its setting>``)
    the mean over ``frames`` of granule count, d50 (m), largest granule and percolating
    share of the granules of ``settings.min_particles`` or more, and d50 relative to the
    definition as set."""
    min_particles = settings.min_particles
    rows = []
    for label, variant in variants(settings):
        ana = GranuleAnalysis(facts, variant, implementation).run(frames)
        stats = [gsdmod.frame_stats(r.table["volume"].to_numpy(), r.table["members"].to_numpy(),
                                    r.table["percolating"].to_numpy(bool), min_particles)
                 for r in ana.results if r.table is not None]
        if not stats:
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            mean = {q: float(np.nanmean([s[q] for s in stats])) for q in
                    ("granules", "d50", "largest_granule", "percolating_share")}
        rows.append({"case_id": facts.case_id, "variant": label, "frames": len(stats),
                     "method": variant.granules, "velocity_frame": variant.velocity_frame,
                     "resolution": variant.resolution,
                     "max_velocity_angle": variant.max_velocity_angle,
                     "min_relative_force": variant.min_relative_force,
                     "hold_time": variant.hold_time, **mean})
    table = pd.DataFrame(rows)
    if not table.empty:
        table["d50_ratio"] = table["d50"] / table["d50"].iloc[0]
    return table
