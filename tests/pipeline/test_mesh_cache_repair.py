"""A damaged drum mesh in ``--mesh-cache`` is repaired with a line (issue 46 item 6): a
truncated or edited STL is named, written again before a case uses it, and every case
folder holds the drum mesh its scene asks for."""

from __future__ import annotations

import pytest

from helpers import ROOT
from ligwf.cli.main import main
from ligwf.study import layout

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


@pytest.mark.parametrize("damage,said", [
    (lambda data: data[:5000], "is truncated (5,000 of"),
    (lambda data: data.replace(b"vertex", b"vertey", 1), "is not the mesh its name stands for"),
])
def test_a_damaged_cached_mesh_is_named_and_written_again(tmp_path, capsys, damage, said):
    cache = tmp_path / "meshes"
    assert main(["render", str(TINY), "--out", str(tmp_path / "first"), "--mesh-cache",
                 str(cache)]) == 0
    (stl,) = cache.glob("*.stl")
    good = stl.read_bytes()
    stl.write_bytes(damage(good))
    capsys.readouterr()
    out = tmp_path / "second"
    assert main(["render", str(TINY), "--out", str(out), "--mesh-cache", str(cache)]) == 0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if "mesh cache" in ln]
    assert len(lines) == 1 and said in lines[0] and str(stl) in lines[0], lines
    assert "written again" in lines[0]
    assert stl.read_bytes() == good
    for case in ("cg3-weber-r0", "cg3-bond-r0"):
        assert (out / case / layout.MESH_NAME).read_bytes() == good
    capsys.readouterr()
    assert main(["render", str(TINY), "--out", str(out), "--mesh-cache", str(cache)]) == 0
    assert "mesh cache" not in capsys.readouterr().err          # repaired: nothing to say
