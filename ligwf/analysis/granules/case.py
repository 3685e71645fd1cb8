"""Granules of the frames of one run (MDAnalysis-style life cycle), and their ParaView files.

:class:`GranuleAnalysis` takes its parameters in the constructor; the frame loop is its
base class's (:class:`~ligwf.analysis.frames.loop.FrameAnalysis`): ``run`` calls
``_prepare``, ``_single_frame`` for each frame and ``_conclude`` and fills ``results``. What it needs to know about the run that wrote the frames is a
:class:`RunFacts`: for a ligwf case it comes from the case's scaled scene
(:meth:`RunFacts.of_case`), and the frames are also checked against the run (its dump
record, particle count and ids, radii, drum, contact geometry:
:mod:`ligwf.analysis.frames.checks`); for dumps ligwf did not write, the caller states
every fact (:mod:`ligwf.analysis.foreign`): nothing defaults silently.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.frames.dumps import (ContactFrame, FrameFiles, ParticleFrame,
                                         read_contacts, read_particles)
from ligwf.analysis.granules.persistent import Frame, bridge_keys, persistent_labels, presence_run
from ligwf.analysis.frames.checks import ExpectedFrames, check_contacts, check_particles, plan_frames
from ligwf.analysis.frames.loop import FrameAnalysis
from ligwf.analysis.granules.definitions import Motion, bond_criterion, identify_granules
from ligwf.analysis.granules.bonds import bonded_contacts, granule_table
from ligwf.analysis.granules.bridge_law import Liquid
from ligwf.analysis.granules.communities import louvain_labels
from ligwf.errors import ConfigError, DumpReadError
from ligwf.fsio import atomic_write_bytes
from ligwf.scene.axis import Axis
from ligwf.scene.settings import AnalysisSettings
from ligwf.study import layout
from ligwf.study.case import CaseFolder


@dataclass(frozen=True)
class RunFacts:
    """What the granule analysis must know about the run that wrote the frames."""

    case_id: str
    cg: float
    liquid: Liquid
    periodic_axis: Axis | None     # None: no periodic axis
    box_length: float              # m, periodic length (the box spans [0, L] on that axis)
    dt: float                      # s per step
    case: CaseFolder | None = None     # a ligwf case: frames checked against its run
    plan: ExpectedFrames | None = None      # ... and its dump record
    omega: float | None = None         # rad/s about +rotation_axis (None: unknown)
    rotation_axis: Axis = Axis.Y       # the drum axis through the origin

    def __post_init__(self) -> None:
        if self.periodic_axis is not None and not self.box_length > 0:
            raise ConfigError(f"{self.case_id}: a periodic axis needs the box length (> 0 m), "
                              f"got {self.box_length!r}; without it granules that wrap "
                              "around the axis would not be detected")
        if not self.dt > 0:
            raise ConfigError(f"{self.case_id}: the time step must be > 0 s, got {self.dt!r}")

    @classmethod
    def of_case(cls, case: CaseFolder, plan: ExpectedFrames | None = None) -> "RunFacts":
        """The facts of a ligwf case (the drum axis spans [0, L], see templates/drum.in.j2)."""
        s = case.scaled
        return cls(case.case_id, case.cg, case_liquid(case), s.drum.periodic_axis,
                   s.drum.length, s.numerics.dt, case, plan, float(s.drum.omega), s.drum.axis)

    @property
    def periodic_column(self) -> int | None:
        """Column of the periodic axis in a position (None: none), for the array kernels."""
        return None if self.periodic_axis is None else self.periodic_axis.index

    @property
    def motion(self) -> Motion:
        """The drum rotation and periodic axis the velocity frames need."""
        return Motion(self.rotation_axis, self.omega, self.periodic_axis, self.box_length)


def case_liquid(case: CaseFolder) -> Liquid:
    """The liquid-bridge law the engine applied in the case."""
    return Liquid.from_scaled(case.scaled)


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
    kind: str | None = None     # why there is no table: missing / unexpected (None: unreadable)


@dataclass
class GranuleAnalysis(FrameAnalysis):
    """Granules of every frame of one case (a :class:`~ligwf.analysis.frames.loop.FrameAnalysis`:
    :meth:`run` over a list of frames, or :meth:`frame` one at a time).

    ``case``: a :class:`~ligwf.study.case.CaseFolder` or the :class:`RunFacts` of a run.
    ``definition``: the study's analysis settings, whose granule definition is used
    (:mod:`ligwf.analysis.granules.definitions`).
    ``implementation`` is ``"fast"`` (compiled) or ``"reference"`` (numpy, networkx,
    leidenalg).
    ``vtu_dir`` set: write ``granules_<step>.vtu`` per frame there (ParaView series).
    ``louvain``: also store Louvain community ids per particle in the ``.vtu``.
    """

    case: CaseFolder | RunFacts
    definition: AnalysisSettings = AnalysisSettings()
    implementation: str = "fast"
    vtu_dir: Path | None = None
    louvain: bool = False
    results: list[FrameResult] = field(default_factory=list)

    def _prepare(self, frames: list[FrameFiles] | None) -> list[FrameFiles]:
        """The run's facts, and the frames to analyse: ``frames``, by default every frame
        the case's run should have left that is there
        (:func:`~ligwf.analysis.frames.checks.plan_frames`)."""
        if self.implementation not in ("fast", "reference"):
            raise ConfigError(f"implementation {self.implementation!r}: use fast or reference")
        self.results = []
        facts = self.case
        if isinstance(facts, CaseFolder):
            facts = RunFacts.of_case(facts, plan_frames(facts))
        self._facts = facts
        if frames is None:
            if facts.case is None:
                raise ConfigError(f"{facts.case_id}: pass the frames to analyse")
            frames = list(facts.plan.frames)
        if facts.plan is None:
            self._sequence = sorted(frames, key=lambda ff: ff.step)   # held windows of foreign dumps
        return list(frames)

    def _single_frame(self, ff: FrameFiles) -> FrameResult:
        f = self._facts
        res = FrameResult(f.case_id, ff.step, ff.step * f.dt)
        try:
            if ff.contacts is None:
                raise DumpReadError(f"{ff.particles}: no contact dump for step {ff.step} "
                                    "(was the case rendered with analysis.contact_dumps: true?)")
            particles, contacts = self._read(ff)
            if self.definition.granules == "held":
                ident = self._held(ff, particles, contacts)
            else:
                ident = identify_granules(particles, contacts, f.liquid, self.definition, f.cg,
                                          f.motion, self.implementation)
        except HoldWindowOpen as exc:
            res.error, res.kind = str(exc), "window"
            return res
        except (DumpReadError, ValueError) as exc:
            res.error = str(exc)
            return res
        labels = ident.labels
        # the periodic axis spans [0, L] (the box, see templates/drum.in.j2)
        table = granule_table(particles, labels, f.cg, ident.unwrapped_axis, f.periodic_column,
                              0.0, f.box_length, ident.percolating)
        res.table, res.particles, res.contacts = table, len(particles), len(contacts)
        res.bonds = len(ident.i)
        if self.vtu_dir is not None:
            extra = {}
            if self.louvain:
                bi, bj, bf = bonded_contacts(particles, contacts, f.liquid,
                                             bond_criterion(self.definition))
                extra["louvain"] = louvain_labels(len(particles), bi, bj, bf)
            res.vtu = layout.granule_frame(ff.step)
            write_particle_vtu(Path(self.vtu_dir) / res.vtu, particles, labels,
                               table["members"].to_numpy()[labels], extra)
        return res

    def _read(self, ff: FrameFiles) -> tuple[ParticleFrame, ContactFrame]:
        """One frame, read and checked against its run (record, particles, contacts)."""
        f = self._facts
        if ff.contacts is None:
            raise DumpReadError(f"{ff.particles}: no contact dump for step {ff.step} "
                                "(was the case rendered with analysis.contact_dumps: true?)")
        if f.plan is not None:
            f.plan.check_record(ff)
        particles = read_particles(ff.particles, ff.step, f.dt)
        contacts = read_contacts(ff.contacts, ff.step)
        if f.case is not None:
            check_particles(f.case, particles)
        check_contacts(particles, contacts, f.periodic_column, f.box_length)
        return particles, contacts

    def _held(self, ff: FrameFiles, particles: ParticleFrame, contacts: ContactFrame):
        """Granules of ``granules: held`` at ``ff``: the bridges present in every frame of
        [t, t + hold_time] (:func:`ligwf.analysis.granules.persistent.persistent_labels`); the frames
        after ``ff`` come from the run's frame plan (foreign dumps: the frames given to
        :meth:`run`), their bridge keys cached while the frames are analysed in order."""
        f = self._facts
        frames = list(f.plan.frames) if f.plan is not None else list(self._sequence)
        steps = [x.step for x in frames]
        k = steps.index(ff.step)
        interval = (steps[1] - steps[0]) * f.dt if len(steps) > 1 else float("inf")
        span = max(1, int(round(self.definition.hold_time / interval)))
        if k + span >= len(frames) or steps[k + span] - ff.step != span * (steps[1] - steps[0]):
            raise HoldWindowOpen(f"step {ff.step}: its hold window of "
                                 f"{self.definition.hold_time:g} s runs past the last frame "
                                 "(or over a missing one): no granules can be held through it")
        if not hasattr(self, "_keys"):
            self._keys: dict[int, np.ndarray] = {}
            self._runs: dict[int, np.ndarray] = {}
        for q in range(k, k + span + 1):
            step = steps[q]
            if step not in self._keys:
                p, c = (particles, contacts) if q == k else self._read(frames[q])
                if not np.array_equal(p.ids, particles.ids):
                    raise DumpReadError(f"{frames[q].particles}: not the particles of step "
                                        f"{ff.step} (a hold window needs the same particles)")
                keys = bridge_keys(Frame(p, c), f.liquid)
                before = steps[q - 1] if q > 0 else None      # cached: the count goes on
                self._runs[step] = presence_run(keys, self._keys.get(before),
                                                self._runs.get(before))
                self._keys[step] = keys
        for old in [s for s in self._keys if s < ff.step]:
            del self._keys[old], self._runs[old]
        last = steps[k + span]
        held = self._keys[last][self._runs[last] >= span + 1]
        return persistent_labels([Frame(particles, contacts)], [held], f.motion)

    def _conclude(self) -> None:
        self.results.sort(key=lambda r: r.step)


class HoldWindowOpen(DumpReadError):
    """A frame too close to the end of the run for its hold window (not an error of it)."""


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
