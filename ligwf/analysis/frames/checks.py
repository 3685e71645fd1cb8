"""Is this frame the run's own, complete and plausible? Checked before any frame is used.

A readable dump is not yet a right one: a frame can be missing, left over from an earlier
run, copied in from another replica, edited, or hold particles the run never had. Every
stage that reads frames (granules, flow) asks this module first, so they use the same
frames and report the same reasons:

* :func:`plan_frames` (before reading): the frames the run must have left are the dump
  steps of its scene up to the step the manifest says it reached
  (:meth:`~ligwf.study.case.CaseFolder.expected_dump_steps`). A missing particle or
  contact dump, a dump at a step the run never writes (beyond the run, or off the dump
  interval) is a problem of that frame: listed with its reason, never analysed, and so is a
  particle dump that holds the same bytes as the frame before it (a copy; an array copy,
  same positions in other bytes, fails :func:`check_particles`). When the
  run left a dump record (:meth:`~ligwf.study.case.CaseFolder.dump_record`),
  :meth:`ExpectedFrames.check_record` refuses a file whose size or SHA-256 differs from what
  the run left (done by whoever reads the frame, so MPI ranks share the hashing).
* :func:`check_particles` / :func:`check_contacts` (after reading): the particle count
  and ids are the scene's (1..N: the fill deletes the surplus of the top-up wave, so the
  ids stay contiguous), radii are the scene's size classes, centres lie inside the drum,
  speeds and liquid contents are physical, and the contact dump describes the particle
  dump of the same step: each pair's overlap equals r_i + r_j minus the distance of the
  two centres (nearest periodic image). Permuted ids, a contact dump of another frame or
  flipped bits in positions fail these; flipped bits elsewhere fail the record or the
  value range LIGGGHTS wrote into the array header (:mod:`ligwf.analysis.frames.vtu`).

Checked once per analysis: inside :func:`shared_checks` (one analysis, or one rank's
share of it) the verdict of each file's record check and of each particle frame's check
is kept, keyed by the file's identity (device, inode, size, modification time), so the
flow stage and the granule stage, which read the same dumps, hash and check each once; a
file replaced in between has another identity and is checked again.
"""

from __future__ import annotations

import hashlib
import os
import re
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from ligwf.analysis.frames.dumps import (ContactFrame, FrameFiles, ParticleFrame, dump_files,
                                         read_particles)
from ligwf.errors import ConfigError, DumpReadError
from ligwf.fsio import file_sha256
from ligwf.study.case import CaseFolder, DumpRecord

#: Relative slack of the geometric checks (float32 positions, mesh facets vs circle).
GEOMETRY_SLACK = 0.05
#: A speed above this many times (tip speed + free fall across the drum) is not physical.
SPEED_FACTOR = 20.0
#: |distance - (r_i + r_j - delta)| allowed, as a fraction of r_i + r_j.
OVERLAP_TOLERANCE = 1e-3


@dataclass(frozen=True)
class ExpectedFrames:
    """The frames of a case to read, and those refused before reading (with reasons)."""

    case_id: str
    frames: tuple[FrameFiles, ...]
    problems: tuple[dict, ...]           # {case_id, step, kind: missing|unexpected, reason}
    expected: int                        # frames the run should have left
    record: DumpRecord | None            # the run's dump record (None: run by hand)

    def check_record(self, ff: FrameFiles) -> None:
        """DumpReadError when a file of the frame is not the one the run left (size or
        SHA-256 differ from the dump record; nothing to check without a record)."""
        if self.record is None:
            return
        for path in (ff.particles, ff.contacts):
            if path is not None:
                _once(("record",), path, lambda path=path: self._check_file(path))

    def _check_file(self, path: Path) -> None:
        if why := self.record.mismatch(path):
            raise DumpReadError(why)


#: verdicts of the checks inside :func:`shared_checks` (None outside: every call checks)
_VERDICTS: dict | None = None


@contextmanager
def shared_checks() -> Iterator[None]:
    """Within: each file's record check and each particle frame's check runs once (see
    the module doc); nested uses share the outermost's verdicts."""
    global _VERDICTS, _POSITIONS
    outer = _VERDICTS is not None
    if not outer:
        _VERDICTS, _POSITIONS = {}, {}
    try:
        yield
    finally:
        if not outer:
            _VERDICTS, _POSITIONS = None, None


def _once(kind: tuple, path: Path, check: Callable[[], None]) -> None:
    """``check()`` (raising DumpReadError), or its kept verdict for this file."""
    if _VERDICTS is None:
        return check()
    try:
        st = os.stat(path)
    except OSError:
        return check()
    key = (*kind, str(path), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)
    if key in _VERDICTS:
        if _VERDICTS[key] is not None:
            raise DumpReadError(_VERDICTS[key])
        return None
    try:
        check()
    except DumpReadError as exc:
        _VERDICTS[key] = str(exc)
        raise
    _VERDICTS[key] = None
    return None


def end_step(case: CaseFolder) -> int:
    """Last step the run reached: the manifest's (or the dump record's) step count; the
    scene's total for a case without either (run by hand)."""
    try:
        m = case.manifest()
    except (ValueError, TypeError, AttributeError):
        m = None
    if m is not None and m.steps_done > 0:
        return int(m.steps_done)
    record = case.dump_record()
    if record is not None and record.steps_done > 0:
        return record.steps_done
    return case.scaled.total_steps


def plan_frames(case: CaseFolder) -> ExpectedFrames:
    """The case's frames to read and the refused ones; ConfigError when its dump record is
    unreadable or belongs to another scene (nothing of the case can be trusted)."""
    record = case.dump_record()
    if record is not None and record.scene_hash != case.scene_hash:
        raise ConfigError(f"{case.path}: the dump record was written for another scene "
                          "(dumps of an earlier run?)")
    s = case.scaled
    last = end_step(case)
    expected = case.expected_dump_steps(last)
    parts, contacts = dump_files(case.path)
    plan = f"every {s.numerics.dump_every} steps from {case.production_start_step} to {last}"
    frames, problems = [], []

    def refuse(step: int, reason: str, kind: str = "missing") -> None:
        problems.append({"case_id": case.case_id, "step": step, "kind": kind, "reason": reason})

    for step in sorted(set(expected) | set(parts) | set(contacts)):
        part, contact = parts.get(step), contacts.get(step)
        if step not in expected:
            refuse(step, f"{part or contact}: not a dump step of this run ({plan}): left "
                   "over from another run or added by hand", "unexpected")
        elif part is None:
            refuse(step, f"missing frame: no particle dump for step {step}"
                   + (f" (its contact dump {contact.name} is left)" if contact else ""))
        elif s.contact_dumps and contact is None:
            refuse(step, f"missing frame: no contact dump for step {step} "
                   f"(its particle dump {part.name} is left)")
        elif (copy := _copy_of(frames[-1] if frames else None, part, record)) is not None:
            refuse(step, f"{part}: byte for byte the particle dump of step {copy} (a copy of "
                   "it: the bed moves between two dumps of a turning drum)", "duplicate")
        else:
            frames.append(FrameFiles(step, part, contact))
    return ExpectedFrames(case.case_id, tuple(frames), tuple(problems), len(expected), record)


def _copy_of(prev: FrameFiles | None, part: Path, record: DumpRecord | None) -> int | None:
    """The step of ``prev`` when ``part`` holds the same bytes as its particle dump (a frame
    copied over its neighbour), else None. Files of different sizes differ; with a dump
    record the run's own digests are compared (a copy made after the run fails the
    record check anyway), without one the two files are hashed."""
    if prev is None:
        return None
    try:
        if os.stat(prev.particles).st_size != os.stat(part).st_size:
            return None
    except OSError:
        return None
    if record is not None:
        a, b = record.files.get(prev.particles.name), record.files.get(part.name)
        same = a is not None and b is not None and a[1] == b[1]
    else:
        same = file_sha256(prev.particles) == file_sha256(part)
    return prev.step if same else None


def _fail(p: ParticleFrame | ContactFrame, what: str) -> None:
    raise DumpReadError(f"{p.path}: {what}")


def check_particles(case: CaseFolder, p: ParticleFrame) -> None:
    """DumpReadError when the particle frame is not one of this run's (see module doc)."""
    _once(("particles", str(case.path)), Path(p.path), lambda: _check_particles(case, p))


def _check_particles(case: CaseFolder, p: ParticleFrame) -> None:
    s = case.scaled
    n = s.particles.count
    if len(p) != n:
        _fail(p, f"{len(p)} particles, the run has {n}")
    if p.ids[0] != 1 or p.ids[-1] != n:
        _fail(p, f"particle ids {p.ids[0]}..{p.ids[-1]}, the run numbers them 1..{n}")
    if np.any(p.types < 1):
        _fail(p, "particle type below 1")
    radii = 0.5 * np.asarray(s.particles.diameters, dtype=float)
    near = np.min(np.abs(p.radii[:, None] - radii[None, :]) / radii[None, :], axis=1)
    if np.any(near > 1e-6):
        _fail(p, f"radius {p.radii[near.argmax()]:.6g} m is none of the scene's size classes")
    ia = s.drum.axis.index
    across = np.delete(p.positions, ia, axis=1)
    reach = 0.5 * s.drum.diameter * (1 + GEOMETRY_SLACK)
    if np.any(np.hypot(across[:, 0], across[:, 1]) > reach):
        _fail(p, "a particle centre lies outside the drum")
    along = p.positions[:, ia]
    slack = GEOMETRY_SLACK * s.drum.length
    if np.any(along < -slack) or np.any(along > s.drum.length + slack):
        _fail(p, f"a particle centre lies outside the drum length [0, {s.drum.length:g}] m")
    limit = SPEED_FACTOR * (s.drum.omega * s.drum.radius + np.sqrt(2 * 9.81 * s.drum.diameter))
    if np.any(np.linalg.norm(p.velocities, axis=1) > limit):
        _fail(p, f"a particle speed above {limit:.3g} m/s (not physical in this drum)")
    if p.liquid_content is not None and np.any((p.liquid_content < 0) | (p.liquid_content > 1)):
        _fail(p, "liquid content outside [0, 1]")
    before = p.step - s.numerics.dump_every
    if before >= case.production_start_step and \
            _positions_digest(Path(p.path).with_name(_step_name(p, before)), case) == \
            _positions_digest(Path(p.path), case, p):
        _fail(p, f"every particle position is that of the frame of step {before} (an array "
              "copy of it: the bed moves between two dumps of a turning drum)")


def _step_name(p: ParticleFrame, step: int) -> str:
    """The file name of the same kind of dump as ``p`` at another step."""
    return re.sub(rf"_{p.step}(\.vt[ur])$", rf"_{step}\1", Path(p.path).name)


#: SHA-256 of a particle frame's positions by (path, identity): kept inside
#: :func:`shared_checks`, so a frame's neighbour is usually read once (see check_particles)
_POSITIONS: dict | None = None


def _positions_digest(path: Path, case: CaseFolder, frame: ParticleFrame | None = None
                      ) -> str | None:
    """SHA-256 of the positions of the particle dump ``path`` (``frame``: already read),
    None when it is missing or unreadable."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    key = (str(path), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)
    if _POSITIONS is not None and key in _POSITIONS:
        return _POSITIONS[key]
    try:
        frame = frame or read_particles(path, None, case.scaled.numerics.dt)
    except (DumpReadError, OSError, ValueError):
        return None
    digest = hashlib.sha256(np.ascontiguousarray(frame.positions).tobytes()).hexdigest()
    if _POSITIONS is not None:
        _POSITIONS[key] = digest
    return digest


def check_contacts(p: ParticleFrame, c: ContactFrame, periodic_axis: int | None,
                   box_length: float) -> None:
    """DumpReadError unless every pair's overlap matches the two particles' centres and
    radii in ``p`` (nearest image along the periodic axis, its column ``periodic_axis``):
    the contact dump then belongs to the same particles at the same step."""
    if len(c) == 0:
        return
    i, j = p.index_of(c.id1), p.index_of(c.id2)
    d = p.positions[i] - p.positions[j]
    if periodic_axis is not None and box_length > 0:
        d[:, periodic_axis] -= box_length * np.round(d[:, periodic_axis] / box_length)
    reach = p.radii[i] + p.radii[j]
    off = np.abs(np.linalg.norm(d, axis=1) - (reach - c.delta)) / reach
    if np.any(off > OVERLAP_TOLERANCE):
        k = int(off.argmax())
        _fail(c, f"pair {c.id1[k]}-{c.id2[k]}: overlap {c.delta[k]:.3g} m does not match the "
              f"particle dump of step {p.step} ({int(np.sum(off > OVERLAP_TOLERANCE))} pair(s) "
              "off: ids permuted, or the dumps are of different frames or runs)")
