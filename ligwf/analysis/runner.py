"""Whole-study analysis: every usable case, every frame -> flow, granule, GSD tables, series.

The MPI runner (:func:`analyse`) deals (case, frame) tasks round-robin to ranks (a frame
depends only on its own two dumps), gathers the results on rank 0, which alone sorts them
and writes the outputs: the same files whatever the number of ranks (each rank writes
the ``.vtu`` files of its own frames into the staging folder).

Cases are used only when the study says they are usable (manifest ``done`` for the scene
the folder holds and a thermo table that agrees with it,
:meth:`ligwf.study.case.CaseFolder.why_not_usable`); frames only when they are the run's
own (:mod:`ligwf.analysis.frames.checks`: expected steps, dump record, particle count and
ids, radii, drum, contact geometry). Everything else is listed with its reason -- skipped
cases, and missing, unexpected or refused frames -- in the analysis record and the frame
table, which the report shows; a case left without any analysable frame is a skipped
case. A usable case whose run holds no granule data by design (a dry scene, or
``scene.analysis.granules: false``: no contact dumps) is not a skipped case: the record
lists it under ``granules_absent`` with the reason in words, and when every usable case
is one, the record is written without granule tables (the flow stage and the report use
those cases all the same). When nothing at all could be analysed otherwise,
:class:`~ligwf.analysis.granule_stage.NothingAnalysed` is raised and the previous outputs stay as they were; a frame
the analysis fails on for any reason is a skipped frame (one bad frame never blocks the
others). Otherwise the outputs are replaced as one set
(:class:`~ligwf.analysis.outputs.OutputSet`). The science settings (bond criterion, GSD
binning and bootstrap, steady window) come from the study
(:class:`~ligwf.scene.settings.AnalysisSettings`), so every path that analyses a study
computes the same numbers. Granules are identified in every frame; the GSD uses the
frames of each case's steady window only, found once by the flow stage
(:mod:`ligwf.analysis.flow.stage`, every usable case, dealt to the ranks case by case).

Outputs (``OUT`` defaults to the study's analysis folder; names in
:mod:`ligwf.study.layout`):

* granule table (parquet): one row per granule per frame (case_id, cg, rule, replica,
  frame, step, time, granule, members, volume, primary_volume, com_x/y/z, first_id,
  percolating: the granule closes a cycle around the periodic axis);
* frame table: per frame: status (ok, missing, unexpected, skipped) and reason,
  particles, contacts, bonds, granules, largest granule share and whether the largest
  granule percolates (wraps around the periodic axis);
* GSD and GSD summary tables: see :mod:`ligwf.analysis.gsd.tables`;
* GSD pooling table and its summary per condition and pool size: the size limits and
  errors of CG-n replica pools of K = 1, 2, 4, 8 against CG1, and CG1 against itself;
* kinetics (per case and frame, per condition with bands and CG-n/CG1 ratios) and
  sensitivity tables: :mod:`ligwf.analysis.gsd.kinetics`; controls: :mod:`.study_controls`;
* flow table and flow record (steady window, metrics, series): :mod:`.flow_run`;
* per case a granule series: particles with a ``granule`` array per frame;
* the analysis record (JSON): settings, analysed and skipped cases with their steady
  window, skipped frames with reasons, cases without granule data, its provenance
  (:func:`~ligwf.analysis.records.provenance.study_provenance`) and the size and SHA-256 of every
  table, which the report checks before it uses any of them.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ligwf.analysis.granules.case import FrameResult, GranuleAnalysis, RunFacts
from ligwf.analysis.frames.dumps import FrameFiles
from ligwf.analysis.flow.stage import field_files, flow_cases, flow_record, flow_table
from ligwf.analysis.frames.checks import FramePlan, plan_frames
from ligwf.analysis.granule_stage import (GRANULE_OUTPUTS, commit, frame_tables,
                                          nothing_analysed, stage_granules)
from ligwf.analysis.outputs import OutputSet, new_token
from ligwf.analysis.records.flow import FlowRecord
from ligwf.analysis.records.provenance import study_provenance
from ligwf.errors import ConfigError
from ligwf.scene.settings import AnalysisSettings
from ligwf.study import layout
from ligwf.study.case import granules_absent
from ligwf.study.study import Study

__all__ = ["AnalysisOptions", "analyse"]

def _mpi_comm():
    """MPI.COMM_WORLD when started under mpirun with more than one rank, else None."""
    if not any(k in os.environ for k in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK")):
        return None
    from mpi4py import MPI

    return MPI.COMM_WORLD if MPI.COMM_WORLD.Get_size() > 1 else None


@dataclass(frozen=True)
class AnalysisOptions:
    """How ``ligwf analyse`` runs (execution only: the science is in ``settings``).

    ``settings`` None: the study's own (what every command uses); tests and benchmarks
    may pass others.
    """

    settings: AnalysisSettings | None = None
    implementation: str = "fast"     # "fast" (compiled) or "reference" (networkx)
    write_vtu: bool = True
    louvain: bool = False
    require_manifest: bool = True


def analyse(run_dir: Path, out_dir: Path | None = None, options: AnalysisOptions = AnalysisOptions(),
            comm=None) -> dict | None:
    """Analyse a study (or one case) folder; on rank 0 write the outputs and return the
    analysis record (other ranks return None). ``comm``: an mpi4py communicator, by
    default COMM_WORLD when running under mpirun with several ranks. NothingAnalysed
    (outputs untouched) when no frame could be analysed."""
    study = Study.open(run_dir)
    out_dir = Path(out_dir) if out_dir is not None else study.analysis_dir
    settings = options.settings or study.analysis
    comm = _mpi_comm() if comm is None else comm
    rank, size = (comm.Get_rank(), comm.Get_size()) if comm is not None else (0, 1)
    token = new_token() if comm is None else comm.bcast(new_token() if rank == 0 else None)
    outputs = OutputSet(out_dir, token)

    usable, skipped_cases = study.usable_cases(options.require_manifest)
    flow_skipped = list(skipped_cases)
    absent = [{"case_id": c.case_id, "reason": why} for c in usable
              if (why := granules_absent(c.scaled)) is not None]
    facts: list[RunFacts] = []
    for c in usable:
        if granules_absent(c.scaled) is not None:
            continue
        try:
            facts.append(RunFacts.of_case(c, plan_frames(c)))
        except ConfigError as exc:
            skipped_cases.append({"case_id": c.case_id, "reason": str(exc)})
    tasks = [(fi, ff) for fi, f in enumerate(facts) for ff in f.plan.frames]
    mine: list[FrameResult] = []
    try:
        my_flows = flow_cases(usable[rank::size], settings.steady_after,
                              settings.field_kernel)
        analyses: dict[int, GranuleAnalysis] = {}   # one per case: held windows share reads
        for fi, ff in tasks[rank::size]:
            f = facts[fi]
            if fi not in analyses:
                analyses[fi] = GranuleAnalysis(
                    f, settings, options.implementation,
                    outputs.case_dir(f.case_id) if options.write_vtu else None, options.louvain)
            mine.append(analyse_frame(analyses[fi], ff))
    except BaseException:
        outputs.discard()
        raise
    if comm is not None:
        gathered = comm.gather((mine, my_flows), root=0)
        if rank != 0:
            comm.barrier()
            return None
        results = [r for part, _ in gathered for r in part]
        by_case = {k: v for _, (f, _) in gathered for k, v in f.items()}
        notes = {k: v for _, (_, n) in gathered for k, v in n.items()}
    else:
        results, (by_case, notes) = mine, my_flows
    order = [c.case_id for c in usable]
    flows = flow_record({k: by_case[k] for k in order if k in by_case},
                        {k: notes[k] for k in order if k in notes}, settings.steady_after,
                        flow_skipped)
    try:
        record = write_outputs(study, outputs, facts, skipped_cases, results, settings, options,
                               absent, flows)
    except BaseException:
        outputs.discard()
        raise
    finally:
        if comm is not None:
            comm.barrier()
    return record


def analyse_frame(ana: GranuleAnalysis, ff: FrameFiles) -> FrameResult:
    """The granules of one frame; a frame the analysis fails on for any reason is a
    skipped frame with that reason (one bad frame never blocks the others)."""
    f = ana.case
    try:
        return ana.run([ff]).results[0]
    except (ConfigError, MemoryError, KeyboardInterrupt):
        raise
    except Exception as exc:   # a frame that passed its checks and still breaks the analysis
        return FrameResult(f.case_id, ff.step, ff.step * f.dt,
                           error=f"{ff.particles}: analysis failed on this frame "
                                 f"({type(exc).__name__}: {exc})")


def write_outputs(study: Study, outputs: OutputSet, facts: list[RunFacts], skipped_cases,
                  results, settings: AnalysisSettings, options: AnalysisOptions,
                  absent: list[dict], flows: FlowRecord) -> dict:
    """Tables, series and record of a study analysis, committed as one set. ``absent``:
    usable cases whose runs hold no granule data (``{case_id, reason}``: dry, or no
    contact dumps); when every usable case is one, the record says so and no granule
    table is written (the flow tables are, and the report uses those cases). ``flows``:
    the flow stage's record (its steady windows are the granule tables' too)."""
    tables = frame_tables(facts, results)
    skipped_frames, frame_index = tables.skipped_frames, tables.frame_index
    analysed = [f for f in facts if frame_index.get(f.case_id, 0) > 0]
    skipped_cases = skipped_cases + [
        {"case_id": f.case_id, "reason": f"no analysable frame ({f.plan.expected} expected; "
         "see the skipped frames)"} for f in facts if f not in analysed]
    base = {
        "run_dir": str(study.path),
        "settings": settings.model_dump(mode="json"),
        "options": {"implementation": options.implementation, "louvain": options.louvain,
                    "write_vtu": options.write_vtu,
                    "require_manifest": options.require_manifest},
        "granules_absent": list(absent),
        "provenance": study_provenance(study, settings),
        "skipped_cases": skipped_cases,
        "skipped_frames": skipped_frames,
    }
    if not analysed:
        if not absent:
            raise nothing_analysed(study.path, skipped_cases, skipped_frames)
        record = {**base, "cases": []}
        stage_flow(outputs, flows)
        commit(outputs, record, obsolete=GRANULE_OUTPUTS)
        return record
    cases = [f.case for f in analysed]
    steady_from = {c.case_id: flows.cases[c.case_id].steady_from_step for c in cases}
    stage_flow(outputs, flows)
    steady = stage_granules(outputs, tables, analysed, cases, steady_from, settings,
                            options.implementation, options.write_vtu, controls=True)
    steady_frames = steady.groupby("case_id")["step"].nunique() if len(steady) else {}
    plans: dict[str, FramePlan] = {f.case_id: f.plan for f in analysed}
    record = {
        **base,
        "cases": [{"case_id": c.case_id, "cg": c.cg, "rule": c.rule, "replica": c.replica,
                   "frames": plans[c.case_id].expected,
                   "analysed": frame_index.get(c.case_id, 0),
                   "dump_record": plans[c.case_id].record is not None,
                   "steady_from_step": steady_from[c.case_id],
                   "steady_frames": int(steady_frames.get(c.case_id, 0))} for c in cases],
    }
    commit(outputs, record, obsolete=GRANULE_OUTPUTS)    # e.g. no twins now: no controls.csv
    return record


def stage_flow(outputs: OutputSet, flows: FlowRecord) -> None:
    """Stage the flow table and the flow record (:mod:`ligwf.analysis.flow.stage`)."""
    outputs.write(layout.FLOW_TABLE, flow_table(flows).to_csv(index=False).encode())
    outputs.write(layout.FLOW_PROFILES, flows.to_text().encode())
    for name, data in field_files(flows).items():   # the cross-section fields
        outputs.write(name, data)
