"""Whole-run analysis: every usable case, every frame -> granule tables, GSD, ParaView series.

Life cycle after MDAnalysis: :class:`GranuleAnalysis` takes its parameters in the
constructor; :meth:`GranuleAnalysis.run` calls ``_prepare``, ``_single_frame`` for each
frame it is given and ``_conclude``, and fills ``results``. Because a frame depends on
nothing but its own two dump files, the MPI runner (:func:`analyse`) only deals
(case, frame) tasks round-robin to ranks, gathers the per-frame results on rank 0 and
lets rank 0 alone sort them and write the outputs: the files are the same whatever the
number of ranks (each rank writes the per-frame ``.vtu`` files of its own frames).

Cases are used only when the study says they are usable (manifest ``done`` for the scene
the folder holds, :meth:`ligwf.study.case.CaseFolder.why_not_usable`); others are skipped
and listed with the reason. A frame whose dump cannot be read
(:class:`~ligwf.errors.DumpReadError`) is skipped and listed, never analysed. The science
settings (bond criterion, GSD binning and bootstrap, steady window) come from the study
(:class:`~ligwf.study.settings.AnalysisSettings`), so every path that analyses a study
computes the same numbers. Granules are identified in every frame; the GSD uses the
frames of each case's steady window only (the flow stage uses the same window).

Outputs (``OUT`` defaults to the study's analysis folder; names in
:mod:`ligwf.study.layout`):

* granule table (parquet): one row per granule per frame (case_id, cg, rule, replica,
  frame, step, time, granule, members, volume, primary_volume, com_x/y/z, first_id,
  percolating: the granule closes a cycle around the periodic axis);
* frame table: per frame: particles, contacts, bonds, granules, largest granule share
  and whether the largest granule percolates (wraps around the periodic axis);
* GSD and GSD summary tables: see :mod:`ligwf.analysis.gsd_tables`;
* ``<case_id>/granules.pvd`` + ``granules_<step>.vtu``: particles with a ``granule`` array;
* the analysis record (JSON): settings, analysed and skipped cases with their steady
  window, skipped frames with reasons.
"""

from __future__ import annotations

import io
import os
import tempfile
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.dumps import FrameFiles, ParticleFrame, discover_frames, read_contacts, read_particles
from ligwf.analysis.granules import AXES, BondCriterion, Liquid, granule_table, identify, louvain_labels
from ligwf.analysis.gsd import GsdSettings
from ligwf.analysis.gsd_tables import gsd_tables
from ligwf.errors import ConfigError, DumpReadError
from ligwf.fsio import atomic_write_bytes, atomic_write_json, atomic_write_text
from ligwf.study import layout
from ligwf.study.case import CaseFolder
from ligwf.study.settings import AnalysisSettings
from ligwf.study.study import Study


def case_liquid(case: CaseFolder) -> Liquid:
    """The liquid-bridge law the engine applied in the case."""
    return Liquid.from_scaled(case.scaled)


def periodic_axis(case: CaseFolder) -> int | None:
    """0, 1, 2 for a periodic drum axis x, y, z; None for a closed drum."""
    return AXES.index(case.scaled.axis) if case.scaled.periodic else None


@dataclass
class FrameResult:
    """Outcome of one frame: its granule table, or why it was skipped."""

    case_id: str
    step: int
    time: float
    table: pd.DataFrame | None = None
    particles: int = 0
    contacts: int = 0
    bonds: int = 0
    error: str | None = None
    vtu: str | None = None      # file name in the case's output folder


@dataclass
class GranuleAnalysis:
    """Granules of every frame of one case (MDAnalysis-style life cycle).

    ``implementation`` is ``"fast"`` (numba-compiled union-find) or ``"reference"`` (networkx BFS).
    ``vtu_dir`` set: write ``granules_<step>.vtu`` per frame there (ParaView series).
    ``louvain``: also store Louvain community ids per particle in the ``.vtu``.
    """

    case: CaseFolder
    criterion: BondCriterion = BondCriterion()
    implementation: str = "fast"
    vtu_dir: Path | None = None
    louvain: bool = False
    results: list[FrameResult] = field(default_factory=list)

    def run(self, frames: list[FrameFiles] | None = None) -> "GranuleAnalysis":
        """Analyse ``frames`` (default: every frame of the case) and fill ``results``."""
        frames = discover_frames(self.case.path) if frames is None else frames
        self._prepare()
        for ff in frames:
            self.results.append(self._single_frame(ff))
        self._conclude()
        return self

    def _prepare(self) -> None:
        if self.implementation not in ("fast", "reference"):
            raise ConfigError(f"implementation {self.implementation!r}: use fast or reference")
        self.results = []
        self._liquid = case_liquid(self.case)
        self._axis = periodic_axis(self.case)

    def _single_frame(self, ff: FrameFiles) -> FrameResult:
        c, dt = self.case, self.case.scaled.dt
        # the drum axis spans [0, L] (the periodic box, see templates/drum.in.j2)
        box_lo, box_length = 0.0, c.scaled.drum_length
        res = FrameResult(c.case_id, ff.step, ff.step * dt)
        try:
            if ff.contacts is None:
                raise DumpReadError(f"{ff.particles}: no contact dump for step {ff.step} "
                                    "(was the case rendered with analysis.granules: true?)")
            particles = read_particles(ff.particles, ff.step, dt)
            contacts = read_contacts(ff.contacts, ff.step)
            ident = identify(particles, contacts, self._liquid, self.criterion, self._axis,
                             box_length, self.implementation, need_force=self.louvain)
        except DumpReadError as exc:
            res.error = str(exc)
            return res
        labels = ident.labels
        table = granule_table(particles, labels, c.cg, ident.unwrapped_axis, self._axis,
                              box_lo, box_length, ident.percolating)
        res.table, res.particles, res.contacts = table, len(particles), len(contacts)
        res.bonds = len(ident.i)
        if self.vtu_dir is not None:
            extra = ({"louvain": louvain_labels(len(particles), ident.i, ident.j, ident.force)}
                     if self.louvain else {})
            res.vtu = f"granules_{ff.step}.vtu"
            write_particle_vtu(Path(self.vtu_dir) / res.vtu, particles, labels,
                               table["members"].to_numpy()[labels], extra)
        return res

    def _conclude(self) -> None:
        self.results.sort(key=lambda r: r.step)


def write_particle_vtu(path: Path, particles: ParticleFrame, labels: np.ndarray,
                       granule_members: np.ndarray, extra: dict[str, np.ndarray] | None = None) -> None:
    """Particles as VTU vertices (meshio, binary) with ``granule`` ids, written atomically."""
    import meshio

    n = len(particles)
    point_data = {"id": particles.ids.astype(np.int64), "type": particles.types,
                  "v": particles.velocities, "radius": particles.radii,
                  "granule": labels.astype(np.int64),
                  "granule_members": granule_members.astype(np.int64)}
    if particles.liquid_content is not None:
        point_data["f_surfaceLiquidContent"] = particles.liquid_content
    point_data.update(extra or {})
    mesh = meshio.Mesh(particles.positions, [("vertex", np.arange(n).reshape(-1, 1))],
                       point_data=point_data)
    with tempfile.TemporaryDirectory() as tmp:
        tmp_path = Path(tmp) / "frame.vtu"
        meshio.write(tmp_path, mesh, file_format="vtu", binary=True, compression=None)
        atomic_write_bytes(path, tmp_path.read_bytes())


def pvd_text(entries: list[tuple[float, str]]) -> str:
    """A ParaView collection (.pvd) of (time s, file name) entries."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    lines += [f'    <DataSet timestep="{t!r}" group="" part="0" file="{name}"/>'
              for t, name in entries]
    lines += ["  </Collection>", "</VTKFile>", ""]
    return "\n".join(lines)


# --------------------------------------------------------------------------- runner

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


def bond_criterion(s: AnalysisSettings) -> BondCriterion:
    """The bond criterion of the settings."""
    return BondCriterion(s.min_bridge_force, s.max_velocity_angle)


def gsd_settings(s: AnalysisSettings) -> GsdSettings:
    """The GSD settings of the settings."""
    return GsdSettings(bins_per_decade=s.bins_per_decade, min_particles=s.min_particles,
                       n_boot=s.bootstrap, seed=s.seed)


def analyse(run_dir: Path, out_dir: Path | None = None, options: AnalysisOptions = AnalysisOptions(),
            comm=None) -> dict | None:
    """Analyse a study (or one case) folder; on rank 0 write the outputs and return the
    analysis record (other ranks return None). ``comm``: an mpi4py communicator, by
    default COMM_WORLD when running under mpirun with several ranks."""
    study = Study.open(run_dir)
    out_dir = Path(out_dir) if out_dir is not None else study.analysis_dir
    settings = options.settings or study.analysis
    comm = _mpi_comm() if comm is None else comm
    rank, size = (comm.Get_rank(), comm.Get_size()) if comm is not None else (0, 1)

    cases, skipped_cases = study.usable_cases(options.require_manifest)
    frames = {c.case_id: discover_frames(c.path) for c in cases}
    tasks = [(ci, k) for ci, c in enumerate(cases) for k in range(len(frames[c.case_id]))]
    mine: list[FrameResult] = []
    for ci, k in tasks[rank::size]:
        c = cases[ci]
        ana = GranuleAnalysis(c, bond_criterion(settings), options.implementation,
                              out_dir / c.case_id if options.write_vtu else None, options.louvain)
        mine.extend(ana.run([frames[c.case_id][k]]).results)
    if comm is not None:
        gathered = comm.gather(mine, root=0)
        if rank != 0:
            comm.barrier()
            return None
        results = [r for part in gathered for r in part]
    else:
        results = mine
    try:
        return _write_outputs(study, out_dir, cases, skipped_cases, frames, results, settings,
                              options)
    finally:
        if comm is not None:
            comm.barrier()


def _tables(cases: list[CaseFolder], results: list[FrameResult]):
    """(granule table, frame rows, skipped frames, analysed frames per case) of results
    in case and step order."""
    by_case = {c.case_id: c for c in cases}
    tables, frame_rows, skipped_frames = [], [], []
    frame_index: dict[str, int] = {}
    for r in results:
        c = by_case[r.case_id]
        if r.error is not None:
            skipped_frames.append({"case_id": r.case_id, "step": r.step, "reason": r.error})
            frame_rows.append({"case_id": r.case_id, "step": r.step, "time": r.time,
                               "status": "skipped", "reason": r.error})
            continue
        k = frame_index.get(r.case_id, 0)
        frame_index[r.case_id] = k + 1
        t = r.table
        tables.append(t.assign(case_id=r.case_id, cg=c.cg, rule=c.rule, replica=c.replica,
                               frame=k, step=r.step, time=r.time))
        vol = t["volume"].to_numpy()
        frame_rows.append({"case_id": r.case_id, "step": r.step, "time": r.time, "status": "ok",
                           "reason": "", "particles": r.particles, "contacts": r.contacts,
                           "bonds": r.bonds, "granules": len(t),
                           "largest_fraction": float(vol.max() / vol.sum()),
                           "largest_percolates": bool(t["percolating"].to_numpy()[vol.argmax()])})
    cols = ["case_id", "cg", "rule", "replica", "frame", "step", "time", "granule", "members",
            "volume", "primary_volume", "com_x", "com_y", "com_z", "first_id", "percolating"]
    granules = (pd.concat(tables, ignore_index=True)[cols] if tables
                else pd.DataFrame({c: pd.Series(dtype=float) for c in cols}))
    return granules, frame_rows, skipped_frames, frame_index


def _write_outputs(study: Study, out_dir: Path, cases, skipped_cases, frames, results,
                   settings: AnalysisSettings, options: AnalysisOptions) -> dict:
    order = {c.case_id: ci for ci, c in enumerate(cases)}
    results = sorted(results, key=lambda r: (order[r.case_id], r.step))   # whatever the ranks
    granules, frame_rows, skipped_frames, frame_index = _tables(cases, results)
    steady_from = {c.case_id: c.steady_start_step(settings.steady_after) for c in cases}
    steady = granules[granules["step"] >= granules["case_id"].map(steady_from).astype(float)]
    gsd_df, summary = gsd_tables(steady, cases, gsd_settings(settings))

    out_dir.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    granules.to_parquet(buf, index=False)
    atomic_write_bytes(out_dir / layout.GRANULES_TABLE, buf.getvalue())
    atomic_write_text(out_dir / layout.FRAMES_TABLE, pd.DataFrame(frame_rows).to_csv(index=False))
    atomic_write_text(out_dir / layout.GSD_TABLE, gsd_df.to_csv(index=False))
    atomic_write_text(out_dir / layout.GSD_SUMMARY_TABLE, summary.to_csv(index=False))
    if options.write_vtu:
        for c in cases:
            entries = [(r.time, r.vtu) for r in results if r.case_id == c.case_id and r.vtu]
            if entries:
                atomic_write_text(out_dir / c.case_id / "granules.pvd", pvd_text(entries))
    steady_frames = steady.groupby("case_id")["step"].nunique() if len(steady) else {}
    record = {
        "run_dir": str(study.path),
        "settings": settings.model_dump(mode="json"),
        "criterion": asdict(bond_criterion(settings)),
        "gsd": asdict(gsd_settings(settings)),
        "options": {"implementation": options.implementation, "louvain": options.louvain,
                    "write_vtu": options.write_vtu,
                    "require_manifest": options.require_manifest},
        "cases": [{"case_id": c.case_id, "cg": c.cg, "rule": c.rule, "replica": c.replica,
                   "frames": len(frames[c.case_id]),
                   "analysed": frame_index.get(c.case_id, 0),
                   "steady_from_step": steady_from[c.case_id],
                   "steady_frames": int(steady_frames.get(c.case_id, 0))} for c in cases],
        "skipped_cases": skipped_cases,
        "skipped_frames": skipped_frames,
    }
    atomic_write_json(out_dir / layout.ANALYSIS_RECORD, record)
    return record
