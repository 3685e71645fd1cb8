"""Drum mesh: an STL of the drum shell with lifters, extruded from a closed 2-D outline.

The outline is the shell circle with rectangular lifter bars cut in radially; it is
star-shaped about the axis, which makes end caps (non-periodic drums) a simple fan.
The extrusion spans exactly [0, L] along the axis, the same as the periodic box: a shorter
mesh leaks particles silently at its ends, a longer one has its elements wrapped.

STL is ASCII (LIGGGHTS' ``fix mesh/surface`` reads it; ParaView opens it). Generating the
text is pure; :func:`cached_mesh` keeps one file per geometry under a cache folder, named
by a hash of the geometry, so many cases of one study share one mesh.
"""

from __future__ import annotations

import hashlib
import json
import math
from functools import lru_cache
from pathlib import Path

import numpy as np

from ligwf.fsio import atomic_write_text
from ligwf.scene.axis import Axis
from ligwf.scene.model import Drum, Scene
from ligwf.study.layout import mesh_file

#: Bump when the mesh algorithm changes, so cached meshes are rebuilt.
MESH_VERSION = 5
#: Largest gap between a shell chord and the true circle, in smallest diameters of the
#: ORIGINAL (CG1) particles: the bumps a particle feels on the polygonal shell stay at
#: 2 % of its size at CG1 (less at CG-n, where particles are n times larger) -- below the
#: Hertz overlaps the stability check allows (5 %) and far below any lifter. One mesh per
#: drum and original size serves every CG level of a study, so CG comparisons share a wall.
SAG_FRACTION = 0.02
#: Fewest polygon segments of the full circle, whatever the sag allows.
MIN_SEGMENTS = 96
#: Smallest angle (deg) a shell triangle may have. LIGGGHTS refuses a mesh with an element
#: angle below its curvature bound (``fix mesh/surface``, 0.256 deg by default: "Bad mesh,
#: cannot continue"). One row of triangles along the axis has the angle atan(edge / length)
#: at its far corner, so a long slice fails: the 40 mm demo drum's 0.63 mm lifter-top edges
#: in a 144 mm slice gave 0.25 deg (measured). Past this bound the shell gets more rows, so
#: every drum short enough for one row (0.5 deg at 72 mm there) keeps its mesh byte for byte.
MIN_FACET_ANGLE_DEG = 0.4


def wall_sag(d_min_original: float) -> float:
    """Largest chord sag (m) of a drum filled with particles whose smallest ORIGINAL (CG1)
    diameter is ``d_min_original`` (m)."""
    return SAG_FRACTION * d_min_original


def scene_sag(scene: Scene) -> float:
    """:func:`wall_sag` of a scene (its particles as given: the original, CG1 sizes)."""
    return wall_sag(min(d for d, _ in scene.particles.size_classes()))


def segment_count(radius: float, sag: float) -> int:
    """Polygon segments for a full circle of ``radius`` so the chord sag stays below
    ``sag`` (both m); at least :data:`MIN_SEGMENTS`.

    On the 18 mm we_vs_bo drum (R 25 mm, 1 mm beads) this is the floor of 96 (the former
    rule, 2.5e-4 R, took 141: the turning CG3 step fell 0.351 -> 0.316 ms with the coarser
    shell); the paper-scale drum (R 0.1 m, 1 mm) gets 158."""
    return max(MIN_SEGMENTS, math.ceil(math.pi / math.acos(1.0 - min(sag / radius, 1.0))))


def drum_outline(drum: Drum, sag: float) -> np.ndarray:
    """Closed outline (counter-clockwise, no repeated end point) as (N, 2) array in (u, v), m;
    ``sag`` (m): see :func:`segment_count`."""
    r = drum.radius
    nseg = segment_count(r, sag)
    step = 2.0 * math.pi / nseg
    lif = drum.lifters
    if not lif.count:
        ang = np.arange(nseg) * step
        return np.column_stack([r * np.cos(ang), r * np.sin(ang)])

    half = 0.5 * math.radians(lif.width_deg)
    pitch = 2.0 * math.pi / lif.count
    inner = r - lif.height
    pts: list[tuple[float, float]] = []
    for k in range(lif.count):
        # lifter centred on -90 deg + k*pitch, so the first one starts at the bottom
        centre = -0.5 * math.pi + k * pitch
        a0, a1 = centre - half, centre + half
        pts.append((a0, r))
        n_top = max(1, math.ceil((a1 - a0) / step))
        for j in range(n_top + 1):
            pts.append((a0 + (a1 - a0) * j / n_top, inner))
        pts.append((a1, r))
        # shell arc up to the next lifter's start
        b0, b1 = a1, centre + pitch - half
        n_arc = max(1, math.ceil((b1 - b0) / step))
        for j in range(1, n_arc):
            pts.append((b0 + (b1 - b0) * j / n_arc, r))
    arr = np.array(pts)
    return np.column_stack([arr[:, 1] * np.cos(arr[:, 0]), arr[:, 1] * np.sin(arr[:, 0])])


def _to_xyz(u: np.ndarray, v: np.ndarray, w: np.ndarray, axis: Axis) -> np.ndarray:
    ia, iu, iv = axis.frame
    out = np.zeros((len(u), 3))
    out[:, ia], out[:, iu], out[:, iv] = w, u, v
    return out


def drum_triangles(drum: Drum, sag: float) -> np.ndarray:
    """Triangles (M, 3 vertices, xyz) of the shell, plus end caps when not periodic.

    Shell normals point towards the axis (into the particle space). Each outline edge
    becomes ONE pair of triangles spanning the whole length (more rows only where a
    triangle would be too thin for the engine, :func:`shell_rows`): the shell is a prism,
    so more rows would add no geometry, only cost. A turning mesh costs per facet and step (moving
    its nodes, refreshing normals and edges): on the 18 mm we_vs_bo drum, 720 facets in
    two rows took 0.26 ms of a 0.45 ms CG3 step, 360 in one row 0.19 ms; the CG1 step did
    not change (7.29 vs 7.36 ms, noise). Long triangles are exact for the engine (contact
    with a triangle is point-to-triangle distance), and LIGGGHTS ghosts mesh elements by
    their bounding radius (``cut_ghost = rBound_max + half_atom_cut`` in
    ``multi_node_mesh_parallel_I.h``), so every rank of an axial decomposition sees them.
    """
    outline = drum_outline(drum, sag)
    nxt = np.roll(outline, -1, axis=0)
    cuts = np.linspace(0.0, drum.length, shell_rows(outline, drum.length) + 1)
    tris = []
    for w_lo, w_hi in zip(cuts[:-1], cuts[1:]):
        lo, hi = np.full(len(outline), w_lo), np.full(len(outline), w_hi)
        a0 = _to_xyz(outline[:, 0], outline[:, 1], lo, drum.axis)
        b0 = _to_xyz(nxt[:, 0], nxt[:, 1], lo, drum.axis)
        a1 = _to_xyz(outline[:, 0], outline[:, 1], hi, drum.axis)
        b1 = _to_xyz(nxt[:, 0], nxt[:, 1], hi, drum.axis)
        tris += [np.stack([a0, b0, b1], axis=1), np.stack([a0, b1, a1], axis=1)]
    if not drum.periodic:
        for w in (0.0, drum.length):
            c = _to_xyz(np.zeros(len(outline)), np.zeros(len(outline)),
                        np.full(len(outline), w), drum.axis)
            a = _to_xyz(outline[:, 0], outline[:, 1], np.full(len(outline), w), drum.axis)
            b = _to_xyz(nxt[:, 0], nxt[:, 1], np.full(len(outline), w), drum.axis)
            fan = np.stack([c, a, b], axis=1)
            # the radial sides of a lifter are collinear with the centre: drop those slivers
            area2 = np.linalg.norm(np.cross(fan[:, 1] - fan[:, 0], fan[:, 2] - fan[:, 0]), axis=1)
            tris.append(fan[area2 > 1e-12 * drum.radius**2])
    tri = np.concatenate(tris)
    return _orient_inward(tri, drum)


def shell_rows(outline: np.ndarray, length: float) -> int:
    """Rows of triangles along the axis so no shell triangle has an angle below
    :data:`MIN_FACET_ANGLE_DEG` (1 for every drum whose shortest outline edge allows it)."""
    edge = float(np.min(np.linalg.norm(np.roll(outline, -1, axis=0) - outline, axis=1)))
    return max(1, math.ceil(length * math.tan(math.radians(MIN_FACET_ANGLE_DEG)) / edge))


def _orient_inward(tri: np.ndarray, drum: Drum) -> np.ndarray:
    """Flip triangles whose normal points away from the drum interior."""
    ia, iu, iv = drum.axis.frame
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    centroid = tri.mean(axis=1)
    inward = np.zeros_like(centroid)
    inward[:, iu] = -centroid[:, iu]
    inward[:, iv] = -centroid[:, iv]
    # caps: interior is towards the mid-plane along the axis
    is_cap = np.abs(n[:, ia]) > 0.5 * np.linalg.norm(n, axis=1)
    inward[is_cap] = 0.0
    inward[is_cap, ia] = 0.5 * drum.length - centroid[is_cap, ia]
    flip = np.einsum("ij,ij->i", n, inward) < 0
    tri = tri.copy()
    tri[flip] = tri[flip][:, ::-1]
    return tri


def stl_text(triangles: np.ndarray, name: str = "drum") -> str:
    """ASCII STL of triangles (M, 3, 3)."""
    n = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    lines = [f"solid {name}"]
    for t, nn in zip(triangles, n):
        lines.append(f"  facet normal {nn[0]:.9e} {nn[1]:.9e} {nn[2]:.9e}")
        lines.append("    outer loop")
        for p in t:
            lines.append(f"      vertex {p[0]:.12e} {p[1]:.12e} {p[2]:.12e}")
        lines.append("    endloop")
        lines.append("  endfacet")
    lines.append(f"endsolid {name}")
    return "\n".join(lines) + "\n"


def geometry_key(drum: Drum, sag: float) -> str:
    """Short content hash of everything the mesh depends on."""
    geo = {"v": MESH_VERSION, "sag": sag, "diameter": drum.diameter, "length": drum.length,
           "axis": drum.axis, "periodic": drum.periodic, "lifters": drum.lifters.model_dump()}
    return hashlib.sha256(json.dumps(geo, sort_keys=True).encode()).hexdigest()[:16]


@lru_cache(maxsize=32)
def drum_stl(drum: Drum, sag: float) -> str:
    """The drum's STL text (pure; memoised per geometry)."""
    return stl_text(drum_triangles(drum, sag), name=f"ligwf_drum_{geometry_key(drum, sag)}")


def mesh_file_name(drum: Drum, sag: float) -> str:
    return mesh_file(geometry_key(drum, sag))


def cache_problem(drum: Drum, sag: float, cache_dir: Path) -> str | None:
    """Why the drum's STL in ``cache_dir`` cannot be used as it is (None: absent, so it
    is generated, or the very mesh): :func:`cached_mesh` writes it again, and the command
    line says so before anything is written."""
    path = Path(cache_dir) / mesh_file_name(drum, sag)
    want = drum_stl(drum, sag).encode()
    try:
        have = path.read_bytes()
    except (FileNotFoundError, IsADirectoryError, NotADirectoryError):
        return None
    if have == want:
        return None
    if len(have) < len(want) and want.startswith(have):
        return (f"mesh cache: {path} is truncated ({len(have):,} of {len(want):,} bytes; a "
                "copy or write cut short): written again before a case uses it")
    return (f"mesh cache: {path} is not the mesh its name stands for ({len(have):,} bytes, "
            f"the mesh has {len(want):,}: edited, damaged or another mesh version): written "
            "again before a case uses it")


def cached_mesh(drum: Drum, sag: float, cache_dir: Path) -> Path:
    """Path of the drum's STL in ``cache_dir``, generated on first use. A cached file is
    checked against the mesh it must hold (generating the text is pure and quick) before
    it is used: one truncated, edited or of another mesh version is written again, so a
    damaged cache never reaches a case (where it would show up as lost atoms)."""
    path = Path(cache_dir) / mesh_file_name(drum, sag)
    text = drum_stl(drum, sag)
    try:
        same = path.read_bytes() == text.encode()
    except (FileNotFoundError, IsADirectoryError):
        same = False
    if not same:
        atomic_write_text(path, text)
    return path
