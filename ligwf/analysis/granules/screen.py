"""The registered granule screen (docs/results/granule_screen/criterion.md, committed before
the runs): phase 1 scores one seed of each condition on four registered points and picks
the best by the registered rule (:func:`condition_row`, :func:`ranked`); phase 2 runs the
pick on :data:`SEEDS` seeds, each beside its cohesionless twin and a uniform twin, and
judges it by the registered per-seed criteria, >= 4 of 5 seeds (:func:`phase2_seeds`,
:func:`phase2_verdict`). Pure: growth rows and frame flows in
(:func:`ligwf.analysis.granules.growth_study.measure_case`), tables out;
:mod:`ligwf.analysis.granules.screen_study` measures the screen's runs and
``scripts/granule_screen_results.py`` writes the folder.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ligwf.analysis.granules.growth import GrowthSettings, hac_slope
from ligwf.analysis.granules.growth_study import CRITERIA, Criteria, seed_table

#: the registered settings: W = 1.3 s, start frames every 0.1 s from W
SETTINGS = GrowthSettings(hold_time=1.3, cadence=0.05, stride=0.1, start_after=1.3)
#: the tie-break reads share_10 over the last this many revolutions
LAST_REVOLUTIONS = 10.0
#: phase 1's registered points: (column, what it asks)
POINTS = (("exists", "share_10 >= 0.02"), ("survives", "mean survival >= 0.5"),
          ("grows", "share_10 slope's 95 % interval above 0"),
          ("comoves", "mean co-movement ratio <= 0.5"))
#: phase 2's registered seeds r0..r4
SEEDS = 5
#: the registered phase-2 pass (criteria 1-3 and 6) and the two reported beside it
REGISTERED = ("pass_control", "pass_survival", "pass_growth", "pass_comovement")
REPORTED = ("pass_no_spanning", "pass_not_wall")


def condition_row(name: str, model: str, liquid: str, rows: pd.DataFrame, flows: pd.DataFrame,
                  status: str, core_s: float, reason: str = "",
                  criteria: Criteria = Criteria()) -> dict:
    """Phase 1's row of condition ``name`` (its liquid ``model`` and how the ``liquid`` is
    placed, as the screen names them): its run's status and core-minutes, its measures
    over the growth ``rows`` and frame ``flows``, each registered point (a run that did not
    finish scores none) and the points (none for a bed bound into one spanning wet mass,
    amendment 1)."""
    out = {"condition": name, "model": model, "liquid": liquid, "status": status,
           "reason": "" if status == "done" else reason,
           "core_minutes": core_s / 60.0, "start_frames": len(rows)}
    if rows.empty:
        return {**out, **{p: False for p, _ in POINTS}, "wet_mass": False, "points": 0}
    lag = int(round(SETTINGS.hold_time / SETTINGS.stride)) + 1
    slope = hac_slope(rows["time"].to_numpy(), rows["share_10"].to_numpy(), lag)
    last = rows[rows.revolutions >= rows.revolutions.max() - LAST_REVOLUTIONS]
    out.update({
        "share_10": rows.share_10.mean(), "share_10_last": last.share_10.mean(),
        "share_10_first_rev": rows[rows.revolutions < rows.revolutions.min() + 1.0].share_10.mean(),
        "d50_particles": rows.d50_particles.mean(), "largest": int(rows.largest.max()),
        "survival": rows.survival.mean(), "comove_ratio": rows.comove_ratio.mean(),
        "slope_per_s": slope.slope, "slope_low": slope.low, "slope_high": slope.high,
        "spanning_frames": rows.spanning.astype(float).mean(),
        "wall_share": rows.wall_share.mean(), "bed_wall_share": rows.bed_wall_share.mean(),
        "wet_share_start": float(flows.sort_values("time").wet_share.iloc[0]),
        "wet_share_end": float(flows.sort_values("time").wet_share.iloc[-1]),
        "angle_deg": flows[flows.time >= SETTINGS.hold_time].angle_of_repose.mean(),
        "revolutions": float(rows.revolutions.max())})
    ok = status == "done"
    out["exists"] = bool(ok and out["share_10"] >= criteria.min_share)
    out["survives"] = bool(ok and np.isfinite(out["survival"])
                           and out["survival"] >= criteria.survival)
    out["grows"] = bool(ok and np.isfinite(out["slope_low"]) and out["slope_low"] > 0.0)
    out["comoves"] = bool(ok and np.isfinite(out["comove_ratio"])
                          and out["comove_ratio"] <= criteria.comove_ratio)
    # amendment 1: a bed bound into one wet mass that spans the slice is not granules
    out["wet_mass"] = bool(out["spanning_frames"] > criteria.spanning_frames)
    out["points"] = 0 if out["wet_mass"] else int(sum(out[p] for p, _ in POINTS))
    return out


def ranked(table: pd.DataFrame) -> pd.DataFrame:
    """The registered pick: most points, ties to the larger share_10 over the last 10
    revolutions."""
    t = table.copy()
    t["share_10_last"] = t.get("share_10_last", pd.Series(np.nan, index=t.index))
    t = t.sort_values(["points", "share_10_last"], ascending=[False, False],
                      na_position="last").reset_index(drop=True)
    t["rank"] = np.arange(1, len(t) + 1)
    return t



def phase2_seeds(rows: pd.DataFrame, flows: pd.DataFrame) -> pd.DataFrame:
    """One row per registered seed r0..r4: the wet run against its cohesionless twin
    (growth_study.seed_table) and against its uniform twin; control passes only when both
    nulls hold <= 1/5 of the wet share_10. A seed whose wet run or a null is missing fails
    every criterion (no evidence)."""
    kw = dict(settings=SETTINGS, steady_after=SETTINGS.hold_time)
    empty = rows.empty
    dry = pd.DataFrame() if empty else seed_table(rows, flows, "cohesionless", **kw)
    uni = pd.DataFrame() if empty else seed_table(rows, flows, "uniform", **kw)
    out = []
    for r in range(SEEDS):
        seed = f"cg1-none-r{r}"
        d = dry[dry.seed == seed] if len(dry) else dry
        u = uni[uni.seed == seed] if len(uni) else uni
        if d.empty or u.empty:
            out.append({"seed": seed, "complete": False,
                        **{c: False for c in REGISTERED + REPORTED}})
            continue
        row = d.iloc[0].to_dict()
        urow = u.iloc[0]
        row.update({"complete": True, "cohesionless_share_10": row.pop("control_share_10"),
                    "uniform_share_10": urow.control_share_10,
                    "uniform_survival": urow.control_survival,
                    "uniform_spanning_frames": urow.control_spanning_frames,
                    "uniform_angle_deg": urow.control_angle_deg,
                    "pass_control_cohesionless": bool(row["pass_control"]),
                    "pass_control_uniform": bool(urow.pass_control)})
        row["pass_control"] = row["pass_control_cohesionless"] and row["pass_control_uniform"]
        out.append(row)
    return pd.DataFrame(out)


def phase2_verdict(seeds: pd.DataFrame, criteria: Criteria = Criteria()) -> pd.DataFrame:
    """One row per criterion: seeds passing of the registered five, whether it passes
    (>= 4 of 5), and whether it is registered for the pass or reported beside it; a last
    row: the screen finds growth (every registered criterion passes)."""
    meaning = dict(CRITERIA)
    meaning["pass_control"] = ("granules exist (share_10 >= 0.02) and each null (cohesionless "
                               "twin, uniform twin) holds <= 1/5 of them")
    rows = []
    for col in REGISTERED + REPORTED:
        k = int(seeds[col].astype(bool).sum())
        rows.append({"criterion": col.removeprefix("pass_"), "meaning": meaning[col],
                     "registered": col in REGISTERED, "seeds_pass": k, "seeds": SEEDS,
                     "passes": k >= criteria.seeds_needed})
    found = all(r["passes"] for r in rows if r["registered"])
    rows.append({"criterion": "finds_growth", "meaning": "every registered criterion passes",
                 "registered": True,
                 "seeds_pass": int(seeds[list(REGISTERED)].astype(bool).all(axis=1).sum()),
                 "seeds": SEEDS, "passes": found})
    return pd.DataFrame(rows)
