"""A study's tables: the case table, the condition table and the noise floors, the numbers
the verdict decides on and the report shows (``cases.csv``, ``conditions.csv``,
``noise_floor.csv``, written by :func:`ligwf.inference.decide.decide_study`).

Inputs (all already on disk): the study (its cases' scaled scenes and manifests, through
:class:`ligwf.study.study.Study`) and the analysis outputs in its analysis folder (flow
table and profiles from the flow stage; frame and GSD summary tables from the granule
stage when granules were analysed; names in :mod:`ligwf.study.layout`).

Per case: CG level, rule, particles, dt, steps, wall and core-seconds split into fill,
settle and production (the manifest's per-phase times), the production cost per simulated
second of production (core-s / s: CG levels may simulate different times, and filling
costs differ), speedup vs CG1 on that footing, and errors vs CG1: angle of repose
(relative), velocity profile (relative L2 on the normalised depth), GSD errors below and
above the lower size limit and over all bins (the limit with them: :data:`GSD_METRICS`),
largest-cluster fraction.
Per condition (CG level, rule, group): value with a 95 % interval that respects the data
(:mod:`ligwf.inference.uncertainty`: block bootstrap over frames and replicas, bounded, never
narrower than the within-run error, none for one replica) and each error against the CG1
noise floor. Only ``done`` cases with a matching scene hash count; the others are listed
with their status and reason, never averaged in.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.records.conditions import Conditions
from ligwf.analysis.records.flow import FlowRecord
from ligwf.analysis.records.gsd import GSD_ERRORS, LOWER_LIMIT
from ligwf.analysis.records.metrics import GRANULE_METRICS, MetricSpec
from ligwf.analysis.records.statistics import MEAN
from ligwf.analysis.records.fields import CaseFields
from ligwf.inference.field_tables import add_field_errors
from ligwf.inference.uncertainty import (ConditionStats, case_series, cost_interval, mark,
                                      report_metrics)
from ligwf.study import layout
from ligwf.study.case import group_label
from ligwf.study.rounds import read_rounds
from ligwf.study.study import Study

#: run costs (a Student-t interval on the logarithm over replicas)
COST_METRICS = ["core_seconds", "wall_seconds", "production_core_rate",
                "production_core_rate_k", "speedup_core", "speedup_wall"]
PHASES = ("fill", "settle", "production")
#: ``gsd_summary.csv`` columns -> case / condition table columns (``gsd_`` + the name; each
#: with ``_lo`` / ``_hi``): already pooled over replicas by the analysis stage (bootstrap
#: bands), one value per condition. The errors name their limit (the lower one, located
#: from the data, ligwf.analysis.records.gsd); ``gsd_lower_limit`` (m^3)
#: is that limit (nan: none located, every bin below it).
GSD_SUMMARY = {**{e: f"gsd_{e}" for e in GSD_ERRORS}, LOWER_LIMIT: "gsd_lower_limit"}
#: ... and the limit's equivalent-sphere diameter (m; the report shows it in mm)
GSD_LIMIT_DIAMETER = "gsd_lower_limit_diameter"
GSD_METRICS = (*GSD_SUMMARY.values(), GSD_LIMIT_DIAMETER)


def metric_columns(flow: FlowRecord) -> list[str]:
    """The metric columns of the condition table: costs, the flow record's metrics (in
    their registration order), the granule metrics, the GSD errors."""
    return [*COST_METRICS, *(m.name for m in flow.metrics),
            *(m.name for m in GRANULE_METRICS), *GSD_METRICS]


def _read_csv(path: Path) -> pd.DataFrame:
    if path.is_file() and path.stat().st_size > 1:
        try:
            return pd.read_csv(path)
        except pd.errors.EmptyDataError:
            return pd.DataFrame()
    return pd.DataFrame()


def _per(cost: float, seconds: float) -> float:
    """Cost per simulated second; nan when the manifest records no simulated time (a case
    marked done by hand or by an older ligwf without step counts: no rate, not a crash)."""
    return cost / seconds if seconds > 0 else math.nan


def case_rows(study: Study) -> tuple[pd.DataFrame, list[dict]]:
    """One row per usable case with run facts; and the skipped cases with reasons."""
    usable, skipped = study.usable_cases()
    rows = []
    for c in usable:
        man = c.manifest()
        s = c.scaled
        phases = man.phases or {}
        prod = phases.get("production", {})
        production_seconds = s.numerics.run_steps * s.numerics.dt
        prod_core = prod.get("core_seconds", math.nan)
        prod_wall = prod.get("wall_seconds", math.nan)
        if not prod:   # a manifest without phase times: whole-run cost over whole-run time
            prod_core, prod_wall = man.core_seconds, man.wall_seconds
            production_seconds = man.steps_done * s.numerics.dt
        rows.append({
            "case_id": c.case_id, "group": c.group, "group_label": group_label(c.group),
            "cg": c.cg, "rule": c.rule,
            "replica": c.replica, "particles": s.particles.count,
            "original_particles": s.particles.original_count, "dt": s.numerics.dt,
            "steps": man.steps_done,
            "simulated_seconds": man.steps_done * s.numerics.dt,
            "production_seconds": production_seconds,
            "wall_seconds": man.wall_seconds,
            "core_seconds": man.core_seconds,
            **{f"{ph}_core_seconds": phases.get(ph, {}).get("core_seconds", math.nan)
               for ph in PHASES},
            "production_core_rate": _per(prod_core, production_seconds),
            # per 1,000 particles of the ORIGINAL system: slices of different length (and
            # CG levels) on one footing
            "production_core_rate_k": _per(prod_core, production_seconds)
            / s.particles.original_count * 1000.0,
            "production_wall_rate": _per(prod_wall, production_seconds),
            "nprocs": man.nprocs,
        })
    return pd.DataFrame(rows), skipped


def merge_analysis(cases: pd.DataFrame, analysis_dir: Path, flow: FlowRecord,
                   granules: bool = True) -> pd.DataFrame:
    """Add flow, cluster and GSD quantities to the case table (nan where not analysed;
    ``granules`` False: the granule tables are not used): every per-case metric of the
    flow record and its steady window."""
    df = cases.copy()
    measured = flow.measured()
    if measured:
        keep = pd.DataFrame([{"case_id": c.case_id,
                              **{m.name: c.values.get(m.name, math.nan)
                                 for m in flow.frame_metrics},
                              "steady_fraction": c.steady_fraction,
                              "steady_from_step": c.steady_from_step} for c in measured])
        df = df.merge(keep, on="case_id", how="left")
    frames = _read_csv(analysis_dir / layout.FRAMES_TABLE) if granules else pd.DataFrame()
    if not frames.empty and "largest_fraction" in frames:
        ok = frames[frames["status"] == "ok"] if "status" in frames else frames
        if "steady_from_step" in df:   # the flow stage's steady window, case by case
            first = ok["case_id"].map(df.set_index("case_id")["steady_from_step"])
            ok = ok[ok["step"] >= first.fillna(-math.inf)]
        # pandas' grouped mean (compensated summation) for means, as the tables always had
        agg = ok.groupby("case_id")["largest_fraction"].agg(
            **{m.name: "mean" if m.statistic == MEAN else m.value for m in GRANULE_METRICS})
        df = df.merge(agg.reset_index(), on="case_id", how="left")
    summary = _read_csv(analysis_dir / layout.GSD_SUMMARY_TABLE) if granules else pd.DataFrame()
    if not summary.empty:
        cols = {f"{k}{sfx}": f"{v}{sfx}" for k, v in GSD_SUMMARY.items()
                for sfx in ("", "_lo", "_hi")}
        g = summary[["group", "cg", "rule", *[c for c in cols if c in summary]]].rename(columns=cols)
        g = g.assign(group=g["group"].astype(str))
        df = df.merge(g, on=["group", "cg", "rule"], how="left")
        for sfx in ("", "_lo", "_hi"):
            if f"{GSD_SUMMARY[LOWER_LIMIT]}{sfx}" in df:
                volume = df[f"{GSD_SUMMARY[LOWER_LIMIT]}{sfx}"].astype(float)
                df[f"{GSD_LIMIT_DIAMETER}{sfx}"] = np.cbrt(6.0 * volume / math.pi)
    for col in [*metric_columns(flow), "steady_fraction", "steady_from_step"]:
        if col not in df:
            df[col] = math.nan
    return df


def compare_to_cg1(df: pd.DataFrame, stats: ConditionStats, errors: list[MetricSpec]
                   ) -> pd.DataFrame:
    """Speedups and errors of every case against the CG1 cases of its sweep group.

    Speedup: CG1 production core-seconds per simulated second of production per original
    (CG1) particle of the scene over the case's (wall likewise): the same physical system
    on one footing even when a CG level runs a shorter slice (per_cg drum.length, as
    we_vs_bo's CG1 does). Errors: against the mean of the group's CG1 runs.
    """
    df = df.copy()
    size = df["original_particles"].astype(float)
    conditions = Conditions.of(df.itertuples())
    for group, sub in df.groupby("group"):   # (production_core_rate / size is _rate_k / 1000)
        ref_ids = conditions.reference_cases(group)
        if not ref_ids:
            continue
        ref = df.index[df["case_id"].isin(ref_ids)]
        idx = sub.index
        for kind in ("core", "wall"):
            rate = df[f"production_{kind}_rate"] / size
            df.loc[idx, f"speedup_{kind}"] = rate[ref].mean() / rate[idx]
        for col in (m.name for m in errors):   # (a whole column at once: .at would add it)
            df.loc[idx, col] = [stats.error_metric([cid], ref_ids, col).value
                                for cid in df.loc[idx, "case_id"]]
    return df


def condition_table(df: pd.DataFrame, stats: ConditionStats, columns: list[str]
                    ) -> pd.DataFrame:
    """Value, 95 % interval (``_lo``/``_hi``, nan: no replica interval) and within-run
    error (``_se``) of every metric per (group, CG level, rule); each error with the
    group's CG1 noise floor (``_floor``, ``_floor_source``) and its mark (``_vs_floor``)."""
    rows = []
    conditions = Conditions.of(df.itertuples())
    for cond in conditions.sorted():
        ids = list(conditions.cases[cond])
        sub = df[df["case_id"].isin(ids)]
        ref_ids = conditions.reference_cases(cond.group)
        row = {"group": cond.group, "group_label": group_label(cond.group), "cg": cond.cg,
               "rule": cond.rule, "replicas": len(sub),
               "particles": int(sub["particles"].iloc[0]), "dt": float(sub["dt"].iloc[0]),
               "steps": int(sub["steps"].max())}
        for ph in PHASES:
            row[f"{ph}_core_seconds"] = float(sub[f"{ph}_core_seconds"].mean())
        for col in columns:
            spec = stats.metrics.get(col)
            if col in GSD_METRICS:  # one value per condition, with its GSD-stage band
                first = sub.iloc[0]
                iv = (first[col], first.get(f"{col}_lo", math.nan),
                      first.get(f"{col}_hi", math.nan), math.nan)
            elif spec is not None and not spec.is_error:
                i = stats.frame_metric(ids, col)
                iv = (i.value, i.lo, i.hi, i.se_within)
            elif spec is not None:
                i = stats.error_metric(ids, ref_ids, col) if ref_ids else None
                iv = (i.value, i.lo, i.hi, i.se_within) if i else (math.nan,) * 4
                fl = stats.floor(ref_ids, col)
                row[f"{col}_floor"], row[f"{col}_floor_source"] = fl.value, fl.source
                row[f"{col}_vs_floor"] = ("reference" if cond.is_reference
                                          else mark(iv[0], fl.value, iv[1], iv[2],
                                                    len(ref_ids)))
            else:
                i = cost_interval(sub[col])
                iv = (i.value, i.lo, i.hi, i.se_within)
            row[col], row[f"{col}_lo"], row[f"{col}_hi"], row[f"{col}_se"] = iv
        rows.append(row)
    return pd.DataFrame(rows)


def noise_floor_table(df: pd.DataFrame, stats: ConditionStats) -> pd.DataFrame:
    """Per group and frame metric: the CG1 value and its CG1-vs-CG1 scatter."""
    rows = []
    conditions = Conditions.of(df.itertuples())
    for group in conditions.groups():
        ref_ids = conditions.reference_cases(group)
        if not ref_ids:
            continue
        for col in (m.name for m in stats.metrics.values() if not m.is_error):
            value = stats.frame_metric(ref_ids, col).value
            scatter, source = stats.scatter(ref_ids, col)
            rows.append({"group": group, "group_label": group_label(group), "metric": col,
                         "cg1_value": value,
                         "cg1_scatter": scatter, "source": source})
    return pd.DataFrame(rows)


def build_tables(study: Study, flow: FlowRecord, fields: dict[str, CaseFields],
                 granules: bool = True
                 ) -> tuple[pd.DataFrame, pd.DataFrame, list[dict], pd.DataFrame]:
    """(case table, condition table, skipped cases, noise-floor table) of a finished study
    from its flow record and its cases' fields (read once by the caller:
    :func:`~ligwf.analysis.records.fields.recorded_fields`; ``granules`` False: without the
    granule analysis' tables)."""
    cases, skipped = case_rows(study)
    analysis_dir = study.analysis_dir
    if cases.empty:
        return cases, pd.DataFrame(), skipped, pd.DataFrame()
    merged = merge_analysis(cases, analysis_dir, flow, granules)
    frames = _read_csv(analysis_dir / layout.FRAMES_TABLE) if granules else pd.DataFrame()
    settings = study.analysis
    stats = ConditionStats(case_series(list(merged["case_id"]), flow, frames),
                           settings.bootstrap, settings.seed, report_metrics(flow))
    df = compare_to_cg1(merged, stats, list(flow.error_metrics))
    df, conditions = add_field_errors(df, condition_table(df, stats, metric_columns(flow)),
                                      fields, settings.bootstrap,
                                      settings.seed, settings.field_kernel,
                                      read_rounds(study.path).alpha_per_look)
    return df, conditions, skipped, noise_floor_table(df, stats)
