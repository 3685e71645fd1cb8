"""A dump array whose byte count disagrees with its piece says both numbers (issue 46 item
6: "decodes to 672 bytes, expected 672" named the decoded size while the byte count in
the array's header was the wrong one). Real engine dumps from ``tests/data/cg3_slice``."""

from __future__ import annotations

import base64
import re
import struct

import pytest

from helpers import ROOT
from ligwf.analysis.frames.dumps import read_particles
from ligwf.errors import DumpReadError

POST = ROOT / "tests" / "data" / "cg3_slice" / "cg3-weber-r0" / "post"


def _with_count(text: str, name: str, count: int) -> str:
    """The dump with array ``name``'s UInt32 byte count set to ``count``."""
    rx = re.compile(r'(<DataArray[^>]*Name="' + name + r'"[^>]*>\s*)(\S{8})')
    head = base64.b64encode(struct.pack("<I", count))[:6].decode()
    return rx.sub(lambda m: m.group(1) + head + m.group(2)[6:], text, count=1)


def test_a_wrong_byte_count_says_both_numbers(tmp_path):
    src = sorted(POST.glob("particles_*.vtu"))[-1]
    bad = tmp_path / src.name
    bad.write_text(_with_count(src.read_text(), "id", 892))      # 222 ids of 4 bytes: 888
    with pytest.raises(DumpReadError) as err:
        read_particles(bad)
    text = str(err.value)
    assert str(bad) in text and "array id" in text
    assert "byte count says 892 bytes" in text and "are 888" in text, text


def test_a_short_array_says_what_it_decodes_to(tmp_path):
    src = sorted(POST.glob("particles_*.vtu"))[-1]
    bad = tmp_path / src.name
    text = src.read_text()
    short = re.sub(r'(<DataArray[^>]*Name="id"[^>]*>\s*)(\S+)',
                   lambda m: m.group(1) + m.group(2)[:400] + "==", text, count=1)
    bad.write_text(short)
    with pytest.raises(DumpReadError, match=r"array id decodes to \d+ bytes, expected 888"):
        read_particles(bad)
