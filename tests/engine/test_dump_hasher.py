"""ligwf.engine.dump_hasher: dumps hashed while the engine runs, used only while unchanged.

Files here are written by the test in LIGGGHTS' naming and ending (``</VTKFile>``); the
real engine path (a case run through ``ligwf run``) is benchmarks/bench_hashing.py and the
engine tests of the runner, whose done records these digests now fill.
"""

from __future__ import annotations

import hashlib
import os
import time

from ligwf.engine.dump_hasher import DumpHasher, complete_dumps
from ligwf.fsio import file_sha256 as file_digest
from ligwf.study.case import NO_DIGESTS


def _dump(post, name: str, body: bytes = b"x" * 1000, whole: bool = True):
    path = post / name
    path.write_bytes(b"<VTKFile>" + body + (b"</VTKFile>\n" if whole else b""))
    return path


def test_a_dump_is_complete_once_a_later_step_of_its_series_exists(tmp_path):
    for step in (100, 200, 300):
        _dump(tmp_path, f"particles_{step}.vtu")
    _dump(tmp_path, "contacts_100.vtu")
    _dump(tmp_path, "contacts_200.vtu", whole=False)       # cut: not complete
    _dump(tmp_path, "contacts_300.vtu")
    (tmp_path / "notes.txt").write_text("not a dump")
    names = [p.name for p in complete_dumps(tmp_path)]
    assert names == ["contacts_100.vtu", "particles_100.vtu", "particles_200.vtu"]


def test_hashed_digests_are_the_files_and_used_only_while_unchanged(tmp_path):
    a = _dump(tmp_path, "particles_100.vtu", b"a" * 5000)
    b = _dump(tmp_path, "particles_200.vtu", b"b" * 5000)
    _dump(tmp_path, "particles_300.vtu")
    hasher = DumpHasher(tmp_path)
    assert hasher.hash_pending() == 2
    assert hasher.hash_pending() == 0                     # each once
    digests = hasher.digests
    assert digests.files[a.name][1] == hashlib.sha256(a.read_bytes()).hexdigest()
    # an unchanged file: the kept digest, without reading it (a file made unreadable
    # would fail a hash: the digest must come from the table)
    os.chmod(b, 0)
    try:
        if not os.access(b, os.R_OK):                     # (root reads anything)
            assert digests.digest(b) == digests.files[b.name][1]
    finally:
        os.chmod(b, 0o644)
    # edited after hashing (same size): another modification time -> hashed again
    time.sleep(0.01)
    a.write_bytes(a.read_bytes().replace(b"aaaa", b"aaab", 1))
    assert digests.digest(a) == file_digest(a) != digests.files[a.name][1]
    # replaced by another file (new inode): hashed again
    b.rename(tmp_path / "old")
    _dump(tmp_path, "particles_200.vtu", b"c" * 5000)
    assert digests.digest(b) == file_digest(b)
    assert NO_DIGESTS.digest(b) == file_digest(b)


def test_background_thread_hashes_while_files_appear(tmp_path):
    with DumpHasher(tmp_path, poll_seconds=0.01) as hasher:
        for step in range(5):
            _dump(tmp_path, f"particles_{step * 10}.vtu", bytes([65 + step]) * 3000)
        deadline = time.monotonic() + 30
        while len(hasher.digests.files) < 4 and time.monotonic() < deadline:
            time.sleep(0.02)
    assert sorted(hasher.digests.files) == [f"particles_{s}.vtu" for s in (0, 10, 20, 30)]
    for name, (_, digest) in hasher.digests.files.items():
        assert digest == file_digest(tmp_path / name)
