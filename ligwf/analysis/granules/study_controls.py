"""The granule controls of a study: every wet case beside each of its control twins.

A workflow with ``sweep.controls: [cohesionless]`` runs, beside each case at the control
CG levels, a twin with surface tension and viscosity / 1000 (``ligwf.scene.workflow``);
``flow_matched`` adds a twin that also has the friction and rolling friction of
``sweep.flow_match`` (a dry bed that flows like the wet one). :func:`study_controls` pairs
each twin with its wet case (same sweep values, CG level,
rule and replica), measures both with the study's granule definition and the candidate
definitions (:mod:`ligwf.analysis.granules.control_run`), and judges every definition by the
pre-registered criteria (:mod:`ligwf.analysis.granules.control_verdict`). The table it returns is
``analysis/controls.csv``; the report prints it beside the GSD with the verdict sentence.
"""

from __future__ import annotations

import pandas as pd

from ligwf.analysis.granules.control_run import DEFAULT_CANDIDATES, control_rows, load_series, summarise
from ligwf.analysis.granules.control_verdict import verdict
from ligwf.scene.settings import AnalysisSettings
from ligwf.study.case import CaseFolder
from ligwf.study.condition import Condition

#: the ``varied`` value (under CONTROL_KEY) of a cohesionless twin
COHESIONLESS = "cohesionless"
#: ... and of a flow-matched one
FLOW_MATCHED = "flow_matched"


def control_pairs(cases: list[CaseFolder]) -> list[tuple[CaseFolder, CaseFolder]]:
    """(wet case, its twin) for every control twin (cohesionless or flow-matched) whose wet
    case is among ``cases``, in case order."""
    wet = {(c.condition, c.replica): c for c in cases if c.sweep_group.control is None}
    out = []
    for c in cases:
        if c.sweep_group.control in (COHESIONLESS, FLOW_MATCHED):
            twin_of = Condition(c.sweep_group.wet.text, c.cg, c.rule)
            w = wet.get((twin_of, c.replica))
            if w is not None:
                out.append((w, c))
    return out


def candidates_for(definition: AnalysisSettings):
    """The study's own definition first, then the candidates of the regime map."""
    name = "study definition (" + definition.granules + ")"
    own = ((name, "window", (definition.hold_time, None)) if definition.granules == "held"
           else (name, "frame", definition))
    return (own,) + tuple(c for c in DEFAULT_CANDIDATES if c[0] != definition.granules)


def study_controls(cases: list[CaseFolder], definition: AnalysisSettings,
                   steady_from: dict[str, float] | None = None) -> pd.DataFrame:
    """One row per (wet case, definition): the wet and twin measures side by side, whether
    the definition passes, and the sentence a report prints. Empty without twins.
    ``steady_from``: production time (s) of each wet case's steady start (default 0.5 s);
    its twin is measured from the same time."""
    rows = []
    for wet, twin in control_pairs(cases):
        cands = candidates_for(definition)
        t0 = (steady_from or {}).get(wet.case_id, 0.5)
        sw = summarise(control_rows(load_series(wet.path), cands, steady_from=t0))
        st = summarise(control_rows(load_series(twin.path), cands, steady_from=t0))
        kind = twin.sweep_group.control or COHESIONLESS
        for (_, w), (_, t) in zip(sw.iterrows(), st.iterrows()):
            ok, sentence = verdict(w.to_dict(), t.to_dict(), w["definition"], kind)
            row = {"case_id": wet.case_id, "twin_id": twin.case_id, "definition": w["definition"],
                   "passes": ok, "verdict": sentence}
            for k in ("share_2", "share_10", "count_10", "d50_mm", "largest_share",
                      "persist_short", "persist_quarter", "comove_ratio", "ari_seed",
                      "ari_order", "percolating_frames"):
                row[k] = w.get(k, float("nan"))
                row[f"twin_{k}"] = t.get(k, float("nan"))
            rows.append(row)
    return pd.DataFrame(rows)
