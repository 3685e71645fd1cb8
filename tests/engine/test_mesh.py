"""Drum mesh: spans exactly the periodic length, lifters where asked, readable STL, cache."""

from __future__ import annotations

import math

import meshio
import numpy as np
import pytest

from ligwf.engine.mesh import (MIN_SEGMENTS, cached_mesh, drum_outline, drum_stl,
                               drum_triangles, geometry_key, segment_count, wall_sag)
from ligwf.scene.model import Drum


SAG = wall_sag(0.001)   # 1 mm original beads


def drum(**kw) -> Drum:
    base = dict(diameter=0.05, length=0.018, lifters={"count": 12, "height": 0.002, "width_deg": 3})
    base.update(kw)
    return Drum.model_validate(base)


@pytest.mark.parametrize("axis,ia", [("x", 0), ("y", 1), ("z", 2)])
def test_spans_exactly_the_axial_length(axis, ia):
    tri = drum_triangles(drum(axis=axis), SAG)
    assert tri[..., ia].min() == 0.0
    assert tri[..., ia].max() == pytest.approx(0.018, abs=1e-15)
    radial = np.delete(tri, ia, axis=2)
    r = np.linalg.norm(radial, axis=2)
    assert r.max() == pytest.approx(0.025, rel=1e-12)
    assert r.min() == pytest.approx(0.023, rel=1e-9)  # lifter tips at R - h


def test_outline_has_lifters_and_is_star_shaped():
    out = drum_outline(drum(), SAG)
    r = np.linalg.norm(out, axis=1)
    inner = r < 0.025 - 1e-9
    assert inner.any()
    ang = np.unwrap(np.arctan2(out[:, 1], out[:, 0]))
    assert np.all(np.diff(ang) >= -1e-12)  # monotone angle: fan caps are valid
    # 12 lifter tops, each spanning 3 degrees at radius 23 mm
    runs = np.flatnonzero(np.diff(inner.astype(int)) == 1)
    assert len(runs) + int(inner[0]) == 12
    tops = ang[inner]
    assert math.degrees(np.ptp(tops[: np.argmax(np.diff(tops) > 0.1) + 1])) == pytest.approx(3.0, abs=1e-6)


def test_no_lifters_is_a_circle():
    out = drum_outline(drum(lifters={"count": 0}), SAG)
    assert np.linalg.norm(out, axis=1) == pytest.approx(0.025, rel=1e-12)


def test_shell_normals_point_inward():
    tri = drum_triangles(drum(lifters={"count": 0}), SAG)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    c = tri.mean(axis=1)
    c[:, 1] = 0.0
    assert np.all(np.einsum("ij,ij->i", n, -c) > 0)


def test_closed_drum_has_end_caps():
    open_tri = drum_triangles(drum(periodic=True), SAG)
    closed = drum_triangles(drum(periodic=False), SAG)
    n_out = len(drum_outline(drum(), SAG))
    # one fan triangle per outline edge, less the 2 radial sides of each of the 12 lifters
    assert len(closed) - len(open_tri) == 2 * (n_out - 2 * 12)
    n = np.cross(closed[:, 1] - closed[:, 0], closed[:, 2] - closed[:, 0])
    assert np.all(np.linalg.norm(n, axis=1) > 0)
    mesh_area = 0.5 * np.linalg.norm(np.cross(closed[:, 1] - closed[:, 0],
                                              closed[:, 2] - closed[:, 0]), axis=1)
    assert mesh_area.sum() > 2 * 0.9 * math.pi * 0.025**2


def test_stl_reads_back_with_meshio(tmp_path):
    path = tmp_path / "drum.stl"
    path.write_text(drum_stl(drum(), SAG))
    m = meshio.read(path)
    assert m.cells[0].type == "triangle"
    assert len(m.cells[0].data) == len(drum_triangles(drum(), SAG))
    assert m.points[:, 1].max() == pytest.approx(0.018)


def test_cache_is_keyed_by_geometry(tmp_path):
    a = cached_mesh(drum(), SAG, tmp_path)
    b = cached_mesh(drum(), SAG, tmp_path)
    c = cached_mesh(drum(length=0.02), SAG, tmp_path)
    assert a == b and a != c
    assert geometry_key(drum(), SAG) in a.name
    assert len(list(tmp_path.glob("*.stl"))) == 2
    # wall properties do not change the geometry, hence not the cached file
    assert geometry_key(drum(wall_friction=0.3), SAG) == geometry_key(drum(), SAG)


def test_sag_follows_the_original_particle_size_not_the_cg_level():
    # the chord sag of R (1 - cos(pi / n)) stays below 2 % of the original diameter
    for radius, d in [(0.025, 1e-3), (0.1, 1e-3), (0.1, 2e-4)]:
        n = segment_count(radius, wall_sag(d))
        assert radius * (1 - math.cos(math.pi / n)) <= 0.02 * d * (1 + 1e-12)
        assert n >= MIN_SEGMENTS
    assert segment_count(0.025, wall_sag(1e-3)) == MIN_SEGMENTS   # small drum: the floor
    assert segment_count(0.1, wall_sag(1e-3)) > MIN_SEGMENTS      # paper-scale drum
    assert segment_count(0.1, wall_sag(2e-4)) > segment_count(0.1, wall_sag(1e-3))


def test_cache_is_keyed_by_sag(tmp_path):
    assert cached_mesh(drum(), SAG, tmp_path) != cached_mesh(drum(), 2 * SAG, tmp_path)


def test_every_cg_level_of_a_study_shares_one_mesh(tmp_path):
    from ligwf.scene.workflow import load_workflow
    from ligwf.pipeline.prepare import render_workflow

    from helpers import ROOT
    wf = load_workflow(ROOT / "workflows" / "we_vs_bo.yaml", [])
    meshes = {rc.mesh_text for rc in render_workflow(wf)}
    assert len(meshes) == 1
