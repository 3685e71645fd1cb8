"""Flow stage over a study: flow metrics of every usable case -> the flow tables.

Only usable cases count (manifest ``done`` for the scene the folder holds: the same rule
as the granule analysis, :meth:`ligwf.study.study.Study.usable_cases`). Only the steady
part of the production phase counts: frames from the study's ``steady_after`` on (a
fraction of the production time, the same window the GSD uses,
:meth:`ligwf.study.case.CaseFolder.steady_start_step`; or ``auto``: from the bed's
measured spin-up, :mod:`ligwf.analysis.steady`, computed on every production frame). Frames are checked as the
granule analysis checks them (:mod:`ligwf.analysis.frame_checks`: expected steps, dump
record, particle count, ids, radii, drum); refused and missing ones are listed per case
with their reasons, never used. Outputs, written atomically
into the study's analysis folder (names in :mod:`ligwf.study.layout`):

* flow table: one row per case with the :class:`~ligwf.analysis.flow.FlowSummary` scalars;
* flow profiles: per case the mean and std velocity profile on the normalised depth
  below the free surface, the per-frame series of the steady window (angle, rigid
  fraction, rms speed, profiles: what the report's block-bootstrap intervals resample),
  the steady window used, and the mean velocity field on a grid of the cross-section.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.dumps import read_particles
from ligwf.analysis.flow import DrumGeometry, frame_flow, summarise, velocity_field
from ligwf.analysis.frame_checks import check_particles, plan_frames
from ligwf.analysis.steady import auto_fraction, is_auto
from ligwf.errors import ConfigError, DumpReadError
from ligwf.fsio import atomic_write_json, atomic_write_text
from ligwf.study import layout
from ligwf.study.case import CaseFolder
from ligwf.study.study import Study


def steady_fraction(case: CaseFolder, steady_after, flows: list) -> float:
    """The steady window as a fraction of production: the fixed setting, or for ``auto``
    the measured spin-up of the flow angle and the kinetic energy (``flows`` are the
    production frames' :class:`~ligwf.analysis.flow.FrameFlow`)."""
    if not is_auto(steady_after):
        return float(steady_after)
    dt = case.scaled.dt
    return auto_fraction(np.array([f.time for f in flows]),
                         [np.array([f.angle_of_repose for f in flows]),
                          np.array([f.kinetic_energy for f in flows])],
                         case.production_start_step * dt, case.scaled.run_steps * dt)


def _production_frames(case: CaseFolder) -> tuple[list, list, list[dict]]:
    """Checked particle frames of the production phase, their flows, and the frames
    refused or missing (``{"step", "reason"}``)."""
    geo = DrumGeometry.from_scaled(case.scaled)
    production = case.production_start_step
    plan = plan_frames(case)
    frames, flows = [], []
    problems = [p for p in plan.problems if p["step"] >= production]
    for ff in plan.frames:
        if ff.step < production:
            continue
        try:
            plan.check_record(ff)
            frame = read_particles(ff.particles, ff.step, case.scaled.dt)
            check_particles(case, frame)
        except DumpReadError as exc:
            problems.append({"step": ff.step, "reason": str(exc)})
            continue
        try:
            flow = frame_flow(frame, geo)
        except (MemoryError, KeyboardInterrupt):
            raise
        except Exception as exc:   # a frame that passed its checks and still breaks a metric
            problems.append({"step": ff.step, "reason": f"{ff.particles}: flow metrics failed "
                             f"on this frame ({type(exc).__name__}: {exc})"})
            continue
        frames.append(frame)
        flows.append(flow)
    return frames, flows, problems


def steady_start_step(case: CaseFolder, steady_after) -> int:
    """First step of the case's steady window: the fixed fraction of production, or for
    ``auto`` the measured spin-up (reads the production frames: the granule stage asks
    this before the flow stage has run)."""
    if not is_auto(steady_after):
        return case.steady_start_step(float(steady_after))
    _, flows, _ = _production_frames(case)
    return case.steady_start_step(steady_fraction(case, steady_after, flows))


def case_flow(case: CaseFolder, steady_after) -> tuple[dict, dict, list[str]]:
    """(summary row, profiles, skipped-frame notes) of one case folder; DumpReadError when
    no frame of the steady window is usable, ConfigError when its dump record is unreadable."""
    geo = DrumGeometry.from_scaled(case.scaled)
    frames, all_flows, problems = _production_frames(case)
    fraction = steady_fraction(case, steady_after, all_flows)
    first = case.steady_start_step(fraction)
    skipped = [p["reason"] for p in problems if p["step"] >= first]
    steady = [k for k, f in enumerate(frames) if f.step >= first]
    if not steady:
        raise DumpReadError(f"{case.path}: no readable particle dump in the steady part "
                            f"(steps >= {first:.0f})"
                            + (f"; first refused: {problems[-1]['reason']}" if problems else ""))
    flows = [all_flows[k] for k in steady]
    summ = summarise(flows)
    cu, cv, mu, mv = velocity_field([frames[k] for k in steady], geo)
    row = {"case_id": case.case_id, "cg": case.cg, "rule": case.rule,
           "replica": case.replica, "group": case.group, "steady_fraction": fraction,
           "steady_from_step": first, **summ.scalars()}

    def clean(values) -> list:
        return [float(x) if np.isfinite(x) else None for x in values]

    prof = {"s": summ.profile_s, "v_mean": summ.profile_v_mean, "v_std": summ.profile_v_std,
            "field_u": cu.tolist(), "field_v": cv.tolist(),
            "field_vel_u": np.where(np.isfinite(mu), mu, None).tolist(),
            "field_vel_v": np.where(np.isfinite(mv), mv, None).tolist(),
            "steady_fraction": fraction, "steady_from_step": first,
            "angle_series": clean(f.angle_of_repose for f in flows),
            "rigid_series": clean(f.rigid_fraction for f in flows),
            "rms_series": clean(f.rms_speed for f in flows),
            "v_frames": [clean(f.profile_v) for f in flows],
            "time_series": [f.time for f in flows],
            "production_times": [f.time for f in all_flows],
            "production_angles": clean(f.angle_of_repose for f in all_flows),
            "production_kinetic": clean(f.kinetic_energy for f in all_flows)}
    return row, prof, skipped


def flow_study(study: Study, out_dir: Path | None = None) -> pd.DataFrame:
    """Flow metrics of every usable case of ``study``; writes the flow tables."""
    out_dir = Path(out_dir) if out_dir else study.analysis_dir
    steady_after = study.analysis.steady_after
    cases, skipped_cases = study.usable_cases()
    rows, profiles, notes = [], {}, {}
    for c in cases:
        try:
            row, prof, skipped = case_flow(c, steady_after)
        except (DumpReadError, ConfigError) as exc:
            notes[c.case_id] = [str(exc)]
            continue
        rows.append(row)
        profiles[c.case_id] = prof
        if skipped:
            notes[c.case_id] = skipped
    df = pd.DataFrame(rows)
    atomic_write_text(out_dir / layout.FLOW_TABLE, df.to_csv(index=False))
    atomic_write_json(out_dir / layout.FLOW_PROFILES, {"steady_after": steady_after,
                                                      "profiles": profiles, "skipped_frames": notes,
                                                      "skipped_cases": skipped_cases})
    return df
