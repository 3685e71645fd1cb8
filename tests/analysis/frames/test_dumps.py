"""ligwf.analysis.frames.dumps on real LIGGGHTS output: reading, conventions, and every kind of bad file."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import meshio
import numpy as np
import pytest

from ligwf.analysis.frames.dumps import discover_frames, read_contacts, read_particles
from ligwf.errors import DumpReadError
from wetdump import wet_study


@pytest.fixture(scope="module")
def case(engine, tmp_path_factory) -> Path:
    return wet_study(engine, tmp_path_factory) / "cg3-weber-r0"


@pytest.fixture(scope="module")
def frame(case):
    return discover_frames(case)[-1]


@pytest.mark.engine
@pytest.mark.mpi
def test_frames_discovered_by_step(case):
    frames = discover_frames(case)
    steps = [f.step for f in frames]
    assert len(frames) >= 3 and steps == sorted(steps)
    assert all(f.contacts is not None and f.contacts.name == f"contacts_{f.step}.vtu"
               for f in frames)
    # the bounding-box files LIGGGHTS writes next to each dump are not frames
    assert not any("boundingBox" in f.particles.name for f in frames)


@pytest.mark.engine
@pytest.mark.mpi
def test_real_frame_arrays(case, frame):
    p = read_particles(frame.particles, dt=2.0e-5)
    c = read_contacts(frame.contacts)
    assert len(p) == 222 and np.all(np.diff(p.ids) > 0)
    assert p.time == pytest.approx(frame.step * 2.0e-5)
    assert p.positions.shape == (222, 3) and p.velocities.shape == (222, 3)
    np.testing.assert_allclose(p.radii, 0.0015)                    # 1 mm x CG3 / 2
    np.testing.assert_allclose(p.liquid_content, 0.02, rtol=0.5)   # fraction, not %
    assert len(c) > 200 and np.all(c.id1 < c.id2)
    assert np.isin(c.id1, p.ids).all() and np.isin(c.id2, p.ids).all()
    assert (c.delta < 0).any(), "non-touching liquid bridges are listed"
    # delta is the overlap r_i + r_j - |x_i - x_j| (checked where the pair does not wrap)
    i, j = p.index_of(c.id1), p.index_of(c.id2)
    dist = np.linalg.norm(p.positions[i] - p.positions[j], axis=1)
    inside = dist < 1.5 * (p.radii[i] + p.radii[j])   # a wrapped pair spans ~ the box (9 mm)
    assert inside.sum() > 100 and (~inside).sum() > 0, "some pairs cross the periodic axis"
    np.testing.assert_allclose((p.radii[i] + p.radii[j] - dist)[inside], c.delta[inside],
                               atol=2e-8)   # float32 points


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("binary", [True, False])
def test_roundtrip_through_meshio(frame, tmp_path, binary):
    p = read_particles(frame.particles)
    m = meshio.read(frame.particles)
    out = tmp_path / f"particles_{frame.step}.vtu"
    meshio.write(out, m, file_format="vtu", binary=binary)
    q = read_particles(out)
    assert q.step == p.step
    for name in ("ids", "types", "positions", "velocities", "radii", "liquid_content"):
        # meshio's ASCII writer prints a limited number of digits
        np.testing.assert_allclose(getattr(q, name), getattr(p, name), rtol=0 if binary else 1e-7)


def _bad(src: Path, dst_dir: Path, edit) -> Path:
    dst = dst_dir / src.name
    text = src.read_text()
    dst.write_text(edit(text))
    return dst


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("kind, edit, message", [
    ("truncated", lambda t: t[: len(t) // 2], "not a readable VTU"),
    ("corrupt base64", lambda t: re.sub(r"(<DataArray[^>]*Name=\"v\"[^>]*>\s*)\S{40}",
                                        lambda m: m.group(1) + "!" * 40, t, count=1),
     "not a readable VTU"),
    ("missing radius", lambda t: re.sub(r"<DataArray[^>]*Name=\"radius\".*?</DataArray>", "",
                                        t, flags=re.S), "lacks the array(s) radius"),
    ("empty", lambda t: "", "empty"),
    ("not xml", lambda t: "hello\n", "not a readable VTU"),
])
@pytest.mark.parametrize("reader", ["fast", "meshio"])
def test_bad_particle_dump(frame, tmp_path, kind, edit, message, reader):
    bad = _bad(frame.particles, tmp_path, edit)
    with pytest.raises(DumpReadError, match=re.escape(message)) as err:
        read_particles(bad, reader=reader)
    assert str(bad) in str(err.value), "the error names the file"


@pytest.mark.engine
@pytest.mark.mpi
def test_zero_particles(frame, tmp_path):
    m = meshio.read(frame.particles)
    empty = meshio.Mesh(np.zeros((0, 3)), [("vertex", np.zeros((0, 1), dtype=int))],
                        point_data={k: v[:0] for k, v in m.point_data.items()})
    path = tmp_path / "particles_5.vtu"
    meshio.write(path, empty, file_format="vtu")
    with pytest.raises(DumpReadError, match="zero particles") as err:
        read_particles(path)
    assert str(path) in str(err.value)


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("kind, edit, message", [
    ("truncated", lambda t: t[: 2 * len(t) // 3], "not a readable VTU"),
    ("missing id2", lambda t: re.sub(r"<DataArray[^>]*Name=\"id2\".*?</DataArray>", "", t,
                                     flags=re.S), "lacks the array(s) id2"),
    ("missing delta", lambda t: re.sub(r"<DataArray[^>]*Name=\"delta\".*?</DataArray>", "", t,
                                       flags=re.S), "lacks the array(s) delta"),
])
def test_bad_contact_dump(frame, tmp_path, kind, edit, message):
    bad = _bad(frame.contacts, tmp_path, edit)
    with pytest.raises(DumpReadError, match=re.escape(message)) as err:
        read_contacts(bad)
    assert str(bad) in str(err.value)


def test_missing_file(tmp_path):
    with pytest.raises(DumpReadError, match="does not exist"):
        read_particles(tmp_path / "particles_1.vtu")


@pytest.mark.engine
@pytest.mark.mpi
def test_contact_to_unknown_particle(frame, tmp_path):
    p = read_particles(frame.particles)
    c = read_contacts(frame.contacts)
    with pytest.raises(DumpReadError, match="no particle with id 99999"):
        p.index_of(np.append(c.id1, 99999))


def test_empty_contact_frame_is_valid(tmp_path):
    """A dump step without any interacting pair (LIGGGHTS writes an empty piece)."""
    path = tmp_path / "contacts_7.vtu"
    path.write_text('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" '
                    'byte_order="LittleEndian" header_type="UInt32">\n  <UnstructuredGrid>\n'
                    '    <Piece NumberOfPoints="0" NumberOfCells="0">\n    </Piece>\n'
                    '  </UnstructuredGrid>\n</VTKFile>\n')
    c = read_contacts(path)
    assert len(c) == 0 and c.step == 7


@pytest.mark.engine
@pytest.mark.mpi
def test_fast_reader_equals_meshio(case):
    """The direct base64 decoder (fast path) gives meshio's arrays (the reference)."""
    for f in discover_frames(case):
        for read, path in ((read_particles, f.particles), (read_contacts, f.contacts)):
            fast, ref = read(path), read(path, reader="meshio")
            for name, value in vars(fast).items():
                if isinstance(value, np.ndarray):
                    other = getattr(ref, name)
                    assert value.dtype == other.dtype, name
                    np.testing.assert_array_equal(value, other, err_msg=name)


# --- the compiled helpers and the direct decoder on files of every layout (no engine) ---

import base64
import binascii

from hypothesis import given, settings, strategies as st

from ligwf.analysis.dumps_numba import decode_base64, first_of_each_pair


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=300), st.sampled_from([4, 8]))
def test_decode_base64_equals_binascii(payload, header_size):
    header = len(payload).to_bytes(header_size, "little")
    text = base64.b64encode(header + payload)
    out = decode_base64(text, header_size)
    assert out is not None and out.tobytes() == binascii.a2b_base64(text)
    if payload:     # (numpy does not offset the pointer of an empty slice)
        assert out[header_size:].ctypes.data % 8 == 0, "data after the header is 8-byte aligned"


@pytest.mark.parametrize("text", [
    base64.b64encode(b"\x04\x00\x00\x00") + base64.b64encode(b"abcd"),   # header block apart
    base64.b64encode(b"\x08\x00\x00\x00abcdefgh")[:-1],                   # truncated
    b"AAAA\nAAAA",                                                        # line break
    b"AAAA!!!!",                                                          # corrupt
])
def test_decode_base64_declines_what_it_does_not_handle(text):
    assert decode_base64(text, 4) is None      # the reader then falls back to binascii


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.integers(1, 30), st.integers(1, 30)), max_size=80))
def test_first_of_each_pair_equals_unique(pairs):
    pairs = [(a, b) for a, b in pairs if a != b]
    lo = np.array([min(p) for p in pairs], dtype=np.int64)
    hi = np.array([max(p) for p in pairs], dtype=np.int64)
    got = first_of_each_pair(lo, hi)
    first = np.sort(np.unique(lo * 31 + hi, return_index=True)[1]) if len(lo) else np.zeros(0, int)
    if len(first) == len(lo):
        assert got is None
    else:
        np.testing.assert_array_equal(got, first)


def _contact_mesh(n: int = 50, m: int = 120, seed: int = 3):
    """A contact dump in LIGGGHTS' arrays, with some pairs listed twice (as by two ranks)."""
    rng = np.random.default_rng(seed)
    a = rng.integers(1, n + 1, m)
    b = (a + rng.integers(0, n - 1, m)) % n + 1
    a[-10:], b[-10:] = b[:10], a[:10]            # the first 10 pairs again, reversed
    pts = rng.uniform(0, 0.01, (2 * m, 3)).astype(np.float32)
    lines = np.column_stack([np.arange(m), np.arange(m) + m])
    cell_data = {"vel1": [rng.normal(size=(m, 3))], "vel2": [rng.normal(size=(m, 3))],
                 "id1": [a.astype(float)], "id2": [b.astype(float)],
                 "force": [rng.normal(size=(m, 3))], "delta": [rng.uniform(-1e-4, 1e-5, m)]}
    return meshio.Mesh(pts, [("line", lines)], cell_data=cell_data)


@pytest.mark.parametrize("compression", [None, "zlib"])
@pytest.mark.parametrize("header_type", ["UInt32", "UInt64"])
def test_fast_contacts_equal_meshio_on_meshio_files(tmp_path, compression, header_type):
    """meshio's layout (Points and Cells before the data, any header type; zlib goes to
    meshio): the fast reader gives the reference arrays, duplicates dropped once."""
    path = tmp_path / "contacts_10.vtu"
    meshio.write(path, _contact_mesh(), file_format="vtu", binary=True,
                 compression=compression, header_type=header_type)
    fast, ref = read_contacts(path), read_contacts(path, reader="meshio")
    assert len(fast) == len(ref) <= 110       # the 10 pairs listed twice are kept once
    for name in ("id1", "id2", "delta"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(ref, name), err_msg=name)
        assert getattr(fast, name).dtype == getattr(ref, name).dtype


def test_fast_reader_header_in_its_own_block(tmp_path):
    """VTK may encode the byte-count header as its own base64 block: still decoded."""
    path = tmp_path / "contacts_11.vtu"
    meshio.write(path, _contact_mesh(), file_format="vtu", binary=True, compression=None)
    text = path.read_text()

    def split(match):
        raw = base64.b64decode(match.group(2))
        return match.group(1) + (base64.b64encode(raw[:4]) + base64.b64encode(raw[4:])).decode()

    text = re.sub(r'(<DataArray[^>]*Name="delta"[^>]*>\s*)([A-Za-z0-9+/=]+)', split, text)
    path.write_text(text)
    fast, ref = read_contacts(path), read_contacts(path, reader="meshio")
    np.testing.assert_array_equal(fast.delta, ref.delta)
