"""Drum mesh: spans exactly the periodic length, lifters where asked, readable STL, cache."""

from __future__ import annotations

import math

import meshio
import numpy as np
import pytest

from ligwf.engine.mesh import (MIN_FACET_ANGLE_DEG, MIN_SEGMENTS, cached_mesh, drum_outline, drum_stl,
                               drum_triangles, geometry_key, segment_count, shell_rows, wall_sag)
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


def _min_angle_deg(tri: np.ndarray) -> float:
    """Smallest corner angle (deg) over triangles (M, 3, 3)."""
    out = []
    for i in range(3):
        u, v = tri[:, (i + 1) % 3] - tri[:, i], tri[:, (i + 2) % 3] - tri[:, i]
        cos = np.einsum("ij,ij->i", u, v) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
        out.append(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    return float(np.min(out))


DEMO = dict(diameter=0.04, lifters={"count": 10, "height": 0.002, "width_deg": 4})


@pytest.mark.parametrize("length", [0.018, 0.036, 0.072, 0.144, 0.5])
def test_no_shell_triangle_is_thinner_than_the_engine_accepts(length):
    """LIGGGHTS refuses element angles below 0.256 deg; a 144 mm slice of the demo drum in
    one row had 0.25 deg (a real failed study). Short slices keep their one-row shell."""
    d = drum(length=length, **DEMO)
    tri = drum_triangles(d, wall_sag(0.0015))
    assert _min_angle_deg(tri) >= MIN_FACET_ANGLE_DEG - 1e-9
    rows = shell_rows(drum_outline(d, wall_sag(0.0015)), length)
    assert len(tri) == 2 * rows * len(drum_outline(d, wall_sag(0.0015)))
    assert (rows == 1) == (length <= 0.072)
    ia = d.axis.index              # rows tile [0, length] without gaps
    assert tri[..., ia].min() == 0.0 and tri[..., ia].max() == pytest.approx(length, abs=1e-15)


_MESH_ONLY = """atom_style granular
atom_modify map array sort 0 0
boundary f p f
newton off
communicate single vel yes
units si
region domain block -0.024 0.024 0 {length} -0.024 0.024 units box
create_box 2 domain
neighbor 0.0005 bin
neigh_modify delay 0
fix m1 all property/global youngsModulus peratomtype 5.e6 5.e6
fix m2 all property/global poissonsRatio peratomtype 0.3 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 2 0.5 0.5 0.5 0.5
fix m4 all property/global coefficientFriction peratomtypepair 2 0.5 0.5 0.5 0.5
pair_style gran model hertz tangential history
pair_coeff * *
timestep 1.0e-6
create_atoms 1 single 0.0 0.05 0.0 units box
set atom 1 diameter 0.0015 density 2500
fix drum all mesh/surface file drum.stl type 2
fix walls all wall/gran model hertz tangential history mesh n_meshes 1 meshes drum
fix integrate all nve/sphere
run 1
print "mesh loaded"
"""


@pytest.mark.engine
def test_the_engine_accepts_the_long_drum_it_refused_in_one_row(engine, tmp_path, monkeypatch):
    """The real engine on the 144 mm demo-drum slice: the mesh ligwf writes loads; the same
    drum in one row (the former mesh) is refused, so this test can tell them apart."""
    import ligwf.engine.mesh as mesh_mod
    from helpers import run_liggghts

    d = drum(length=0.144, axis="y", **DEMO)

    def load(folder):
        folder.mkdir()
        (folder / "drum.stl").write_text(mesh_mod.stl_text(mesh_mod.drum_triangles(
            d, wall_sag(0.0015))))
        (folder / "in.liggghts").write_text(_MESH_ONLY.format(length=0.144))
        return run_liggghts(engine, folder, nprocs=1, timeout=120)

    ok = load(tmp_path / "rows")
    assert ok.returncode == 0 and "mesh loaded" in ok.stdout, ok.stdout[-2000:]
    monkeypatch.setattr(mesh_mod, "MIN_FACET_ANGLE_DEG", 0.0)
    bad = load(tmp_path / "one_row")
    assert bad.returncode != 0 and "minumum angle" in bad.stdout, bad.stdout[-2000:]
