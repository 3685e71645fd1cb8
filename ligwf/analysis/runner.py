"""Whole-run analysis: every usable case, every frame -> granule tables, GSD, ParaView series.

Life cycle after MDAnalysis: :class:`GranuleAnalysis` takes its parameters in the
constructor; :meth:`GranuleAnalysis.run` calls ``_prepare``, ``_single_frame`` for each
frame it is given and ``_conclude``, and fills ``results``. Because a frame depends on
nothing but its own two dump files, the MPI runner (:func:`analyse`) only deals
(case, frame) tasks round-robin to ranks, gathers the per-frame results on rank 0 and
lets rank 0 alone sort them and write the outputs: the files are the same whatever the
number of ranks (each rank writes the per-frame ``.vtu`` files of its own frames).

Cases are used only when their ``manifest.json`` says ``done`` and its scene hash matches
``scene.json``; others are skipped and listed with the reason. A frame whose dump cannot
be read (:class:`~ligwf.errors.DumpReadError`) is skipped and listed, never analysed.

Outputs (``OUT`` defaults to ``RUN_DIR/analysis``):

* ``granules.parquet``: one row per granule per frame (case_id, cg, rule, replica,
  frame, step, time, granule, members, volume, primary_volume, com_x/y/z, first_id,
  percolating: the granule closes a cycle around the periodic axis);
* ``frames.csv``: per frame: particles, contacts, bonds, granules, largest granule share
  and whether the largest granule percolates (wraps around the periodic axis);
* ``gsd.csv``: per condition (group, CG level, rule; replicas pooled) and bin: number- and
  volume-weighted fractions with bootstrap bands and, for CG > 1, the CG1 reference, the
  per-bin relative error (with band) and whether the bin lies below the size limit;
* ``gsd_summary.csv``: per condition: d10/d50/d90, size limit, error below/above it;
* ``<case_id>/granules.pvd`` + ``granules_<step>.vtu``: particles with a ``granule`` array;
* ``analysis.json``: settings, analysed and skipped cases, skipped frames with reasons.
"""

from __future__ import annotations

import io
import json
import math
import os
import tempfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ligwf.analysis import gsd as gsdmod
from ligwf.analysis.dumps import FrameFiles, ParticleFrame, discover_frames, read_contacts, read_particles
from ligwf.errors import ConfigError, DumpReadError
from ligwf.fsio import atomic_write_bytes, atomic_write_json, atomic_write_text
from ligwf.engine.health import DONE
from ligwf.engine.manifest import MANIFEST_FILE
from ligwf.analysis.granules import AXES, BondCriterion, Liquid, granule_table, identify, louvain_labels



@dataclass(frozen=True)
class CaseInfo:
    """What the analysis needs to know about one case folder (from ``scene.json``)."""

    case_id: str
    case_dir: Path
    cg: float
    rule: str
    replica: int
    group: str                 # JSON of the swept scene values: cases comparable with CG1
    dt: float                  # s
    liquid: Liquid
    periodic_axis: int | None  # 0, 1, 2 or None
    box_lo: float              # m, lower bound of the periodic axis
    box_length: float          # m

    @classmethod
    def from_folder(cls, case_dir: Path) -> "CaseInfo":
        case_dir = Path(case_dir)
        try:
            rec = json.loads((case_dir / "scene.json").read_text())
            s = rec["scaled"]
            return cls(
                case_id=rec["case_id"], case_dir=case_dir, cg=float(rec["cg"]), rule=s["rule"],
                replica=int(rec.get("replica", 0)),
                group=json.dumps(rec.get("varied", {}), sort_keys=True),
                dt=float(s["dt"]), liquid=Liquid.from_scaled(s),
                periodic_axis=AXES.index(s["axis"]) if s.get("periodic") else None,
                # the drum axis spans [0, L] (the periodic box, see templates/drum.in.j2)
                box_lo=0.0, box_length=float(s["drum_length"]))
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise ConfigError(f"{case_dir}: scene.json missing or invalid ({exc})") from None


def manifest_problem(case_dir: Path) -> str | None:
    """Why a case may not be analysed (None when its manifest says done and matches)."""
    path = Path(case_dir) / MANIFEST_FILE
    if not path.is_file():
        return "no manifest.json (the case was not run by `ligwf run`)"
    try:
        m = json.loads(path.read_text())
        scene_hash = json.loads((Path(case_dir) / "scene.json").read_text())["scene_hash"]
    except (OSError, ValueError, KeyError) as exc:
        return f"unreadable manifest.json or scene.json ({exc})"
    if m.get("status") != DONE:
        reason = m.get("reason") or ""
        return f"manifest status {m.get('status')!r}" + (f": {reason}" if reason else "")
    if m.get("scene_hash") != scene_hash:
        return "manifest scene_hash differs from scene.json (re-rendered since the run)"
    return None


def discover_cases(run_dir: Path, require_manifest: bool = True) -> tuple[list[CaseInfo], list[dict]]:
    """Usable cases of a study folder (``study.json``) or of one case folder, in study
    order, and the skipped ones as ``{"case_id", "reason"}``."""
    run_dir = Path(run_dir)
    if (run_dir / "study.json").is_file():
        study = json.loads((run_dir / "study.json").read_text())
        dirs = [run_dir / c["case_id"] for c in study["cases"]]
    elif (run_dir / "scene.json").is_file():
        dirs = [run_dir]
    else:
        raise ConfigError(f"{run_dir}: neither a study folder (study.json) nor a case folder "
                          "(scene.json)")
    cases, skipped = [], []
    for d in dirs:
        problem = manifest_problem(d) if require_manifest else None
        if problem is None and not (d / "scene.json").is_file():
            problem = "case folder or scene.json missing"
        if problem:
            skipped.append({"case_id": d.name, "reason": problem})
        else:
            cases.append(CaseInfo.from_folder(d))
    return cases, skipped


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

    case: CaseInfo
    criterion: BondCriterion = BondCriterion()
    implementation: str = "fast"
    vtu_dir: Path | None = None
    louvain: bool = False
    results: list[FrameResult] = field(default_factory=list)

    def run(self, frames: list[FrameFiles] | None = None) -> "GranuleAnalysis":
        """Analyse ``frames`` (default: every frame of the case) and fill ``results``."""
        frames = discover_frames(self.case.case_dir) if frames is None else frames
        self._prepare()
        for ff in frames:
            self.results.append(self._single_frame(ff))
        self._conclude()
        return self

    def _prepare(self) -> None:
        if self.implementation not in ("fast", "reference"):
            raise ConfigError(f"implementation {self.implementation!r}: use fast or reference")
        self.results = []

    def _single_frame(self, ff: FrameFiles) -> FrameResult:
        c = self.case
        res = FrameResult(c.case_id, ff.step, ff.step * c.dt)
        try:
            if ff.contacts is None:
                raise DumpReadError(f"{ff.particles}: no contact dump for step {ff.step} "
                                    "(was the case rendered with analysis.granules: true?)")
            particles = read_particles(ff.particles, ff.step, c.dt)
            contacts = read_contacts(ff.contacts, ff.step)
            ident = identify(particles, contacts, c.liquid, self.criterion, c.periodic_axis,
                             c.box_length, self.implementation, need_force=self.louvain)
        except DumpReadError as exc:
            res.error = str(exc)
            return res
        labels = ident.labels
        table = granule_table(particles, labels, c.cg, ident.unwrapped_axis, c.periodic_axis,
                              c.box_lo, c.box_length, ident.percolating)
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


# --------------------------------------------------------------------------- GSD stage

@dataclass(frozen=True)
class Condition:
    """Cases pooled for a GSD: same group, CG level and rule (replicas together)."""

    group: str
    cg: float
    rule: str

    @property
    def name(self) -> str:
        tag = f"cg{self.cg:g}" + ("" if self.cg == 1 else f"-{self.rule}")
        return tag if self.group in ("{}", "") else f"{tag} {self.group}"


def gsd_tables(granules: pd.DataFrame, cases: list[CaseInfo], settings: gsdmod.GsdSettings,
               discard_frames: int = 0) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``gsd.csv`` and ``gsd_summary.csv`` contents from the granule table of all frames."""
    if granules.empty:
        return pd.DataFrame(), pd.DataFrame()
    g = granules[granules["frame"] >= discard_frames]
    edges = gsdmod.log_edges(float(g["primary_volume"].min()), float(g["primary_volume"].max()),
                             settings.bins_per_decade)
    rng = np.random.default_rng(settings.seed)
    replica_of = {c.case_id: c.replica for c in cases}
    cond_of = {c.case_id: Condition(c.group, c.cg, c.rule) for c in cases}
    per_cond: dict[Condition, dict[str, Any]] = {}
    for (case_id, step), fr in g.groupby(["case_id", "step"], sort=True):
        cond = cond_of[case_id]
        v = fr["primary_volume"].to_numpy()
        num, vol = gsdmod.histogram(v, edges)
        d = per_cond.setdefault(cond, {"num": [], "vol": [], "rep": [], "pct": [], "largest": [],
                                       "ppv": []})
        d["num"].append(num)
        d["vol"].append(vol)
        d["rep"].append(replica_of[case_id])
        d["pct"].append(gsdmod.percentile_diameters(v))
        d["largest"].append(v.max() / v.sum())
        d["ppv"].append(v.sum() / fr["members"].sum())   # mean particle primary volume
    rows, summary = [], []
    conds = sorted(per_cond, key=lambda c: (c.group, c.cg, c.rule))
    ref_of = {c.group: c for c in conds if c.cg == 1}
    lo_hi = settings.confidence
    for cond in conds:
        d = per_cond[cond]
        rep = np.asarray(d["rep"])
        num, vol = np.asarray(d["num"]), np.asarray(d["vol"])
        scalars = np.column_stack([np.asarray(d["pct"]), np.asarray(d["largest"])])
        num_lo, num_hi = gsdmod.band(gsdmod.bootstrap_means(num, rep, settings.n_boot, rng), lo_hi)
        vol_draws = gsdmod.bootstrap_means(vol, rep, settings.n_boot, rng)
        vol_lo, vol_hi = gsdmod.band(vol_draws, lo_hi)
        sc_lo, sc_hi = gsdmod.band(gsdmod.bootstrap_means(scalars, rep, settings.n_boot, rng), lo_hi)
        mean_vol = vol.mean(axis=0)
        limit = gsdmod.size_limit(float(np.mean(d["ppv"])), settings.min_particles)
        below = gsdmod.below_limit(edges, limit)
        ref = ref_of.get(cond.group) if cond.cg != 1 else None
        nan = np.full(len(edges) - 1, np.nan)
        rel = rel_lo = rel_hi = ref_vol = nan
        err = {"error_below": math.nan, "error_below_lo": math.nan, "error_below_hi": math.nan,
               "error_above": math.nan, "error_above_lo": math.nan, "error_above_hi": math.nan}
        if ref is not None:
            r = per_cond[ref]
            ref_vol = np.asarray(r["vol"]).mean(axis=0)
            ref_draws = gsdmod.bootstrap_means(np.asarray(r["vol"]), np.asarray(r["rep"]),
                                               settings.n_boot, rng)
            rel = gsdmod.relative_error(mean_vol, ref_vol)
            rel_lo, rel_hi = gsdmod.band(gsdmod.relative_error(vol_draws, ref_draws), lo_hi)
            eb, ea = gsdmod.side_errors(mean_vol, ref_vol, below)
            eb_d, ea_d = gsdmod.side_errors(vol_draws, ref_draws, below)
            (eb_lo, ea_lo), (eb_hi, ea_hi) = (gsdmod.band(np.column_stack([eb_d, ea_d]), lo_hi))
            err = {"error_below": float(eb), "error_below_lo": float(eb_lo),
                   "error_below_hi": float(eb_hi), "error_above": float(ea),
                   "error_above_lo": float(ea_lo), "error_above_hi": float(ea_hi)}
        n_reps = len(np.unique(rep))
        for b in range(len(edges) - 1):
            rows.append({"condition": cond.name, "group": cond.group, "cg": cond.cg,
                         "rule": cond.rule, "replicas": n_reps, "frames": len(rep), "bin": b,
                         "v_lo": edges[b], "v_hi": edges[b + 1],
                         "v_mid": math.sqrt(edges[b] * edges[b + 1]),
                         "number_fraction": num.mean(axis=0)[b], "number_lo": num_lo[b],
                         "number_hi": num_hi[b], "volume_fraction": mean_vol[b],
                         "volume_lo": vol_lo[b], "volume_hi": vol_hi[b],
                         "ref_volume_fraction": ref_vol[b], "rel_error": rel[b],
                         "rel_error_lo": rel_lo[b], "rel_error_hi": rel_hi[b],
                         "below_limit": bool(below[b])})
        means = scalars.mean(axis=0)
        summary.append({"condition": cond.name, "group": cond.group, "cg": cond.cg,
                        "rule": cond.rule, "replicas": n_reps, "frames": len(rep),
                        "d10": means[0], "d10_lo": sc_lo[0], "d10_hi": sc_hi[0],
                        "d50": means[1], "d50_lo": sc_lo[1], "d50_hi": sc_hi[1],
                        "d90": means[2], "d90_lo": sc_lo[2], "d90_hi": sc_hi[2],
                        "largest_fraction": means[3], "largest_fraction_lo": sc_lo[3],
                        "largest_fraction_hi": sc_hi[3],
                        "size_limit": limit, "min_particles": settings.min_particles,
                        "reference": ref.name if ref is not None else "", **err})
    return pd.DataFrame(rows), pd.DataFrame(summary)


# --------------------------------------------------------------------------- runner

def _mpi_comm():
    """MPI.COMM_WORLD when started under mpirun with more than one rank, else None."""
    if not any(k in os.environ for k in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK")):
        return None
    from mpi4py import MPI

    return MPI.COMM_WORLD if MPI.COMM_WORLD.Get_size() > 1 else None


@dataclass(frozen=True)
class AnalysisOptions:
    """Settings of ``ligwf analyse`` (recorded in ``analysis.json``)."""

    criterion: BondCriterion = BondCriterion()
    gsd: gsdmod.GsdSettings = gsdmod.GsdSettings()
    implementation: str = "fast"
    discard_frames: int = 0          # first frames of each case left out of the GSD
    write_vtu: bool = True
    louvain: bool = False
    require_manifest: bool = True


def analyse(run_dir: Path, out_dir: Path | None = None, options: AnalysisOptions = AnalysisOptions(),
            comm=None) -> dict | None:
    """Analyse a study (or one case) folder; on rank 0 write the outputs and return the
    ``analysis.json`` record (other ranks return None). ``comm``: an mpi4py communicator,
    by default COMM_WORLD when running under mpirun with several ranks."""
    run_dir = Path(run_dir)
    out_dir = Path(out_dir) if out_dir is not None else run_dir / "analysis"
    comm = _mpi_comm() if comm is None else comm
    rank, size = (comm.Get_rank(), comm.Get_size()) if comm is not None else (0, 1)

    cases, skipped_cases = discover_cases(run_dir, options.require_manifest)
    frames = {c.case_id: discover_frames(c.case_dir) for c in cases}
    tasks = [(ci, k) for ci, c in enumerate(cases) for k in range(len(frames[c.case_id]))]
    mine: list[FrameResult] = []
    for ci, k in tasks[rank::size]:
        c = cases[ci]
        ana = GranuleAnalysis(c, options.criterion, options.implementation,
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
        return _write_outputs(run_dir, out_dir, cases, skipped_cases, frames, results, options)
    finally:
        if comm is not None:
            comm.barrier()


def _write_outputs(run_dir, out_dir, cases, skipped_cases, frames, results, options) -> dict:
    order = {c.case_id: ci for ci, c in enumerate(cases)}
    results = sorted(results, key=lambda r: (order[r.case_id], r.step))
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
    gsd_df, summary = gsd_tables(granules, cases, options.gsd, options.discard_frames)

    out_dir.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    granules.to_parquet(buf, index=False)
    atomic_write_bytes(out_dir / "granules.parquet", buf.getvalue())
    atomic_write_text(out_dir / "frames.csv", pd.DataFrame(frame_rows).to_csv(index=False))
    atomic_write_text(out_dir / "gsd.csv", gsd_df.to_csv(index=False))
    atomic_write_text(out_dir / "gsd_summary.csv", summary.to_csv(index=False))
    if options.write_vtu:
        for c in cases:
            entries = [(r.time, r.vtu) for r in results if r.case_id == c.case_id and r.vtu]
            if entries:
                atomic_write_text(out_dir / c.case_id / "granules.pvd", pvd_text(entries))
    record = {
        "run_dir": str(run_dir),
        "options": {"criterion": asdict(options.criterion), "gsd": asdict(options.gsd),
                    "implementation": options.implementation,
                    "discard_frames": options.discard_frames, "louvain": options.louvain,
                    "require_manifest": options.require_manifest},
        "cases": [{"case_id": c.case_id, "cg": c.cg, "rule": c.rule, "replica": c.replica,
                   "frames": len(frames[c.case_id]),
                   "analysed": frame_index.get(c.case_id, 0)} for c in cases],
        "skipped_cases": skipped_cases,
        "skipped_frames": skipped_frames,
    }
    atomic_write_json(out_dir / "analysis.json", record)
    return record
