"""Report stage: turn a finished study into the answer to "what error for what run time".

Inputs (all already on disk): the study (its cases' scaled scenes and manifests, through
:class:`ligwf.study.study.Study`) and the analysis outputs in its analysis folder (flow
table and profiles from the flow stage; frame and GSD summary tables from the granule
stage when granules were analysed; names in :mod:`ligwf.study.layout`).

Per case: CG level, rule, particles, dt, steps, wall and core-seconds, speedup vs CG1
(core-seconds per simulated second of the CG1 cases of the same sweep group over this
case's: CG levels may simulate different times, e.g. more revolutions where they are
cheap), and errors vs
CG1: angle of repose (relative), velocity profile (relative L2), GSD error below/above the
size limit, largest-cluster fraction. Per condition (CG level, rule, group): mean and 95 %
confidence interval over replicas (Student t; a single replica has no interval).
Only ``done`` cases with a matching scene hash count; the others are listed with their
status and reason, never averaged in.
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from ligwf.analysis.flow import profile_l2_error
from ligwf.study import layout
from ligwf.study.study import Study

METRICS = ["core_seconds", "wall_seconds", "speedup_core", "speedup_wall",
           "angle_of_repose", "angle_of_repose_std", "angle_error", "profile_error",
           "rigid_frame_share", "rms_speed_rel_fluctuation", "largest_cluster_fraction",
           "one_granule_frame_share", "gsd_error_below", "gsd_error_above"]


#: Already pooled over replicas by the analysis stage (bootstrap bands), not per case.
GSD_METRICS = ("gsd_error_below", "gsd_error_above")


def _read_csv(path: Path) -> pd.DataFrame:
    if path.is_file() and path.stat().st_size > 1:
        try:
            return pd.read_csv(path)
        except pd.errors.EmptyDataError:
            return pd.DataFrame()
    return pd.DataFrame()


def case_rows(study: Study) -> tuple[pd.DataFrame, list[dict]]:
    """One row per usable case with run facts; and the skipped cases with reasons."""
    usable, skipped = study.usable_cases()
    rows = []
    for c in usable:
        man = c.manifest()
        s = c.scaled
        prod = (man.phases or {}).get("production", {})
        rows.append({
            "case_id": c.case_id, "group": c.group, "cg": c.cg, "rule": c.rule,
            "replica": c.replica, "particles": s.particle_count, "dt": s.dt,
            "steps": man.steps_done,
            "simulated_seconds": man.steps_done * s.dt,
            "wall_seconds": man.wall_seconds,
            "core_seconds": man.core_seconds,
            "production_core_seconds": prod.get("core_seconds", math.nan),
            "nprocs": man.nprocs,
        })
    return pd.DataFrame(rows), skipped


def merge_analysis(cases: pd.DataFrame, analysis_dir: Path) -> pd.DataFrame:
    """Add flow, cluster and GSD quantities to the case table (nan where not analysed)."""
    df = cases.copy()
    flow = _read_csv(analysis_dir / layout.FLOW_TABLE)
    if not flow.empty:
        keep = flow[["case_id", "angle_of_repose_mean", "angle_of_repose_std", "rigid_frame_share",
                     "rms_speed_rel_fluctuation", "flowing_layer_thickness_mean"]]
        df = df.merge(keep.rename(columns={"angle_of_repose_mean": "angle_of_repose"}),
                      on="case_id", how="left")
    frames = _read_csv(analysis_dir / layout.FRAMES_TABLE)
    if not frames.empty and "largest_fraction" in frames:
        ok = frames[frames.get("status", "ok") == "ok"] if "status" in frames else frames
        agg = ok.groupby("case_id")["largest_fraction"].agg(
            largest_cluster_fraction="mean",
            one_granule_frame_share=lambda x: float(np.mean(np.asarray(x) > 0.99)))
        df = df.merge(agg.reset_index(), on="case_id", how="left")
    summary = _read_csv(analysis_dir / layout.GSD_SUMMARY_TABLE)
    if not summary.empty:
        cols = {f"error_{side}{sfx}": f"gsd_error_{side}{sfx}"
                for side in ("below", "above") for sfx in ("", "_lo", "_hi")}
        g = summary[["group", "cg", "rule", *[c for c in cols if c in summary]]].rename(columns=cols)
        g = g.assign(group=g["group"].astype(str))
        df = df.merge(g, on=["group", "cg", "rule"], how="left")
    for col in METRICS:
        if col not in df:
            df[col] = math.nan
    return df


def compare_to_cg1(df: pd.DataFrame, profiles: dict) -> pd.DataFrame:
    """Speedups and errors of every case against the CG1 cases of its sweep group."""
    df = df.copy()
    for group, sub in df.groupby("group"):
        ref = sub[sub["cg"] == 1]
        if ref.empty:
            continue
        # cost per simulated second, so cases simulated for different times compare
        sim = df.loc[sub.index, "simulated_seconds"]
        core1 = (ref["core_seconds"] / ref["simulated_seconds"]).mean()
        wall1 = (ref["wall_seconds"] / ref["simulated_seconds"]).mean()
        ang1 = ref["angle_of_repose"].mean()
        ref_prof = [profiles[c] for c in ref["case_id"] if c in profiles]
        if ref_prof:
            s_ref = ref_prof[0]["s"]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # bins empty in every CG1 case
                v_ref = np.nanmean(np.array([p["v_mean"] for p in ref_prof], dtype=float), axis=0)
        idx = sub.index
        df.loc[idx, "speedup_core"] = core1 / (df.loc[idx, "core_seconds"] / sim)
        df.loc[idx, "speedup_wall"] = wall1 / (df.loc[idx, "wall_seconds"] / sim)
        df.loc[idx, "angle_error"] = (df.loc[idx, "angle_of_repose"] - ang1).abs() / ang1
        if ref_prof:
            for i in idx:
                p = profiles.get(df.at[i, "case_id"])
                if p is not None:
                    df.at[i, "profile_error"] = profile_l2_error(s_ref, v_ref, p["s"], p["v_mean"])
    return df


def confidence(values: pd.Series, level: float = 0.95) -> tuple[float, float, float]:
    """(mean, lo, hi) with a Student-t interval over replicas; lo = hi = nan for n < 2."""
    x = values.dropna().to_numpy(dtype=float)
    if len(x) == 0:
        return math.nan, math.nan, math.nan
    m = float(x.mean())
    if len(x) < 2:
        return m, math.nan, math.nan
    half = float(stats.t.ppf(0.5 + level / 2, len(x) - 1) * x.std(ddof=1) / math.sqrt(len(x)))
    return m, m - half, m + half


def condition_table(df: pd.DataFrame) -> pd.DataFrame:
    """Mean and 95 % CI of every metric per (group, CG level, rule)."""
    rows = []
    for (group, cg, rule), sub in df.groupby(["group", "cg", "rule"], sort=True):
        row = {"group": group, "cg": cg, "rule": rule, "replicas": len(sub),
               "particles": int(sub["particles"].iloc[0]), "dt": float(sub["dt"].iloc[0]),
               "steps": int(sub["steps"].max())}
        for col in METRICS:
            if col in GSD_METRICS:  # one value per condition, with its bootstrap band
                first = sub.iloc[0]
                m, lo, hi = first[col], first.get(f"{col}_lo", math.nan), first.get(f"{col}_hi", math.nan)
            else:
                m, lo, hi = confidence(sub[col])
            row[col], row[f"{col}_lo"], row[f"{col}_hi"] = m, lo, hi
        rows.append(row)
    return pd.DataFrame(rows)


def build_tables(study: Study) -> tuple[pd.DataFrame, pd.DataFrame, list[dict], dict]:
    """(case table, condition table, skipped cases, profiles) of a finished study."""
    cases, skipped = case_rows(study)
    analysis_dir = study.analysis_dir
    prof_path = analysis_dir / layout.FLOW_PROFILES
    profiles = json.loads(prof_path.read_text())["profiles"] if prof_path.is_file() else {}
    if cases.empty:
        return cases, pd.DataFrame(), skipped, profiles
    df = compare_to_cg1(merge_analysis(cases, analysis_dir), profiles)
    return df, condition_table(df), skipped, profiles
