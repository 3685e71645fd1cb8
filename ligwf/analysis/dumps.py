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

import base64
import binascii
import mmap
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ligwf.analysis.dumps_numba import decode_base64, first_of_each_pair
from ligwf.errors import DumpReadError

PARTICLE_ARRAYS = ("id", "type", "v", "radius")
CONTACT_ARRAYS = ("id1", "id2", "delta")
_CONTACT_WANTED = frozenset(CONTACT_ARRAYS)     # contact geometry (Points) is not used
_PARTICLE_RE = re.compile(r"^particles_(\d+)\.vtu$")
_CONTACT_RE = re.compile(r"^contacts_(\d+)\.vtu$")


@dataclass(frozen=True)
class ParticleFrame:
    """Particles of one dump, sorted by id. Positions in m, velocities in m/s."""

    path: Path
    step: int
    time: float                  # s, step * dt
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


def discover_frames(case_dir: Path) -> list[FrameFiles]:
    """Frames of a case folder (its ``post/`` subfolder or itself), sorted by step.

    A particle dump without its contact dump is listed with ``contacts=None`` (a dry run
    or a run without granule analysis); a contact dump without particles is ignored.
    The ``particles_boundingBox_*`` files LIGGGHTS writes next to each dump do not match.
    """
    case_dir = Path(case_dir)
    post = case_dir / "post" if (case_dir / "post").is_dir() else case_dir
    parts: dict[int, Path] = {}
    contacts: dict[int, Path] = {}
    for path in post.iterdir():
        if m := _PARTICLE_RE.match(path.name):
            parts[int(m.group(1))] = path
        elif m := _CONTACT_RE.match(path.name):
            contacts[int(m.group(1))] = path
    return [FrameFiles(step, parts[step], contacts.get(step)) for step in sorted(parts)]


def _read_mesh(path: Path):
    """meshio.read with every failure turned into a DumpReadError naming the file."""
    import meshio

    path = Path(path)
    if not path.is_file():
        raise DumpReadError(f"{path}: dump file does not exist")
    if path.stat().st_size == 0:
        raise DumpReadError(f"{path}: dump file is empty (0 bytes)")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return meshio.read(path, file_format="vtu")
    except (KeyboardInterrupt, MemoryError):
        raise
    except BaseException as exc:  # meshio raises ParseError, ReadError, ValueError, SystemExit...
        reason = f"{type(exc).__name__}: {exc}".strip().rstrip(":")
        raise DumpReadError(f"{path}: not a readable VTU file (truncated or corrupt?): "
                            f"{reason}") from None


_PIECE_RE = re.compile(rb'<Piece\s+NumberOfPoints="(\d+)"\s+NumberOfCells="(\d+)"')


def _piece_counts(path: Path) -> tuple[int, int] | None:
    """(points, cells) from the ``<Piece>`` header, read before meshio: meshio cannot read
    a VTU without points (it fails concatenating zero arrays), which an empty frame is."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096)
    except OSError:
        return None
    m = _PIECE_RE.search(head)
    return (int(m.group(1)), int(m.group(2))) if m else None


@dataclass(frozen=True)
class _VtuData:
    """The parts of a VTU file the readers use (meshio's layout: 1-D or (n, components))."""

    points: np.ndarray
    point_data: dict[str, np.ndarray]
    cell_data: dict[str, np.ndarray]
    n_cells: int


_VTK_DTYPES = {"Int8": "i1", "UInt8": "u1", "Int16": "i2", "UInt16": "u2", "Int32": "i4",
               "UInt32": "u4", "Int64": "i8", "UInt64": "u8", "Float32": "f4", "Float64": "f8"}
_ATTR_RE = re.compile(rb'(\w+)="([^"]*)"')


_SECTION_TAGS = ((b"<Points", "points"), (b"<PointData", "point"), (b"<CellData", "cell"),
                 (b"<Cells", "cells"))


def _skip_space(raw, pos: int) -> int:
    while raw[pos:pos + 1] in (b" ", b"\n", b"\r", b"\t"):
        pos += 1
    return pos


def _data_arrays(raw, header: np.dtype):
    """(section, attributes, content start, content end) of every DataArray element.

    A binary array is one base64 block whose first bytes are its byte count (``header``);
    decoding just those gives the block's length, and the closing tag is looked for right
    there, so the megabytes of base64 in between (of arrays the caller may not even want)
    are never scanned or paged in. Where it is not there (header in a block of its own,
    line breaks, ASCII), bytes.find scans as before. The section (points, point, cell,
    cells) is the last section tag seen in the short XML between two arrays.
    """
    head_chars = 4 * -(-header.itemsize // 3)
    pos, where = 0, None
    while (start := raw.find(b"<DataArray", pos)) >= 0:
        gap = raw[pos:start]
        last = max((gap.rfind(tag), name) for tag, name in _SECTION_TAGS)
        if last[0] >= 0:
            where = last[1]
        tag_end = raw.find(b">", start)
        if tag_end < 0:
            raise ValueError("unterminated DataArray element")
        attrs = dict(_ATTR_RE.findall(raw[start + 10:tag_end]))
        content = _skip_space(raw, tag_end + 1)
        length = None
        if attrs.get(b"format") == b"binary":
            try:
                nbytes = int(np.frombuffer(binascii.a2b_base64(
                    raw[content:content + head_chars])[:header.itemsize], header)[0])
                length = 4 * -(-(header.itemsize + nbytes) // 3)
            except (binascii.Error, ValueError, IndexError):
                length = None
        end = close = -1
        if length is not None:
            guess = _skip_space(raw, content + length)
            if raw[guess:guess + 12] == b"</DataArray>":
                end, close = content + length, guess
        if end < 0:
            end = close = raw.find(b"</DataArray>", tag_end)
            if end < 0:
                raise ValueError("unterminated DataArray element")
        yield where, attrs, content, end
        pos = close + 12


def _read_vtu_fast(path: Path, wanted: frozenset[str] | None) -> _VtuData | None:
    """Decode LIGGGHTS' binary inline VTU directly: base64 of only the wanted arrays.

    meshio parses the whole XML tree and decodes every array; for a 360k-particle contact
    dump that is seconds per frame. This maps the file into memory, walks the DataArray
    elements (jumping over each one's base64 by its known length) and decodes only what the
    analysis uses, stopping once it has all of it: of a contact dump (seven cell arrays,
    points and connectivity) only id1, id2 and delta are ever read from disk. Returns None
    for any other flavour (ASCII, compressed, appended, big-endian), which meshio then
    reads; tests check both give identical arrays on real dumps.
    """
    with open(path, "rb") as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as raw:
        return _decode_vtu(path, raw, wanted)


def _decode_vtu(path: Path, raw, wanted: frozenset[str] | None) -> _VtuData | None:
    head = raw[:1024]
    if (b'type="UnstructuredGrid"' not in head or b"compressor" in head
            or b"BigEndian" in head or b"<AppendedData" in raw[-4096:]):
        return None
    if not raw[-256:].rstrip().endswith(b"</VTKFile>"):
        raise DumpReadError(f"{path}: not a readable VTU file (truncated or corrupt?): "
                            "no closing </VTKFile>")
    header = np.dtype("<u8") if b'header_type="UInt64"' in head else np.dtype("<u4")
    m = _PIECE_RE.search(head)
    if m is None:
        return None
    n_points, n_cells = int(m.group(1)), int(m.group(2))

    point_data, cell_data, points = {}, {}, None
    missing = None if wanted is None else set(wanted)
    for where, attrs, start, end in _data_arrays(raw, header):
        if where not in ("points", "point", "cell"):     # Cells: connectivity, offsets, types
            continue
        name = attrs.get(b"Name", b"").decode()
        key = "Points" if where == "points" else name
        if missing is not None and key not in missing:
            continue
        if attrs.get(b"format") != b"binary":
            return None
        comps = int(attrs.get(b"NumberOfComponents", b"1"))
        dtype = np.dtype("<" + _VTK_DTYPES[attrs[b"type"].decode()])
        rows = n_cells if where == "cell" else n_points
        text = raw[start:end].rstrip()
        decoded = decode_base64(text, header.itemsize)
        if decoded is not None and len(decoded) > header.itemsize:
            nbytes = int(decoded[:header.itemsize].view(header)[0])
            data = decoded[header.itemsize:]
        else:       # not one plain block: binascii (which skips stray characters)
            raw_data = binascii.a2b_base64(text)
            nbytes = int(np.frombuffer(raw_data[:header.itemsize], header)[0]) \
                if len(raw_data) >= header.itemsize else -1
            if len(raw_data) == header.itemsize:       # header encoded as its own block
                raw_data = binascii.a2b_base64(text[len(base64.b64encode(raw_data)):])
            else:
                raw_data = raw_data[header.itemsize:]
            data = np.frombuffer(raw_data, np.uint8)
        expected = rows * comps * dtype.itemsize
        if nbytes != expected or len(data) < expected:
            raise DumpReadError(f"{path}: not a readable VTU file (truncated or corrupt?): "
                                f"array {name or 'Points'} decodes to {len(data)} bytes, "
                                f"expected {expected}")
        arr = data[:expected].view(dtype)
        arr = arr.reshape(rows, comps) if comps > 1 else arr
        if where == "points":
            points = arr
        elif where == "cell":
            cell_data[name] = arr
        else:
            point_data[name] = arr
        if missing is not None:
            missing.discard(key)
            if not missing:
                break
    if points is None:
        points = np.zeros((n_points, 3))
    return _VtuData(points, point_data, cell_data, n_cells)


def _read_vtu(path: Path, wanted: frozenset[str] | None, reader: str) -> _VtuData:
    """``reader="fast"``: the direct decoder (meshio for other VTU flavours);
    ``"meshio"``: meshio only (the reference)."""
    path = Path(path)
    if not path.is_file():
        raise DumpReadError(f"{path}: dump file does not exist")
    if path.stat().st_size == 0:
        raise DumpReadError(f"{path}: dump file is empty (0 bytes)")
    if reader == "fast":
        try:
            data = _read_vtu_fast(path, wanted)
        except (ValueError, KeyError, binascii.Error) as exc:
            raise DumpReadError(f"{path}: not a readable VTU file (truncated or corrupt?): "
                                f"{type(exc).__name__}: {exc}") from None
        if data is not None:
            return data
    elif reader != "meshio":
        raise ValueError(f"reader {reader!r}: use fast or meshio")
    mesh = _read_mesh(path)
    cell_data = {name: np.concatenate(arrs) if len(arrs) > 1 else arrs[0]
                 for name, arrs in mesh.cell_data.items()}
    return _VtuData(mesh.points, dict(mesh.point_data), cell_data,
                    sum(len(block.data) for block in mesh.cells))


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


def read_particles(path: Path, step: int | None = None, dt: float = 0.0,
                   reader: str = "fast") -> ParticleFrame:
    """Read one particle dump; ``step`` defaults to the number in the file name.

    ``dt`` (s) converts the step to a time (LIGGGHTS' time is step * dt with a fixed dt).
    """
    path = Path(path)
    if step is None:
        m = _PARTICLE_RE.match(path.name)
        step = int(m.group(1)) if m else 0
    counts = _piece_counts(path)
    if counts is not None and counts[0] == 0:
        raise DumpReadError(f"{path}: particle dump holds zero particles")
    mesh = _read_vtu(path, None, reader)
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
        path=path, step=int(step), time=int(step) * float(dt), ids=ids,
        types=arrays["type"].astype(np.int32), positions=positions[order],
        velocities=arrays["v"].astype(np.float64), radii=arrays["radius"].astype(np.float64),
        liquid_content=None if liquid is None else liquid.astype(np.float64))


def read_contacts(path: Path, step: int | None = None, reader: str = "fast") -> ContactFrame:
    """Read one contact dump (zero contacts is a valid frame: a dispersed or dry bed)."""
    path = Path(path)
    if step is None:
        m = _CONTACT_RE.match(path.name)
        step = int(m.group(1)) if m else 0
    counts = _piece_counts(path)
    if counts is not None and counts[1] == 0:
        empty = np.zeros(0, dtype=np.int64)
        return ContactFrame(path, int(step), empty, empty.copy(), np.zeros(0))
    mesh = _read_vtu(path, _CONTACT_WANTED, reader)
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
