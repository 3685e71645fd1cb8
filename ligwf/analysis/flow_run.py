"""Flow stage over a study: flow metrics of every usable case -> ``analysis/flow.csv``.

Only cases whose manifest says ``done`` with a matching scene hash are used (the same rule
as the granule analysis, :func:`ligwf.analysis.runner.discover_cases`). Only the steady part of
the production phase counts: frames from ``steady_after`` (a fraction of the production
time) on. Outputs, written atomically:

* ``flow.csv``: one row per case with the :class:`~ligwf.analysis.flow.FlowSummary` scalars;
* ``flow_profiles.json``: per case the mean and std velocity profile along the line
  through the drum centre normal to the free surface, and the mean velocity field on a
  grid of the cross-section (for figures).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.runner import discover_cases
from ligwf.analysis.dumps import discover_frames, read_particles
from ligwf.errors import DumpReadError
from ligwf.fsio import atomic_write_json, atomic_write_text
from ligwf.analysis.flow import DrumGeometry, frame_flow, summarise, velocity_field

FLOW_FILE = "flow.csv"
PROFILES_FILE = "flow_profiles.json"


def production_start_step(scaled: dict) -> int:
    """Step at which the drum starts turning (after the fill waves and settling)."""
    return len(scaled["insertion_waves"]) * scaled["wave_steps"] + scaled["settle_steps"]


def case_flow(case_dir: Path, steady_after: float = 0.25) -> tuple[dict, dict, list[str]]:
    """(summary row, profiles, skipped-frame notes) of one case folder."""
    rec = json.loads((case_dir / "scene.json").read_text())
    scaled = rec["scaled"]
    geo = DrumGeometry.from_scaled(scaled)
    start = production_start_step(scaled)
    first = start + steady_after * scaled["run_steps"]
    frames, skipped = [], []
    for ff in discover_frames(case_dir):
        if ff.step < first:
            continue
        try:
            frames.append(read_particles(ff.particles, ff.step, scaled["dt"]))
        except DumpReadError as exc:
            skipped.append(str(exc))
    if not frames:
        raise DumpReadError(f"{case_dir}: no readable particle dump in the steady part "
                            f"(steps >= {first:.0f})")
    flows = [frame_flow(f, geo) for f in frames]
    summ = summarise(flows)
    cu, cv, mu, mv = velocity_field(frames, geo)
    row = {"case_id": rec["case_id"], "cg": rec["cg"], "rule": rec["rule"],
           "replica": rec["replica"], "group": json.dumps(rec.get("varied", {}), sort_keys=True),
           **summ.scalars()}
    prof = {"s": summ.profile_s, "v_mean": summ.profile_v_mean, "v_std": summ.profile_v_std,
            "field_u": cu.tolist(), "field_v": cv.tolist(),
            "field_vel_u": np.where(np.isfinite(mu), mu, None).tolist(),
            "field_vel_v": np.where(np.isfinite(mv), mv, None).tolist(),
            "angle_series": [f.angle_of_repose for f in flows],
            "time_series": [f.time for f in flows]}
    return row, prof, skipped


def flow_study(run_dir: Path, out_dir: Path | None = None, steady_after: float = 0.25) -> pd.DataFrame:
    """Flow metrics of every usable case of ``run_dir``; writes flow.csv and profiles."""
    run_dir = Path(run_dir)
    out_dir = Path(out_dir) if out_dir else run_dir / "analysis"
    cases, skipped_cases = discover_cases(run_dir)
    rows, profiles, notes = [], {}, {}
    for c in cases:
        try:
            row, prof, skipped = case_flow(c.case_dir, steady_after)
        except DumpReadError as exc:
            notes[c.case_id] = [str(exc)]
            continue
        rows.append(row)
        profiles[c.case_id] = prof
        if skipped:
            notes[c.case_id] = skipped
    df = pd.DataFrame(rows)
    atomic_write_text(out_dir / FLOW_FILE, df.to_csv(index=False))
    atomic_write_json(out_dir / PROFILES_FILE, {"steady_after": steady_after,
                                               "profiles": profiles, "skipped_frames": notes,
                                               "skipped_cases": skipped_cases})
    return df
