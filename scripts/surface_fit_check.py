"""Angle of repose of a finished case: ligwf's estimator next to an independent fit.

Independent fit: the solid volume fraction on a grid of d x d cells of the cross-section
(particle volumes over cell area x slice length), the free surface in each vertical column
where that fraction falls through half its bulk value (linear interpolation), and a plain
least-squares line through the columns of the central half of the drum (|u| < R / 2).
It shares no step with ligwf.analysis.flow.surface (no strip tops, no centre-of-mass guess, no
outlier rejection). Usage: python scripts/surface_fit_check.py CASE_DIR [CASE_DIR ...]
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from ligwf.analysis.frames.dumps import read_particles
from ligwf.analysis.flow.frame import DrumGeometry, cross_section, frame_flow, rising_side
from ligwf.analysis.flow.stage import steady_fraction
from ligwf.analysis.frames.checks import plan_frames
from ligwf.analysis.flow.steady import AUTO
from ligwf.study.case import CaseFolder


def density_surface_angle(frame, geo: DrumGeometry, length: float) -> float:
    """Signed surface angle (deg) from the half-bulk contour of the volume fraction."""
    u, v, _, _ = cross_section(frame, geo)
    cell = geo.d_mean
    edges = np.arange(-geo.radius, geo.radius + cell, cell)
    vol, _, _ = np.histogram2d(u, v, [edges, edges], weights=frame.volumes)
    phi = vol / (cell * cell * length)
    bulk = np.median(phi[phi > 0.5 * phi.max()])
    centres = 0.5 * (edges[:-1] + edges[1:])
    us, vs = [], []
    for i, uc in enumerate(centres):
        if abs(uc) > 0.5 * geo.radius:
            continue
        col = phi[i]
        full = np.flatnonzero(col > 0.5 * bulk)
        if not len(full) or full[-1] + 1 >= len(col):
            continue
        k = full[-1]
        f = (col[k] - 0.5 * bulk) / (col[k] - col[k + 1])
        us.append(uc)
        vs.append(centres[k] + f * cell)
    a, _ = np.polyfit(us, vs, 1)
    return math.degrees(math.atan(a)) * rising_side(geo)


def main(paths: list[str]) -> None:
    for p in paths:
        case = CaseFolder.open(Path(p))
        geo = DrumGeometry.from_scaled(case.scaled)
        rows = []
        for ff in plan_frames(case).frames:
            if ff.step < case.production_start_step:
                continue
            fr = read_particles(ff.particles, ff.step, case.scaled.numerics.dt)
            rows.append((fr.time, frame_flow(fr, geo),
                         density_surface_angle(fr, geo, case.scaled.drum.length)))
        fraction = steady_fraction(case, AUTO, [f for _, f, _ in rows])
        first = case.steady_start_step(fraction)
        steady = [(f.angle_of_repose, d) for _, f, d in rows if f.step >= first]
        ours, indep = np.array(steady).T
        print(f"{case.case_id}: steady_after auto = {fraction:.2f} of production, "
              f"{len(ours)} steady frames; ligwf {np.nanmean(ours):.2f} +- "
              f"{np.nanstd(ours):.2f} deg; independent {np.mean(indep):.2f} +- "
              f"{np.std(indep):.2f} deg; mean frame difference {np.nanmean(ours - indep):+.2f} "
              f"deg (median {np.nanmedian(ours - indep):+.2f})")


if __name__ == "__main__":
    main(sys.argv[1:])
