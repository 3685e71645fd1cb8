"""ParaView collections: one ``.pvd`` per case with the particles and the turning drum.

Part 0 is the particle series (the granule-labelled ``.vtu`` from the analysis stage when
it exists, else the raw dumps); part 1 is the drum mesh, rotated to its position at each
frame (omega x time since the drum started turning), so the lifters move with the bed
when the series is played.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import meshio
import numpy as np

from ligwf.scene.axis import Axis
from ligwf.study.layout import MESH_NAME
from ligwf.fsio import atomic_write_text
from ligwf.study import layout
from ligwf.study.case import CaseFolder


def rotation_matrix(axis: Axis, angle: float) -> np.ndarray:
    """Right-handed rotation by ``angle`` (rad) about +axis."""
    k = np.zeros(3)
    k[axis.index] = 1.0
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def read_stl(path: Path) -> np.ndarray:
    """Triangles (M, 3, 3) of an ASCII STL file such as the drum ligwf writes
    (:func:`ligwf.engine.mesh.stl_text`). ligwf reads its own mesh instead of meshio, whose
    STL reader first tries the binary layout and prints a numpy overflow warning on ASCII."""
    words = Path(path).read_text().split()
    coords = [words[k + 1:k + 4] for k, w in enumerate(words) if w == "vertex"]
    return np.asarray(coords, dtype=float).reshape(-1, 3, 3)


def _pvd(entries: list[tuple[float, int, str]]) -> str:
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    for t, part, f in entries:
        lines.append(f'    <DataSet timestep="{t:.9g}" group="" part="{part}" file="{f}"/>')
    lines += ["  </Collection>", "</VTKFile>", ""]
    return "\n".join(lines)


def case_collection(case: CaseFolder, frames, analysis_dir: Path, out_dir: Path) -> Path | None:
    """Write ``out_dir/<case>.pvd`` (+ rotated drum files) over ``frames`` (the frames the
    analysis planned, ``(step, dump relative to the case folder)``: missing or unexpected
    dumps left out, :attr:`ligwf.analysis.records.flow.CaseFlow.frames`); None when there
    are no frames."""
    s = case.scaled
    if not frames:
        return None
    tri_pts = read_stl(case.path / MESH_NAME)
    points = tri_pts.reshape(-1, 3)
    tri = np.arange(len(points)).reshape(-1, 3)
    case_out = out_dir / case.case_id
    case_out.mkdir(parents=True, exist_ok=True)
    entries = []
    labelled = analysis_dir / case.case_id
    for step, dump in frames:
        t = step * s.numerics.dt
        g = labelled / layout.granule_frame(step)
        particles = g if g.is_file() else case.path / dump
        entries.append((t, 0, os.path.relpath(particles, out_dir)))
        pts = points @ rotation_matrix(s.drum.axis, case.drum_angle(step)).T
        drum_file = case_out / layout.drum_frame(step)
        tmp = drum_file.with_suffix(".tmp.vtu")
        meshio.write(tmp, meshio.Mesh(pts, [("triangle", tri)]), binary=True)
        os.replace(tmp, drum_file)
        entries.append((t, 1, os.path.relpath(drum_file, out_dir)))
    path = out_dir / layout.paraview_collection(case.case_id)
    atomic_write_text(path, _pvd(entries))
    return path
