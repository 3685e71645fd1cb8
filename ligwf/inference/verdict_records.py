"""The verdict's records in the report folder: a table (one row per sweep group, CG level,
rule and criterion) and a JSON record the terminal and the Python API read back; and the
verdict of a study's report tables (:func:`study_verdict`, with the granule control
verdicts of its analysis folder). File names: :mod:`ligwf.study.layout`."""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from pathlib import Path

import pandas as pd

from ligwf.inference.equivalence import ALPHA, WELCH
from ligwf.fsio import atomic_write_json, atomic_write_text, json_safe
from ligwf.inference.registry import CriterionResult
from ligwf.inference.verdict import ConditionVerdict, GroupVerdict, Verdict, decide, granule_gates
from ligwf.scene.accept import AcceptSettings
from ligwf.study import layout
from ligwf.study.condition import Condition


def verdict_rows(verdict: Verdict) -> pd.DataFrame:
    """One row per condition (group, CG level, rule) and criterion: what verdict.csv holds."""
    rows = []
    for g in verdict.groups:
        for c in g.conditions:
            for r in c.criteria:
                rows.append({"group": c.condition.group, "cg": c.condition.cg,
                             "rule": c.condition.rule,
                             "condition": c.name, "replicas": c.replicas,
                             "condition_state": c.state, "speedup_core": c.speedup,
                             "speedup_core_lo": c.speedup_lo, "speedup_core_hi": c.speedup_hi,
                             "criterion": r.name, "label": r.label, "unit": r.unit,
                             "state": r.state, "value": r.value, "lo": r.lo, "hi": r.hi,
                             "budget": r.budget, "shown_within": r.bound,
                             "budget_source": r.budget_source,
                             "decide_by": r.decide_by, "decide_arm": r.decide_arm,
                             "decide_amount": r.decide_amount,
                             "decide_amount_cg1": r.decide_amount_cg1,
                             "decide_core_hours": r.decide_core_hours,
                             "decide_half_width": r.decide_half_width,
                             "note": r.note, "too_short": bool(c.too_short),
                             "too_short_note": c.too_short,
                             "cheapest": g.cheapest == c.name})
    return pd.DataFrame(rows)


def write_verdict(verdict: Verdict, out: Path) -> None:
    """``verdict.csv`` and ``verdict.json`` into the report folder ``out`` (atomically)."""
    record = {"accept": verdict.accept, "statistics": json_safe(verdict.statistics), "groups": [
        {**json_safe(asdict(g)), "conditions": [{**json_safe(asdict(c)), "state": c.state,
                                              "name": c.name} for c in g.conditions]}
        for g in verdict.groups]}
    atomic_write_text(out / layout.VERDICT_TABLE, verdict_rows(verdict).to_csv(index=False))
    atomic_write_json(out / layout.VERDICT_RECORD, record)


def _nan(v) -> float:
    return math.nan if v is None else float(v)


def read_verdict(out: Path) -> Verdict | None:
    """The verdict written into the report folder ``out`` (None when there is none)."""
    try:
        rec = json.loads((Path(out) / layout.VERDICT_RECORD).read_text())
        groups = []
        for g in rec["groups"]:
            conds = []
            for c in g["conditions"]:
                crit = tuple(CriterionResult(**{**r, **{k: _nan(r.get(k)) for k in
                                                        ("value", "lo", "hi", "budget",
                                                         "bound", "decide_amount", "decide_amount_cg1",
                                                         "round_amount", "round_amount_cg1",
                                                         "round_core_hours",
                                                         "decide_core_hours",
                                                         "decide_half_width")
                                                        if k in r}})
                             for r in c["criteria"])
                conds.append(ConditionVerdict(c["group"], float(c["cg"]), c["rule"],
                                              int(c["replicas"]), _nan(c["speedup"]),
                                              _nan(c["speedup_lo"]), _nan(c["speedup_hi"]), crit,
                                              c.get("too_short") or ""))
            groups.append(GroupVerdict(g["group"], tuple(conds), g["sentence"], g["cheapest"]))
        return Verdict(tuple(groups), rec.get("accept", {}), rec.get("statistics") or {})
    except (OSError, ValueError, KeyError, TypeError):
        return None


def study_verdict(cases: pd.DataFrame, conditions: pd.DataFrame, accept: AcceptSettings,
                  controls: pd.DataFrame | None, profiles: dict | None = None,
                  noise: pd.DataFrame | None = None, alpha: float = ALPHA,
                  df_rule: str = WELCH, size_ratio: float = math.nan,
                  speedups: dict[Condition, float] | None = None) -> Verdict:
    """The verdict of a study's report tables, with its granule control verdicts
    (``controls``: the analysis' controls table, None without twins; ``noise``: the runs'
    noise and prices, what would decide; ``alpha``: each test's level; ``size_ratio`` and
    ``speedups``: a sweep without CG1, :func:`ligwf.inference.verdict.decide`)."""
    if cases.empty or conditions.empty:
        return Verdict((), accept.model_dump(mode="json"))
    return decide(conditions, accept, granule_gates(cases, controls),
                  cases, profiles, alpha, noise, df_rule, size_ratio, speedups)
