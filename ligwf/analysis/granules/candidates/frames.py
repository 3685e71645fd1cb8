"""A case's frames as the candidate definitions read them: every capillary bridge of every
production dump with its relative force and rupture work, and the cosine of the angle
between its two particles' velocities in the lab frame, the drum frame and against the local
flow (see :mod:`ligwf.analysis.granules.candidates` for the definitions)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from ligwf import liquids
from ligwf.analysis.frames.dumps import discover_frames, read_contacts, read_particles
from ligwf.analysis.granules.bridge_law import Liquid, relative_energy
from ligwf.errors import ConfigError
from ligwf.study.case import CaseFolder


def capillary(model, *args):
    """The registered liquid model's capillary bridge force (ligwf.liquids registry)."""
    return liquids.get(model).capillary_force(*args)


@dataclass
class Frame:
    step: int
    n: int
    ids: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    radii: np.ndarray
    vprim: np.ndarray        # particle volume, m^3 (physical: NOT divided by n^3, see below)
    i: np.ndarray            # bridged pairs (rows), F > 0
    j: np.ndarray
    dy: np.ndarray           # minimum-image displacement y_j - y_i along the axis, m
    force: np.ndarray        # N
    frel: np.ndarray         # F / (2 pi R* gamma cos theta)
    erel: np.ndarray         # rupture work / (F0 R*) (ligwf.analysis.granules.bridge_law.relative_energy)
    keys: np.ndarray         # id1 * big + id2 (id1 < id2), for persistence
    cos: dict                # velocity frame -> cos(angle) per bridge (1 for zero speed)


@dataclass
class Case:
    path: Path
    cg: float
    rule: str
    length: float
    axis: int
    omega: float
    liquid_content: float
    diameter: float
    frames: list             # all production frames, in step order
    steady: list             # indices into frames


def _cos(vi, vj):
    dot = np.einsum("ij,ij->i", vi, vj)
    nn = np.sqrt(np.einsum("ij,ij->i", vi, vi) * np.einsum("ij,ij->i", vj, vj))
    out = np.ones(len(dot))
    ok = nn > 0
    out[ok] = dot[ok] / nn[ok]
    return out

def load_case(path: Path, steady_fraction: float, flow_radii=(3.0,)) -> Case:
    """The production frames of the case folder ``path`` (the dumps after the settle runs,
    with contacts), its steady ones those after the first ``steady_fraction`` of the
    rendered production; ConfigError for a drum not along y."""
    folder = CaseFolder.open(path)
    s = folder.rendered_scaled
    axis = s.drum.axis.index
    if axis != 1:
        raise ConfigError(f"{path}: drum axis {s.drum.axis.value!r}: only drums along y are handled")
    length = float(s.drum.length)
    omega = float(s.drum.omega)
    lv = s.liquid_values
    theta = math.radians(float(lv.contact_angle_deg))   # compensated input: engine applies it
    gamma = float(lv.surface_tension)
    model = lv.model
    run = int(s.numerics.run_steps)
    # production starts with the first dump (the dumps are defined after the settle runs)
    files = [f for f in discover_frames(path) if f.contacts is not None]
    frames = []
    big = 10 ** 7
    for f in files:
        p = read_particles(f.particles)
        c = read_contacts(f.contacts)
        i, j = p.index_of(c.id1), p.index_of(c.id2)
        content = p.liquid_content if p.liquid_content is not None else np.full(len(p), lv.liquid_content)
        gap = -c.delta
        F = np.asarray(capillary(model, p.radii[i], p.radii[j], gap, gamma, theta,
                                 content[i], content[j]), float)
        keep = F > 0
        i, j, F = i[keep], j[keep], F[keep]
        reff = p.radii[i] * p.radii[j] / (p.radii[i] + p.radii[j])
        frel = F / (2 * math.pi * reff * gamma * math.cos(theta))
        erel = relative_energy(p, i, j, gap[keep], Liquid(model, gamma, theta, float(lv.liquid_content)))
        y = p.positions[:, 1]
        d = y[j] - y[i]
        dy = d - length * np.round(d / length)
        lo, hi = np.minimum(p.ids[i], p.ids[j]), np.maximum(p.ids[i], p.ids[j])
        frames.append(Frame(f.step, len(p), p.ids, p.positions, p.velocities, p.radii,
                            p.volumes, i, j, dy, F, frel, erel,
                            lo * big + hi, {}))
    case = Case(path, float(folder.cg), str(folder.rule), length, axis, omega,
                float(lv.liquid_content), float(np.mean(frames[0].radii) * 2) if frames else 0.0,
                frames, [])
    t0 = frames[0].step + steady_fraction * run
    case.steady = [k for k, fr in enumerate(frames) if fr.step >= t0]
    _velocity_frames(case, flow_radii)
    return case


def _velocity_frames(case: Case, flow_radii=(3.0,)) -> None:
    """cos(angle) per bridge in the lab frame, the drum frame and against the local flow."""
    L = case.length
    for fr in case.frames:
        v, r = fr.vel, fr.pos
        fr.cos["lab"] = _cos(v[fr.i], v[fr.j])
        # rigid rotation about +y (fix move/mesh rotate axis 0 1 0, period > 0): omega y x r
        wr = case.omega * np.stack([r[:, 2], np.zeros(len(r)), -r[:, 0]], axis=1)
        vr = v - wr
        fr.cos["rot"] = _cos(vr[fr.i], vr[fr.j])
        # local mean flow within 3 diameters, periodic along y
        box = 1.0
        pts = np.stack([r[:, 0] + 0.5 * box, np.mod(r[:, 1], L), r[:, 2] + 0.5 * box], axis=1)
        tree = cKDTree(pts, boxsize=[box, L, box])
        for rad in flow_radii:
            nb = tree.query_ball_point(pts, rad * case.diameter)
            mean = np.empty_like(v)
            for a, lst in enumerate(nb):
                mean[a] = v[lst].mean(axis=0)
            vf = v - mean
            fr.cos["flow" if rad == 3.0 else f"flow@{rad:g}"] = _cos(vf[fr.i], vf[fr.j])


def rotation_check(case: Case) -> tuple[float, float]:
    """Mean |v - omega x r| / mean |v| over steady frames for +omega and -omega (the
    right sign makes the bed nearly still in the drum frame)."""
    out = []
    for sign in (1.0, -1.0):
        num = den = 0.0
        for k in case.steady:
            fr = case.frames[k]
            r = fr.pos
            wr = sign * case.omega * np.stack([r[:, 2], np.zeros(len(r)), -r[:, 0]], axis=1)
            num += np.linalg.norm(fr.vel - wr, axis=1).mean()
            den += np.linalg.norm(fr.vel, axis=1).mean()
        out.append(num / den)
    return out[0], out[1]

