"""Granule definitions compared case by case on one analysed study: the steady frames of
every case identified again under each definition, and per case what acceptance (a) of the
source-study issue asks (no percolating granule, no granule holding the bed) beside the d50
and the granule count. ``scripts/gsd_cg_report.py`` writes this for
``docs/results/gsd_cg/previous_2026-11-28``; :func:`ligwf.analysis.gsd.pooling.pooling_table`
then pools its granules as ``ligwf analyse`` does.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd

from ligwf.analysis.frames.checks import plan_frames
from ligwf.analysis.granules.case import GranuleAnalysis
from ligwf.analysis.gsd import bins as gsdmod
from ligwf.analysis.records.analysis_record import AnalysisRecord
from ligwf.analysis.records.conditions import CaseLike
from ligwf.errors import DumpReadError
from ligwf.scene.settings import AnalysisSettings
from ligwf.study.case import CaseFolder
from ligwf.study.study import Study

#: the definitions compared (README name: settings): the default (Leiden CPM of the
#: rupture-work-weighted bridge network), the source study's (connected components of bridges
#: co-moving within 30 deg in the lab frame) and the force-weighted CPM of the old default
DEFINITIONS = {
    "cpm-energy (default until 2026-12-02)": AnalysisSettings(granules="communities"),
    "components lab 30 (source)": AnalysisSettings(granules="components", velocity_frame="lab",
                                                   max_velocity_angle=30.0),
    "cpm-force 0.02 (old default)": AnalysisSettings(granules="communities", resolution=0.02,
                                                     community_weight="force"),
}
#: columns of :func:`definition_table`
DEFINITION_COLUMNS = ["case_id", "cg", "replica", "frames", "percolating_frames",
                      "largest_share", "largest_share_max", "d50_mm", "granules"]


def steady_granules(study: Study, definition: AnalysisSettings) -> tuple[pd.DataFrame, list[CaseFolder]]:
    """The granule table (with ``case_id`` and ``step``) of the steady frames (the window
    the study's analysis used, ``analysis/analysis.json``) of every analysed case of
    ``study`` under ``definition``, and those cases; DumpReadError naming the case and
    step of a frame that cannot be read."""
    analysed = AnalysisRecord.load(study.analysis_dir).items("cases")
    steady_from = {c["case_id"]: c["steady_from_step"] for c in analysed}
    tables, cases = [], []
    for case in study.cases:
        if case.case_id not in steady_from:
            continue
        frames = [f for f in plan_frames(case).frames if f.step >= steady_from[case.case_id]]
        for r in GranuleAnalysis(case, definition).run(frames).results:
            if r.table is None:
                raise DumpReadError(f"{case.case_id} step {r.step}: {r.error}")
            tables.append(r.table.assign(case_id=case.case_id, step=r.step))
        cases.append(case)
    return pd.concat(tables, ignore_index=True), cases


def definition_table(granules: pd.DataFrame, cases: Sequence[CaseLike],
                     min_particles: int = 2) -> pd.DataFrame:
    """Per case (:data:`DEFINITION_COLUMNS`): its frames, the share of them with a
    percolating granule, the largest granule's share of the bed (mean and max over frames,
    every granule), the mean d50 (mm) and count of the counted granules (>=
    ``min_particles``, not percolating)."""
    rows = []
    for c in cases:
        t = granules[granules.case_id == c.case_id]
        perc, largest, d50, count = [], [], [], []
        for _, fr in t.groupby("step"):
            counted = gsdmod.counted(fr["members"].to_numpy(), fr["percolating"].to_numpy(bool),
                                     min_particles)
            perc.append(bool(fr["percolating"].any()))
            largest.append(fr["volume"].max() / fr["volume"].sum())
            d50.append(gsdmod.percentile_diameters(fr["volume"].to_numpy()[counted], (0.5,))[0])
            count.append(int(counted.sum()))
        rows.append({"case_id": c.case_id, "cg": c.cg, "replica": c.replica, "frames": len(perc),
                     "percolating_frames": float(np.mean(perc)),
                     "largest_share": float(np.mean(largest)),
                     "largest_share_max": float(np.max(largest)),
                     "d50_mm": 1e3 * float(np.nanmean(d50)), "granules": float(np.mean(count))})
    return pd.DataFrame(rows, columns=DEFINITION_COLUMNS)
