"""The granule stage's outputs, shared by every frame source (a study, foreign dumps).

From the per-frame results of :class:`~ligwf.analysis.granules.case.GranuleAnalysis`
(whichever ranks computed them) and each case's steady window, :func:`stage_granules`
stages the same set for a study (:mod:`ligwf.analysis.runner`) and for dumps ligwf did
not write (:mod:`ligwf.analysis.foreign`): granule and frame tables, GSD and GSD summary
(steady window), replica pooling and its summary, kinetics and its summary, the
definition sensitivity, the granule controls (a study's twins) and per case the granule
series; :meth:`~ligwf.analysis.records.analysis_record.AnalysisRecord.commit` then
writes the analysis record and moves the set into place. File names in
:mod:`ligwf.study.layout`.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.granules.case import FrameResult, RunFacts, pvd_text
from ligwf.analysis.frames.dumps import FrameFiles
from ligwf.analysis.gsd.pooling import pooling_summary, pooling_table
from ligwf.analysis.gsd.tables import gsd_tables
from ligwf.analysis.gsd.kinetics import kinetics_summary, kinetics_table, sensitivity_table
from ligwf.analysis.outputs import OutputSet
from ligwf.analysis.records.conditions import CaseLike, Conditions
from ligwf.analysis.granules.study_controls import control_pairs, study_controls
from ligwf.errors import LigwfError
from ligwf.scene.settings import AnalysisSettings
from ligwf.study import layout


class NothingAnalysed(LigwfError):
    """No frame of any case could be analysed; the previous outputs were kept."""


def nothing_analysed(where: Path, skipped_cases: list[dict], skipped_frames: list[dict]) -> NothingAnalysed:
    """The one-line refusal when no frame could be analysed (first reason included)."""
    first = (skipped_frames or skipped_cases or [{"reason": "no case and no frame"}])[0]
    return NothingAnalysed(
        f"nothing analysed in {where}: {len(skipped_cases)} case(s) skipped, "
        f"{len(skipped_frames)} frame(s) missing or refused; first: "
        f"{first.get('case_id', '')} {first['reason']}; previous outputs kept")


#: replica pool sizes of the GSD pooling table (ensembles: the source study's fix)
POOL_SIZES = (1, 2, 4, 8)


@dataclass(frozen=True)
class GranuleTables:
    """What :func:`frame_tables` makes of the frame results."""

    granules: pd.DataFrame
    frames: pd.DataFrame
    skipped_frames: list[dict]
    frame_index: dict[str, int]     # analysed frames per case
    results: list[FrameResult]      # in case and step order


def stage_granules(outputs: OutputSet, tables: GranuleTables, analysed: list[RunFacts],
                   cases: list[CaseLike], steady_from: dict[str, float],
                   settings: AnalysisSettings, implementation: str, write_vtu: bool,
                   controls: bool, frames_of: dict[str, list[FrameFiles]] | None = None
                   ) -> pd.DataFrame:
    """Stage every granule output of the ``analysed`` runs (``cases``: the same runs as
    cases of the tables) and return the granule rows of the steady windows.
    ``frames_of``: the frames of each run (default: its frame plan), for the sensitivity
    table; ``controls``: the cases are a study's case folders (twins are looked for)."""
    granules = tables.granules
    steady = granules[granules["step"] >= granules["case_id"].map(steady_from).astype(float)]
    gsd_df, summary = gsd_tables(steady, cases, settings)
    stage_tables(outputs, granules, tables.frames, gsd_df, summary)
    pooled = pooling_table(steady, cases, settings, POOL_SIZES)
    outputs.write(layout.GSD_POOLING_TABLE, pooled.to_csv(index=False).encode())
    if not pooled.empty:
        outputs.write(layout.GSD_POOLING_SUMMARY_TABLE,
                      pooling_summary(pooled).to_csv(index=False).encode())
    frames_of = frames_of or {f.case_id: f.plan.frames for f in analysed}
    stage_kinetics(outputs, granules, analysed, cases, frames_of, steady_from, settings,
                   implementation)
    if controls:
        stage_controls(outputs, cases, steady_from, settings)
    if write_vtu:
        for f in analysed:
            entries = [(r.time, r.vtu) for r in tables.results
                       if r.case_id == f.case_id and r.vtu]
            if entries:
                outputs.write(f"{f.case_id}/{layout.GRANULE_SERIES}", pvd_text(entries).encode())
    return steady


def frame_tables(facts: list[RunFacts], results: list[FrameResult]) -> GranuleTables:
    """The granule table, frame rows, skipped frames and analysed frames per case of
    ``results`` (and of the frames refused before reading) in case and step order."""
    order = {f.case_id: fi for fi, f in enumerate(facts)}
    refused = [FrameResult(p["case_id"], p["step"], p["step"] * facts[order[p["case_id"]]].dt,
                           error=p["reason"], kind=p["kind"])
               for f in facts if f.plan is not None for p in f.plan.problems]
    results = sorted(results + refused, key=lambda r: (order[r.case_id], r.step))
    by_case = {f.case_id: f for f in facts}
    tables, frame_rows, skipped_frames = [], [], []
    frame_index: dict[str, int] = {}
    for r in results:
        f = by_case[r.case_id]
        if r.error is not None:
            kind = r.kind or "skipped"
            if kind != "window":      # the last hold_time of a run (granules: held): not a fault
                skipped_frames.append({"case_id": r.case_id, "step": r.step, "kind": kind,
                                       "reason": r.error})
            frame_rows.append({"case_id": r.case_id, "step": r.step, "time": r.time,
                               "status": kind, "reason": r.error})
            continue
        k = frame_index.get(r.case_id, 0)
        frame_index[r.case_id] = k + 1
        t = r.table
        c = f.case
        tables.append(t.assign(case_id=r.case_id, cg=f.cg, rule=c.rule if c else "",
                               replica=c.replica if c else 0, frame=k, step=r.step, time=r.time))
        vol = t["volume"].to_numpy()
        frame_rows.append({"case_id": r.case_id, "step": r.step, "time": r.time, "status": "ok",
                           "reason": "", "particles": r.particles, "contacts": r.contacts,
                           "bonds": r.bonds, "granules": len(t),
                           "largest_fraction": float(vol.max() / vol.sum()),
                           "largest_percolates": bool(t["percolating"].to_numpy()[vol.argmax()])})
    granules = (pd.concat(tables, ignore_index=True)[GRANULE_COLUMNS] if tables
                else pd.DataFrame({c: pd.Series(dtype=float) for c in GRANULE_COLUMNS}))
    frames = pd.DataFrame(frame_rows, columns=FRAME_COLUMNS)
    return GranuleTables(granules, frames, skipped_frames, frame_index, results)


GRANULE_COLUMNS = ["case_id", "cg", "rule", "replica", "frame", "step", "time", "granule",
                   "members", "volume", "primary_volume", "com_x", "com_y", "com_z", "first_id",
                   "percolating"]
FRAME_COLUMNS = ["case_id", "step", "time", "status", "reason", "particles", "contacts",
                 "bonds", "granules", "largest_fraction", "largest_percolates"]


def stage_tables(outputs: OutputSet, granules: pd.DataFrame, frames: pd.DataFrame,
                 gsd_df: pd.DataFrame, summary: pd.DataFrame) -> None:
    """Stage the four tables of an analysis."""
    buf = io.BytesIO()
    granules.to_parquet(buf, index=False)
    outputs.write(layout.GRANULES_TABLE, buf.getvalue())
    outputs.write(layout.FRAMES_TABLE, frames.to_csv(index=False).encode())
    outputs.write(layout.GSD_TABLE, gsd_df.to_csv(index=False).encode())
    outputs.write(layout.GSD_SUMMARY_TABLE, summary.to_csv(index=False).encode())


def stage_kinetics(outputs: OutputSet, granules: pd.DataFrame, analysed: list[RunFacts],
                   cases: list[CaseLike], frames_of: dict[str, list[FrameFiles]],
                   steady_from: dict[str, float], settings: AnalysisSettings,
                   implementation: str) -> None:
    """Stage the kinetics tables (every frame) and the sensitivity table: up to
    ``settings.sensitivity_frames`` steady frames, evenly spread, of the first CG1 case
    (else the first case), analysed again under each variant of the definition."""
    kin = kinetics_table(granules, cases, settings)
    outputs.write(layout.KINETICS_TABLE, kin.to_csv(index=False).encode())
    summary = kinetics_summary(kin, settings)
    outputs.write(layout.KINETICS_SUMMARY_TABLE, summary.to_csv(index=False).encode())
    if settings.sensitivity_frames == 0:
        return
    first = Conditions.of(cases).first_reference_case()
    facts = next((f for f in analysed if f.case_id == first), analysed[0])
    steady = [ff for ff in frames_of[facts.case_id] if ff.step >= steady_from[facts.case_id]]
    if not steady:
        return
    pick = np.unique(np.linspace(0, len(steady) - 1, settings.sensitivity_frames).round())
    table = sensitivity_table(facts, [steady[int(k)] for k in pick], settings,
                              implementation)
    outputs.write(layout.SENSITIVITY_TABLE, table.to_csv(index=False).encode())


def stage_controls(outputs: OutputSet, cases: list, steady_from: dict[str, int],
                   settings: AnalysisSettings) -> None:
    """``controls.csv``: every wet case beside its cohesionless twin (none without twins),
    measured from the wet case's steady window on (:mod:`ligwf.analysis.granules.study_controls`)."""
    pairs = control_pairs(cases)
    if not pairs:
        return
    start = {w.case_id: (steady_from[w.case_id] - w.production_start_step) * w.scaled.numerics.dt
             for w, _ in pairs}
    table = study_controls(cases, settings, start)
    outputs.write(layout.CONTROLS_TABLE, table.to_csv(index=False).encode())


#: Tables of a granule analysis: an analysis without granule data removes old ones.
GRANULE_OUTPUTS = (layout.GRANULES_TABLE, layout.FRAMES_TABLE, layout.GSD_TABLE,
                   layout.GSD_SUMMARY_TABLE, layout.GSD_POOLING_TABLE,
                   layout.GSD_POOLING_SUMMARY_TABLE, layout.KINETICS_TABLE,
                   layout.KINETICS_SUMMARY_TABLE, layout.SENSITIVITY_TABLE, layout.CONTROLS_TABLE)
