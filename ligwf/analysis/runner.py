"""Whole-study analysis: every usable case, every frame -> flow, granule, GSD tables, series.

The MPI runner (:func:`analyse`) gives each rank a contiguous run of the (case, frame)
tasks (a frame depends only on its own dumps, a ``held`` window on the frames after it,
which then stay on one rank) and the flow of the cases whose middle frame it holds
(:meth:`AnalysisShares.share`), gathers the results on rank 0, which alone sorts them and
writes the outputs: the same files whatever the number of ranks (each rank writes the
``.vtu`` files of its own frames into the staging folder). The same shares can run as
the tasks of a Slurm array instead (:func:`analyse_part`, each writing one partial
output, then :func:`merge_parts`: :mod:`ligwf.analysis.parts`), with the same outputs.
Within a share each dump is checked once for both stages
(:func:`~ligwf.analysis.frames.checks.shared_checks`).

Cases are used only when the study says they are usable (manifest ``done`` for the scene
the folder holds and a thermo table that agrees with it,
:meth:`ligwf.study.case.CaseFolder.why_not_usable`); frames only when they are the run's
own (:mod:`ligwf.analysis.frames.checks`: expected steps, dump record, particle count and
ids, radii, drum, contact geometry). Everything else is listed with its reason -- skipped
cases, and missing, unexpected or refused frames -- in the analysis record and the frame
table, which the report shows; a case left without any analysable frame is a skipped
case. A usable case whose run holds no granule data by design (a dry scene, or
``scene.analysis.contact_dumps: false``: no contact dumps) is not a skipped case: the record
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
* frame table: per frame: status (ok, missing, unexpected, duplicate, skipped) and reason,
  particles, contacts, bonds, granules, largest granule share and whether the largest
  granule percolates (wraps around the periodic axis);
* GSD and GSD summary tables: see :mod:`ligwf.analysis.gsd.tables`;
* GSD pooling table and its summary per condition and pool size: the size limits and
  errors of CG-n replica pools of K = 1, 2, 4, 8 against CG1, and CG1 against itself;
* kinetics (per case and frame, per condition with bands and CG-n/CG1 ratios) and
  sensitivity tables: :mod:`ligwf.analysis.gsd.kinetics`; controls:
  :mod:`ligwf.analysis.granules.study_controls`;
* flow table and flow record (steady window, metrics, series): :mod:`ligwf.analysis.flow.stage`;
* per case a granule series: particles with a ``granule`` array per frame;
* the analysis record (JSON): settings, analysed and skipped cases with their steady
  window, skipped frames with reasons, cases without granule data, its provenance
  (:func:`~ligwf.analysis.records.provenance.study_provenance`) and the size and SHA-256 of every
  table, which the report checks before it uses any of them.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

from ligwf.analysis.granules.case import FrameResult, GranuleAnalysis, RunFacts
from ligwf.analysis.frames.dumps import FrameFiles
from ligwf.analysis.flow.stage import field_files, flow_cases, flow_record, flow_table
from ligwf.scene.grains import scaled_mean_diameter, study_strip
from ligwf.analysis.frames.checks import ExpectedFrames, plan_frames, shared_checks
from ligwf.analysis.records.analysis_record import AnalysisRecord
from ligwf.analysis.granule_stage import (GRANULE_OUTPUTS, frame_tables,
                                          nothing_analysed, stage_granules)
from ligwf.analysis.outputs import OutputSet, new_token
from ligwf.analysis.parts import Share, check_token, drop_parts, read_parts, write_part
from ligwf.analysis.records.flow import FlowRecord
from ligwf.analysis.records.provenance import study_provenance
from ligwf.errors import ConfigError
from ligwf.scene.settings import AnalysisSettings
from ligwf.study import layout
from ligwf.study.case import CaseFolder, folder_fingerprint, granules_absent
from ligwf.study.study import Study

__all__ = ["AnalysisOptions", "AnalysisShares", "analyse", "analyse_part", "merge_parts", "mpi_comm"]

def mpi_comm():
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


@dataclass
class AnalysisShares:
    """What an analysis decides before computing anything, the same on every MPI rank and
    in every array task (:mod:`ligwf.analysis.parts`): the study, its usable cases, the
    (case, frame) tasks and the cases' run facts."""

    study: Study
    settings: AnalysisSettings
    options: AnalysisOptions
    usable: list[CaseFolder]
    unusable: list[dict]            # cases the study does not let any stage use
    skipped_cases: list[dict]       # ... and those whose frames cannot be planned
    absent: list[dict]
    facts: list[RunFacts]
    tasks: list[tuple[int, FrameFiles]]

    @property
    def strip(self) -> float | None:
        """The angle's surface strips (m): one physical width for every case of the study
        (:func:`~ligwf.analysis.flow.surface.study_strip`), the same on every rank."""
        return study_strip([scaled_mean_diameter(c.scaled) for c in self.usable],
                           self.settings.surface_strip)

    def share(self, rank: int, size: int) -> tuple[list[tuple[int, FrameFiles]], list[CaseFolder]]:
        """The tasks and flow cases of rank ``rank`` of ``size``: a contiguous run of the
        tasks (a case's frames stay together, so a ``held`` window reads each frame once
        per rank), and the flow of every case whose middle frame it holds (that rank has
        just checked those dumps; cases without granule frames are dealt round-robin)."""
        n = len(self.tasks)
        mine = self.tasks[rank * n // size:(rank + 1) * n // size]
        where: dict[int, list[int]] = {}
        for k, (fi, _) in enumerate(self.tasks):
            where.setdefault(fi, []).append(k)
        owner: dict[str, int] = {}
        for fi, ks in where.items():
            middle = ks[len(ks) // 2]
            # the rank r with r n // size <= middle < (r + 1) n // size
            owner[self.facts[fi].case_id] = next(r for r in range(size)
                                                 if middle < (r + 1) * n // size)
        rest = [c.case_id for c in self.usable if c.case_id not in owner]
        ids = {k for k, r in owner.items() if r == rank}
        ids |= {cid for k, cid in enumerate(rest) if k % size == rank}
        return mine, [c for c in self.usable if c.case_id in ids]

    def fingerprint(self) -> str:
        """SHA-256 of what the shares depend on: cases (scene hash, dump record), frames,
        settings and options; a part computed for another plan is refused at the merge."""
        data = {"cases": [[c.case_id, folder_fingerprint(c.path)] for c in self.usable],
                "skipped": self.skipped_cases,
                "tasks": [[self.facts[fi].case_id, ff.step, str(ff.particles),
                           str(ff.contacts)] for fi, ff in self.tasks],
                "settings": self.settings.model_dump(mode="json"),
                "options": [self.options.implementation, self.options.write_vtu,
                            self.options.louvain, self.options.require_manifest]}
        return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def plan_analysis(run_dir: Path, options: AnalysisOptions = AnalysisOptions()) -> AnalysisShares:
    """The :class:`AnalysisShares` of a study (or one case) folder."""
    study = Study.open(run_dir)
    settings = options.settings or study.analysis
    usable, skipped_cases = study.usable_cases(options.require_manifest)
    unusable = list(skipped_cases)
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
    return AnalysisShares(study, settings, options, usable, unusable, skipped_cases, absent,
                        facts, tasks)


def compute_share(plan: AnalysisShares, outputs: OutputSet, rank: int, size: int) -> Share:
    """Rank ``rank`` of ``size``'s frame results and flows (each dump checked once:
    :func:`~ligwf.analysis.frames.checks.shared_checks`)."""
    tasks, flow_of = plan.share(rank, size)
    share = Share()
    with shared_checks():
        share.flows, share.notes = flow_cases(flow_of, plan.settings.steady_after,
                                              plan.settings.field_kernel, plan.strip)
        analyses: dict[int, GranuleAnalysis] = {}   # one per case: held windows share reads
        for fi, ff in tasks:
            f = plan.facts[fi]
            if fi not in analyses:
                analyses[fi] = GranuleAnalysis(
                    f, plan.settings, plan.options.implementation,
                    outputs.case_dir(f.case_id) if plan.options.write_vtu else None,
                    plan.options.louvain)
            share.results.append(analyse_frame(analyses[fi], ff))
    return share


def finish(plan: AnalysisShares, outputs: OutputSet, shares: list[Share]) -> dict:
    """Merge the shares (any split: the same outputs) and write the outputs as one set."""
    results = [r for s in shares for r in s.results]
    by_case = {k: v for s in shares for k, v in s.flows.items()}
    notes = {k: v for s in shares for k, v in s.notes.items()}
    order = [c.case_id for c in plan.usable]
    flows = flow_record({k: by_case[k] for k in order if k in by_case},
                        {k: notes[k] for k in order if k in notes},
                        plan.settings.steady_after, list(plan.unusable))
    return write_outputs(plan.study, outputs, plan.facts, list(plan.skipped_cases), results,
                         plan.settings, plan.options, plan.absent, flows)


def analyse(run_dir: Path, out_dir: Path | None = None, options: AnalysisOptions = AnalysisOptions(),
            comm=None) -> dict | None:
    """Analyse a study (or one case) folder; on rank 0 write the outputs and return the
    analysis record (other ranks return None). ``comm``: an mpi4py communicator, by
    default COMM_WORLD when running under mpirun with several ranks. NothingAnalysed
    (outputs untouched) when no frame could be analysed."""
    plan = plan_analysis(run_dir, options)
    out_dir = Path(out_dir) if out_dir is not None else plan.study.analysis_dir
    comm = mpi_comm() if comm is None else comm
    rank, size = (comm.Get_rank(), comm.Get_size()) if comm is not None else (0, 1)
    token = new_token() if comm is None else comm.bcast(new_token() if rank == 0 else None)
    outputs = OutputSet(out_dir, token)
    try:
        mine = compute_share(plan, outputs, rank, size)
    except BaseException:
        outputs.discard()
        raise
    if comm is not None:
        shares = comm.gather(mine, root=0)
        if rank != 0:
            comm.barrier()
            return None
    else:
        shares = [mine]
    try:
        return finish(plan, outputs, shares)
    except BaseException:
        outputs.discard()
        raise
    finally:
        if comm is not None:
            comm.barrier()


def analyse_part(run_dir: Path, token: str, index: int, count: int, out_dir: Path | None = None,
                 options: AnalysisOptions = AnalysisOptions()) -> Path:
    """Array task ``index`` of ``count``: compute its share and write it as one partial
    output (its ``.vtu`` frames into the staging folder of ``token``); returns the part's
    path. The merge (:func:`merge_parts`) writes the outputs."""
    plan = plan_analysis(run_dir, options)
    out_dir = Path(out_dir) if out_dir is not None else plan.study.analysis_dir
    share = compute_share(plan, OutputSet(out_dir, check_token(token)), index, count)
    return write_part(out_dir, token, index, count, plan.fingerprint(), share)


def merge_parts(run_dir: Path, token: str, count: int, out_dir: Path | None = None,
                options: AnalysisOptions = AnalysisOptions(), rerun: str = "") -> dict:
    """Merge the ``count`` parts of ``token`` into the outputs (the same bytes as one local
    run); AnalysisIncomplete (outputs, parts and staged frames kept) when a part is
    missing or was computed for another plan. ``rerun``: the command that re-runs task
    ``{index}``, for the message."""
    plan = plan_analysis(run_dir, options)
    out_dir = Path(out_dir) if out_dir is not None else plan.study.analysis_dir
    shares = read_parts(out_dir, token, count, plan.fingerprint(),
                        rerun or f"ligwf analyse {plan.study.path} --part {{index}}/{count} "
                                 f"--token {token}")
    outputs = OutputSet(out_dir, token)
    record = finish(plan, outputs, shares)
    drop_parts(out_dir, token)
    return record


def analyse_frame(ana: GranuleAnalysis, ff: FrameFiles) -> FrameResult:
    """The granules of one frame; a frame the analysis fails on for any reason is a
    skipped frame with that reason (one bad frame never blocks the others)."""
    f = ana.case
    try:
        return ana.frame(ff)
    except (ConfigError, MemoryError, KeyboardInterrupt):
        raise
    except Exception as exc:   # a frame that passed its checks and still breaks the analysis
        return FrameResult(f.case_id, ff.step, ff.step * f.dt,
                           error=f"{ff.particles}: analysis failed on this frame "
                                 f"({type(exc).__name__}: {exc})")


def window_reason(f: RunFacts, results, settings: AnalysisSettings) -> str | None:
    """Why a case has no granules when from every one of its frames the hold window ran
    past the run's end (``granules: held`` on a run shorter than ``hold_time``): a setting,
    not a fault, so the case keeps its flow metrics and the record says why and what to
    change. None when any frame of the case had another fate."""
    mine = [r for r in results if r.case_id == f.case_id]
    if not mine or any(r.kind != "window" for r in mine):
        return None
    return (f"from each of its {len(mine)} frame(s) the hold window (analysis.hold_time = "
            f"{settings.hold_time:g} s, granules: held) runs past the last frame; shorten "
            "analysis.hold_time or lengthen process.run_time (ligwf check warns of this "
            "before a run)")


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
    unanalysed = [(f, window_reason(f, results, settings)) for f in facts if f not in analysed]
    absent = list(absent) + [{"case_id": f.case_id, "reason": why}
                             for f, why in unanalysed if why is not None]
    skipped_cases = skipped_cases + [
        {"case_id": f.case_id, "reason": f"no analysable frame ({f.plan.expected} expected; "
         "see the skipped frames)"} for f, why in unanalysed if why is None]
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
        AnalysisRecord.commit(outputs, record,
                              obsolete=GRANULE_OUTPUTS + field_outputs(outputs.out_dir))
        return record
    cases = [f.case for f in analysed]
    steady_from = {c.case_id: flows.cases[c.case_id].steady_from_step for c in cases}
    stage_flow(outputs, flows)
    steady = stage_granules(outputs, tables, analysed, cases, steady_from, settings,
                            options.implementation, options.write_vtu, controls=True)
    steady_frames = steady.groupby("case_id")["step"].nunique() if len(steady) else {}
    plans: dict[str, ExpectedFrames] = {f.case_id: f.plan for f in analysed}
    record = {
        **base,
        "cases": [{"case_id": c.case_id, "cg": c.cg, "rule": c.rule, "replica": c.replica,
                   "frames": plans[c.case_id].expected,
                   "analysed": frame_index.get(c.case_id, 0),
                   "dump_record": plans[c.case_id].record is not None,
                   "steady_from_step": steady_from[c.case_id],
                   "steady_frames": int(steady_frames.get(c.case_id, 0))} for c in cases],
    }
    # e.g. no twins now: no controls.csv; a case no longer measured: no fields_<case>.vti
    AnalysisRecord.commit(outputs, record,
                          obsolete=GRANULE_OUTPUTS + field_outputs(outputs.out_dir))
    return record


def field_outputs(out_dir: Path) -> tuple[str, ...]:
    """The field files an earlier analysis left in ``out_dir`` (the archive and every
    case's ParaView image): replaced by this analysis' or dropped with it, so no image of
    a case the study no longer measures outlives it."""
    names = [layout.FIELDS_DATA]
    if Path(out_dir).is_dir():
        prefix, suffix = layout.field_image("\0").split("\0")
        names += sorted(p.name for p in Path(out_dir).iterdir()
                        if p.is_file() and p.name.startswith(prefix) and p.name.endswith(suffix))
    return tuple(names)


def stage_flow(outputs: OutputSet, flows: FlowRecord) -> None:
    """Stage the flow table and the flow record (:mod:`ligwf.analysis.flow.stage`)."""
    outputs.write(layout.FLOW_TABLE, flow_table(flows).to_csv(index=False).encode())
    outputs.write(layout.FLOW_PROFILES, flows.to_text().encode())
    for name, data in field_files(flows).items():   # the cross-section fields
        outputs.write(name, data)
