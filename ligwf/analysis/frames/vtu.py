"""VTU (VTK XML unstructured grid) reading for the dump readers of :mod:`ligwf.analysis.frames.dumps`.

Two readers return the same :class:`VtuData`: meshio (the reference; it reads every VTU
flavour) and a direct decoder for what LIGGGHTS writes (``dump_modify binary yes``: inline
base64 with a byte-count header per array), which maps the file, jumps over arrays nobody
asked for by their byte count and decodes the wanted ones with a compiled base64 decoder.
Decoded arrays are checked against the value range LIGGGHTS records in each array's
header, so corrupt data that is still valid base64 is caught too. Every failure to read
a file raises :class:`~ligwf.errors.DumpReadError` naming it.
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

from ligwf.analysis.dumps_numba import decode_base64
from ligwf.errors import DumpReadError


def _require_file(path: Path) -> None:
    if not path.is_file():
        raise DumpReadError(f"{path}: dump file does not exist")
    if path.stat().st_size == 0:
        raise DumpReadError(f"{path}: dump file is empty (0 bytes)")


def _read_with_meshio(path: Path):
    """meshio.read with every failure turned into a DumpReadError naming the file."""
    import meshio

    path = Path(path)
    _require_file(path)
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


def piece_counts(path: Path) -> tuple[int, int] | None:
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
class VtuData:
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


def _read_fast(path: Path, wanted: frozenset[str] | None) -> VtuData | None:
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


def _decode_vtu(path: Path, raw, wanted: frozenset[str] | None) -> VtuData | None:
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
        if nbytes != expected or len(data) < expected:     # each count said, both sides
            what = (f"its byte count says {nbytes} bytes, the piece's {rows} x {comps} "
                    f"values of {dtype.itemsize} bytes are {expected}" if nbytes != expected
                    else f"decodes to {len(data)} bytes, expected {expected}")
            raise DumpReadError(f"{path}: not a readable VTU file (truncated or corrupt?): "
                                f"array {name or 'Points'} {what}")
        arr = data[:expected].view(dtype)
        arr = arr.reshape(rows, comps) if comps > 1 else arr
        _check_range(path, name or "Points", attrs, arr)
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
    return VtuData(points, point_data, cell_data, n_cells)


def _check_range(path: Path, name: str, attrs: dict, arr: np.ndarray) -> None:
    """DumpReadError when the decoded values leave the range the writer recorded in the
    array's header (``RangeMin`` / ``RangeMax``, of the magnitude for vectors): flipped bits
    in valid base64 decode without error but usually move a value out of it. Arrays with
    nan or inf are left to the dump readers (they name the problem)."""
    if b"RangeMin" not in attrs or b"RangeMax" not in attrs or len(arr) == 0:
        return
    try:
        lo, hi = float(attrs[b"RangeMin"]), float(attrs[b"RangeMax"])
    except ValueError:
        return
    values = np.asarray(arr, dtype=np.float64)
    if values.ndim == 2:
        values = np.linalg.norm(values, axis=1)
    if not np.all(np.isfinite(values)):
        return
    tol = 1e-6 * max(abs(lo), abs(hi)) + 1e-300
    got_lo, got_hi = float(values.min()), float(values.max())
    if abs(got_lo - lo) > tol or abs(got_hi - hi) > tol:
        raise DumpReadError(f"{path}: array {name} spans [{got_lo:.9g}, {got_hi:.9g}], its header "
                            f"says [{lo:.9g}, {hi:.9g}] (corrupt data: flipped bits?)")


def read_vtu(path: Path, wanted: frozenset[str] | None, reader: str) -> VtuData:
    """``reader="fast"``: the direct decoder (meshio for other VTU flavours);
    ``"meshio"``: meshio only (the reference)."""
    path = Path(path)
    _require_file(path)
    if reader == "fast":
        try:
            data = _read_fast(path, wanted)
        except (ValueError, KeyError, binascii.Error) as exc:
            raise DumpReadError(f"{path}: not a readable VTU file (truncated or corrupt?): "
                                f"{type(exc).__name__}: {exc}") from None
        if data is not None:
            return data
    elif reader != "meshio":
        raise ValueError(f"reader {reader!r}: use fast or meshio")
    mesh = _read_with_meshio(path)
    cell_data = {name: np.concatenate(arrs) if len(arrs) > 1 else arrs[0]
                 for name, arrs in mesh.cell_data.items()}
    return VtuData(mesh.points, dict(mesh.point_data), cell_data,
                    sum(len(block.data) for block in mesh.cells))
