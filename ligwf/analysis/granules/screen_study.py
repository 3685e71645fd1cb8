"""The granule screen's study folder measured (docs/results/granule_screen/criterion.md):
phase 1's conditions (one seed each, in sub-folders named by them; which conditions, and
their liquid model and placement, the results script declares) and phase 2's pick beside
its uniform twin (:data:`PHASE2`, :data:`PHASE2_UNIFORM`), each run
read once by :func:`~ligwf.analysis.granules.growth_study.measure_case` with the registered
settings; :mod:`ligwf.analysis.granules.screen` scores what this returns.
"""

from __future__ import annotations

import json
import math
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

import pandas as pd

from ligwf.analysis.granules.growth_study import measure_case
from ligwf.analysis.granules.screen import SETTINGS, condition_row, phase2_seeds, ranked
from ligwf.study import layout

#: phase 2 (criterion.md): the pick's sub-study and its uniform twin's
PHASE2, PHASE2_UNIFORM = "P2", "P2U"


@dataclass(frozen=True)
class Phase1:
    """Phase 1 measured: every start frame of every run (``rows``, with its ``condition``)
    and one row per condition, scored and ranked (``conditions``)."""

    rows: pd.DataFrame
    conditions: pd.DataFrame


@dataclass(frozen=True)
class Phase2:
    """Phase 2 measured: every start frame of every run (``rows``), each run's status and
    core-minutes (``runs``), one row per registered seed with both nulls and the criteria
    (``seeds``). A uniform twin's case id has the suffix ``_uniform``."""

    rows: pd.DataFrame
    runs: pd.DataFrame
    seeds: pd.DataFrame


def case_folder(study: Path, name: str) -> Path | None:
    """The one case folder of condition ``name`` (its seed r0), or None when not run."""
    found = sorted(p.parent for p in (study / name).glob(f"cg1-*/{layout.MANIFEST_FILE}"))
    return found[0] if found else None


def status_of(case: Path) -> tuple[str, float, str]:
    """(status, core seconds, the manifest's reason) of a run."""
    m = json.loads((case / layout.MANIFEST_FILE).read_text())
    return (str(m.get("status")), float(m.get("core_seconds") or math.nan),
            str(m.get("reason") or ""))


def measure_phase1(study: Path, conditions: Mapping[str, tuple[str, str]]) -> Phase1 | None:
    """Each of ``conditions`` (name -> (liquid model, how the liquid is placed)) that ran in
    ``study``, measured and scored; None when none ran."""
    all_rows, table = [], []
    for name, (model, liquid) in conditions.items():
        case = case_folder(study, name)
        if case is None:
            continue
        status, core_s, reason = status_of(case)
        rows, _, flows = measure_case(case, SETTINGS, cadences=(SETTINGS.cadence,))
        rows.insert(0, "condition", name)
        all_rows.append(rows)
        table.append(condition_row(name, model, liquid, rows, flows, status, core_s, reason))
    if not table:
        return None
    return Phase1(pd.concat(all_rows), ranked(pd.DataFrame(table)))


def measure_phase2(study: Path) -> Phase2 | None:
    """Phase 2's runs in ``study`` measured (two at a time, the machine's cores, in case
    order) and their seeds paired with both nulls; None when phase 2 has not run."""
    if not (study / PHASE2).is_dir():
        return None
    all_rows, all_flows, runs, done = [], [], [], []
    for folder, suffix in ((PHASE2, ""), (PHASE2_UNIFORM, "_uniform")):
        for manifest in sorted((study / folder).glob(f"cg1-*/{layout.MANIFEST_FILE}")):
            case = manifest.parent
            status, core_s, reason = status_of(case)
            runs.append({"case_id": case.name + suffix, "status": status,
                         "reason": "" if status == "done" else reason,
                         "core_minutes": core_s / 60.0})
            if status == "done":
                done.append((case, case.name + suffix))
    with ProcessPoolExecutor(max_workers=min(2, os.cpu_count() or 1)) as pool:
        measured = list(pool.map(_measure, [case for case, _ in done]))
    for (_, case_id), (rows, flows) in zip(done, measured):
        rows["case_id"], flows["case_id"] = case_id, case_id
        all_rows.append(rows)
        all_flows.append(flows)
    rows = pd.concat(all_rows) if all_rows else pd.DataFrame()
    flows = pd.concat(all_flows) if all_flows else pd.DataFrame()
    return Phase2(rows, pd.DataFrame(runs), phase2_seeds(rows, flows))


def _measure(case: Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    rows, _, flows = measure_case(case, SETTINGS, cadences=(SETTINGS.cadence,))
    return rows, flows
