"""A study decided: its tables (cases, conditions with their intervals, noise floors:
:mod:`ligwf.inference.study_tables`), the verdict record and the extrapolated CG1 table,
computed once from the analysis' values and written into the report folder before
anything is rendered.

This is the one place a study's statistics are computed: the report
(:func:`ligwf.report.write.write_report`) renders what :func:`decide_study` returns and
wrote, and the API (:func:`ligwf.api.open_study`) reads the same files back (the verdict
through :func:`~ligwf.inference.verdict_records.read_verdict`). What it reads besides the
analysis' flow record and tables: the granule controls
(:mod:`ligwf.analysis.records.controls`), the field archive, the runs' noise and prices
(:func:`~ligwf.inference.planning.noise_table`), the level each test is run at (a
sequential study's looks: :func:`look_level`), and the drum's size ratio and the planner's
CG1 speedup per level (:func:`extrapolation_inputs`) for a sweep judged against an
extrapolated CG1.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from ligwf.analysis.records.controls import read_controls
from ligwf.analysis.records.fields import CaseFields, recorded_fields
from ligwf.analysis.records.flow import FlowRecord
from ligwf.fsio import atomic_write_text
from ligwf.inference.budget import signed_columns
from ligwf.inference.equivalence import HSU, WELCH_BF
from ligwf.inference.field_tables import null_check
from ligwf.inference.planning import noise_table
from ligwf.inference.reference import extrapolation_rows, planned_cg1_speedup, size_ratio
from ligwf.inference.spreading import case_times, level_rates
from ligwf.inference.study_tables import build_tables
from ligwf.inference.verdict import Verdict
from ligwf.inference.verdict_records import study_verdict, write_verdict
from ligwf.study import layout
from ligwf.study.case import CaseFolder
from ligwf.study.condition import Condition
from ligwf.study.rounds import Rounds, read_rounds
from ligwf.study.study import Study


@dataclass(frozen=True)
class Decided:
    """What :func:`decide_study` wrote: the case, condition and noise-floor tables
    (``cases.csv``, ``conditions.csv``, ``noise_floor.csv``), the verdict (its record
    ``verdict.json`` / ``verdict.csv``), the extrapolated CG1 rows (``extrapolation.csv``)
    and the drum's d / D they were computed with (nan without a scene record), the field
    null checks and placed liquid's spreading (no rows without fields / placed liquid)."""

    cases: pd.DataFrame
    conditions: pd.DataFrame
    floors: pd.DataFrame
    verdict: Verdict
    extrapolated: pd.DataFrame
    size_ratio: float
    field_null: pd.DataFrame        # the field criterion's null checks (field_null.csv)
    spreading_cases: pd.DataFrame   # placed liquid's spreading time per case
    spreading_levels: pd.DataFrame  # and per CG-n level against CG1 (spreading.csv)
    fields: dict[str, CaseFields]   # the cases' fields they were computed from (the maps')


def look_level(rounds: Rounds) -> tuple[float, str]:
    """(alpha, df rule) of each test: a sequential study's looks test at alpha / looks with
    Hsu's conservative degrees of freedom (:mod:`ligwf.study.rounds`); a single look Welch's
    for equal arms and the Behrens-Fisher distribution for unequal ones (Welch is liberal
    there, Hsu's far too wide: docs/results/verdict_rates)."""
    return rounds.alpha_per_look, (HSU if rounds.max_looks > 1 else WELCH_BF)


def extrapolation_inputs(usable: list[CaseFolder]) -> tuple[float, dict[Condition, float]]:
    """(d / D of the study's drum, condition -> the planner's CG1 cost over the level's):
    read from the ``usable`` cases' scene records (nan / empty without one)."""
    ratio, speedups = math.nan, {}
    for case in usable:
        try:
            scene = json.loads((case.path / layout.SCENE_FILE).read_text())["scene"]
        except (OSError, ValueError, KeyError):
            continue
        if not math.isfinite(ratio):
            ratio = size_ratio(scene)
        if case.cg > 1.0 and case.condition not in speedups:
            speedups[case.condition] = planned_cg1_speedup(scene, case.cg, case.rule)
    return ratio, speedups


def decide_study(study: Study, flow: FlowRecord, out: Path) -> Decided:
    """Decide ``study`` from its analysis (``flow``, and the tables beside it): build its
    tables (:func:`~ligwf.inference.study_tables.build_tables`), decide the verdict and
    write the tables, the verdict record and ``extrapolation.csv`` into ``out``."""
    fields = recorded_fields(study.analysis_dir)       # the field archive, read once
    cases, conditions, _, floors = build_tables(study, flow, fields)
    atomic_write_text(out / layout.CASES_REPORT, cases.to_csv(index=False))
    atomic_write_text(out / layout.CONDITIONS_REPORT, conditions.to_csv(index=False))
    atomic_write_text(out / layout.NOISE_FLOOR_REPORT, floors.to_csv(index=False))
    usable = study.usable_cases()[0]
    ratio, speedups = extrapolation_inputs(usable)
    verdict = study_verdict(cases, conditions, study.accept, read_controls(study.analysis_dir),
                            {cid: c.profile_v_mean for cid, c in flow.cases.items()},
                            noise_table(usable, flow, signed_columns()),
                            *look_level(read_rounds(study.path)), size_ratio=ratio,
                            speedups=speedups)
    write_verdict(verdict, out)
    extrapolated = extrapolation_rows(cases, signed_columns(), ratio)
    atomic_write_text(out / layout.EXTRAPOLATION_REPORT, extrapolated.to_csv(index=False))
    settings = study.analysis
    null = null_check(cases, fields, settings.bootstrap, settings.seed, settings.field_kernel)
    atomic_write_text(out / layout.FIELD_NULL_REPORT, null.to_csv(index=False))
    spread_cases = case_times(flow.cases.values())
    spread_levels = level_rates(spread_cases)
    atomic_write_text(out / layout.SPREADING_REPORT, spread_levels.to_csv(index=False))
    return Decided(cases, conditions, floors, verdict, extrapolated, ratio, null,
                   spread_cases, spread_levels, fields)
