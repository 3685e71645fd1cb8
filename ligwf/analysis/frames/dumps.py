"""Dump reading: LIGGGHTS particle and contact ``.vtu`` files -> numpy arrays, per frame.

The drum input (``templates/drum.in.j2``) writes, every ``dump_every`` production steps,

* ``post/particles_<step>.vtu``: one vertex per particle, point arrays ``id``, ``type``,
  ``v`` (m/s), ``radius`` (m) and, when wet, ``f_surfaceLiquidContent`` (fraction of the
  particle volume, despite the LIGGGHTS docs saying %);
* ``post/contacts_<step>.vtu``: one line cell per interacting pair from
  ``compute pair/gran/local`` with cell arrays ``id1``, ``id2`` (stored as doubles),
  ``vel1``, ``vel2``, ``force``, ``force_normal`` (N) and ``delta`` (overlap, m; negative
  for a liquid bridge between separated spheres).

Both are read with meshio (the ``.vtu`` flavour is the one meshio can read, see
LIGGGHTS_NOTES "Output"). Particles are returned sorted by id, so a particle's index is
the same in every frame of a run and contacts refer to particles by id only: pairs across
the periodic boundary have line cells that span the whole box, their geometry is useless.

Every failure to read a file (missing, empty, truncated XML, corrupt base64, a missing
array, zero particles, ids a contact refers to that are not in the particle frame) raises
:class:`~ligwf.errors.DumpReadError` naming the file, so a whole-run analysis can report
and skip that frame instead of analysing garbage.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ligwf.analysis.dumps_numba import first_of_each_pair
from ligwf.analysis.frames.vtu import piece_counts, read_vtu
from ligwf.errors import DumpReadError
from ligwf.study.layout import CONTACT_DUMP_RE, PARTICLE_DUMP_RE, POST_DIR

PARTICLE_ARRAYS = ("id", "type", "v", "radius")
CONTACT_ARRAYS = ("id1", "id2", "delta")
_CONTACT_WANTED = frozenset(CONTACT_ARRAYS)     # contact geometry (Points) is not used



@dataclass(frozen=True)
class ParticleFrame:
    """Particles of one dump, sorted by id. Positions in m, velocities in m/s."""

    path: Path
    step: int
    time: float                  # s, step * dt (nan when dt was not given)
    ids: np.ndarray              # (N,) int64, ascending
    types: np.ndarray            # (N,) int32
    positions: np.ndarray        # (N, 3) float64 (the dump stores float32)
    velocities: np.ndarray       # (N, 3) float64
    radii: np.ndarray            # (N,) float64
    liquid_content: np.ndarray | None   # (N,) float64 fraction of particle volume, or None (dry)

    def __len__(self) -> int:
        return len(self.ids)

    @property
    def volumes(self) -> np.ndarray:
        """Sphere volumes, m^3."""
        return 4.0 / 3.0 * np.pi * (self.radii * self.radii * self.radii)

    def index_of(self, ids: np.ndarray) -> np.ndarray:
        """Row index of each particle id in ``ids``; DumpReadError if one is not present."""
        ids = np.asarray(ids)
        if len(self.ids) and len(ids) and self.ids[-1] - self.ids[0] == len(self.ids) - 1:
            # ids are contiguous (LIGGGHTS numbers 1..N while no particle is deleted):
            # the row is id - first id, no search needed
            lo, hi = ids.min(), ids.max()
            if lo >= self.ids[0] and hi <= self.ids[-1]:
                return ids - self.ids[0]
        idx = np.searchsorted(self.ids, ids)
        idx = np.minimum(idx, len(self.ids) - 1)
        missing = self.ids[idx] != ids
        if np.any(missing):
            raise DumpReadError(f"{self.path}: no particle with id {int(np.asarray(ids)[missing][0])} "
                                "(referred to by the contact dump of the same step)")
        return idx


@dataclass(frozen=True)
class ContactFrame:
    """Interacting pairs of one dump (each unordered pair once)."""

    path: Path
    step: int
    id1: np.ndarray              # (M,) int64
    id2: np.ndarray              # (M,) int64
    delta: np.ndarray            # (M,) float64 overlap, m (negative: separated, bridged)

    def __len__(self) -> int:
        return len(self.id1)


@dataclass(frozen=True)
class FrameFiles:
    """The dump files of one output step of a run."""

    step: int
    particles: Path
    contacts: Path | None


def dump_files(case_dir: Path) -> tuple[dict[int, Path], dict[int, Path]]:
    """(particle dumps, contact dumps) of a case folder (its ``post/`` subfolder or itself)
    by step. The ``particles_boundingBox_*`` files LIGGGHTS writes next to each dump do
    not match."""
    case_dir = Path(case_dir)
    post = case_dir / POST_DIR if (case_dir / POST_DIR).is_dir() else case_dir
    parts: dict[int, Path] = {}
    contacts: dict[int, Path] = {}
    if not post.is_dir():
        return parts, contacts
    for path in post.iterdir():
        if m := PARTICLE_DUMP_RE.match(path.name):
            parts[int(m.group(1))] = path
        elif m := CONTACT_DUMP_RE.match(path.name):
            contacts[int(m.group(1))] = path
    return parts, contacts


def discover_frames(case_dir: Path) -> list[FrameFiles]:
    """Frames of a case folder (its ``post/`` subfolder or itself), sorted by step.

    A particle dump without its contact dump is listed with ``contacts=None`` (a dry run
    or a run without granule analysis); a contact dump without particles is ignored here
    (:func:`ligwf.analysis.frames.checks.plan_frames` reports it).
    """
    parts, contacts = dump_files(case_dir)
    return [FrameFiles(step, parts[step], contacts.get(step)) for step in sorted(parts)]


def _step_of(path: Path, step: int | None, pattern: re.Pattern) -> int:
    """The step given, else the number in a LIGGGHTS dump name; DumpReadError otherwise
    (never a silent step 0: every frame would then claim the same time)."""
    if step is not None:
        return int(step)
    m = pattern.match(path.name)
    if m is None:
        raise DumpReadError(f"{path}: no step in the file name (expected "
                            f"{pattern.pattern.strip('^$')}); pass step=")
    return int(m.group(1))


def _need(path: Path, data: dict, names: tuple[str, ...], kind: str) -> None:
    missing = [n for n in names if n not in data]
    if missing:
        raise DumpReadError(f"{path}: {kind} dump lacks the array(s) {', '.join(missing)} "
                            f"(has: {', '.join(sorted(data)) or 'none'})")


def _check_rows(path: Path, name: str, arr: np.ndarray, rows: int, cols: int | None) -> None:
    shape_ok = arr.shape[0] == rows and (arr.ndim == 1 if cols is None else
                                         arr.ndim == 2 and arr.shape[1] == cols)
    if not shape_ok:
        raise DumpReadError(f"{path}: array {name} has shape {arr.shape}, expected "
                            f"({rows}{'' if cols is None else f', {cols}'})")
    if not np.all(np.isfinite(arr)):
        raise DumpReadError(f"{path}: array {name} holds nan or inf values")


def read_particles(path: Path, step: int | None = None, dt: float | None = None,
                   reader: str = "fast") -> ParticleFrame:
    """Read one particle dump; ``step`` defaults to the number in the file name (a name
    without one is an error: pass ``step``).

    ``dt`` (s) converts the step to a time (LIGGGHTS' time is step * dt with a fixed dt);
    without it the time is nan (unknown), never 0.
    """
    path = Path(path)
    step = _step_of(path, step, PARTICLE_DUMP_RE)
    counts = piece_counts(path)
    if counts is not None and counts[0] == 0:
        raise DumpReadError(f"{path}: particle dump holds zero particles")
    mesh = read_vtu(path, None, reader)
    n = len(mesh.points)
    if n == 0:
        raise DumpReadError(f"{path}: particle dump holds zero particles")
    data = mesh.point_data
    _need(path, data, PARTICLE_ARRAYS, "particle")
    ids = np.asarray(data["id"]).astype(np.int64).reshape(-1)
    _check_rows(path, "id", ids, n, None)
    order = np.argsort(ids, kind="stable")
    ids = ids[order]
    if np.any(ids[1:] == ids[:-1]):
        raise DumpReadError(f"{path}: duplicate particle ids")
    arrays = {}
    for name, cols in (("type", None), ("v", 3), ("radius", None),
                       ("f_surfaceLiquidContent", None)):
        if name not in data:
            arrays[name] = None
            continue
        arr = np.asarray(data[name])
        if cols is None:
            arr = arr.reshape(-1) if arr.ndim == 2 and arr.shape[1] == 1 else arr
        _check_rows(path, name, arr, n, cols)
        arrays[name] = arr[order]
    positions = np.asarray(mesh.points, dtype=np.float64)
    _check_rows(path, "points", positions, n, 3)
    if np.any(arrays["radius"] <= 0):
        raise DumpReadError(f"{path}: non-positive particle radius")
    liquid = arrays["f_surfaceLiquidContent"]
    return ParticleFrame(
        path=path, step=step, time=math.nan if dt is None else step * float(dt), ids=ids,
        types=arrays["type"].astype(np.int32), positions=positions[order],
        velocities=arrays["v"].astype(np.float64), radii=arrays["radius"].astype(np.float64),
        liquid_content=None if liquid is None else liquid.astype(np.float64))


def read_contacts(path: Path, step: int | None = None, reader: str = "fast") -> ContactFrame:
    """Read one contact dump (zero contacts is a valid frame: a dispersed or dry bed);
    ``step`` defaults to the number in the file name (a name without one is an error)."""
    path = Path(path)
    step = _step_of(path, step, CONTACT_DUMP_RE)
    counts = piece_counts(path)
    if counts is not None and counts[1] == 0:
        empty = np.zeros(0, dtype=np.int64)
        return ContactFrame(path, int(step), empty, empty.copy(), np.zeros(0))
    mesh = read_vtu(path, _CONTACT_WANTED, reader)
    m_rows = mesh.n_cells
    data = mesh.cell_data
    if m_rows == 0:
        empty = np.zeros(0, dtype=np.int64)
        return ContactFrame(path, int(step), empty, empty.copy(), np.zeros(0))
    _need(path, data, CONTACT_ARRAYS, "contact")
    for name in CONTACT_ARRAYS:
        _check_rows(path, name, np.asarray(data[name]), m_rows, None)
    id1 = np.asarray(data["id1"]).astype(np.int64)
    id2 = np.asarray(data["id2"]).astype(np.int64)
    if np.any(id1 < 1) or np.any(id2 < 1) or np.any(id1 == id2):
        raise DumpReadError(f"{path}: contact ids out of range or a particle paired with itself")
    # Each unordered pair once: a pair straddling two MPI subdomains could be listed by both.
    lo, hi = np.minimum(id1, id2), np.maximum(id1, id2)
    first = first_of_each_pair(lo, hi)
    data_delta = np.asarray(data["delta"], dtype=np.float64)
    if first is not None:
        lo, hi, data_delta = lo[first], hi[first], data_delta[first]
    return ContactFrame(path, int(step), lo, hi, data_delta)
