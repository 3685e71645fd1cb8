"""The GSD claim of the source study measured on an analysed ligwf study (issue 11 item 6).

Usage (after ``ligwf study workflows/gsd_cg.yaml --out runs/gsd_cg``)::

    .venv/bin/python scripts/gsd_cg_report.py runs/gsd_cg --out docs/results/gsd_cg

For each granule definition (the default, Leiden CPM of the rupture-work-weighted bridge
network; the source study's connected components of bridges co-moving within 30 deg in the
lab frame; the force-weighted CPM of the previous default) it identifies the granules of
every case's steady frames (the window the study's analysis used, from
``analysis/analysis.json``), then prints and writes:

* ``definitions.csv``: per case, percolating frames, largest granule (share of the bed),
  d50 and granule count (acceptance (a) of the issue);
* ``pooling.csv`` / ``pooling_summary.csv``: :mod:`ligwf.analysis.gsd.pooling` per
  definition and volume convention (physical, and primary = volume / n^3, the source
  study's), pool sizes K = 1, 2, 4, with the CG1-vs-CG1 noise floor.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.gsd import bins as gsd
from ligwf.analysis.records.analysis_record import AnalysisRecord
from ligwf.analysis.granules.case import GranuleAnalysis
from ligwf.analysis.frames.checks import plan_frames
from ligwf.analysis.gsd.pooling import pooling_summary, pooling_table
from ligwf.fsio import atomic_write_text
from ligwf.scene.settings import AnalysisSettings
from ligwf.study.study import Study

DEFINITIONS = {
    "cpm-energy (default until 2026-12-02)": AnalysisSettings(granules="communities"),
    "components lab 30 (source)": AnalysisSettings(granules="components", velocity_frame="lab",
                                                   max_velocity_angle=30.0),
    "cpm-force 0.02 (old default)": AnalysisSettings(granules="communities", resolution=0.02,
                                                     community_weight="force"),
}


def steady_tables(study: Study, definition: AnalysisSettings) -> tuple[pd.DataFrame, list]:
    """Granule table of every case's steady frames under ``definition``."""
    analysed = AnalysisRecord.load(study.analysis_dir).items("cases")
    steady_from = {c["case_id"]: c["steady_from_step"] for c in analysed}
    tables, cases = [], []
    for case in study.cases:
        if case.case_id not in steady_from:
            continue
        frames = [f for f in plan_frames(case).frames if f.step >= steady_from[case.case_id]]
        ana = GranuleAnalysis(case, definition).run(frames)
        for r in ana.results:
            if r.table is None:
                raise SystemExit(f"{case.case_id} step {r.step}: {r.error}")
            t = r.table.copy()
            t["case_id"], t["step"] = case.case_id, r.step
            tables.append(t)
        cases.append(case)
    return pd.concat(tables, ignore_index=True), cases


def per_case(g: pd.DataFrame, cases) -> pd.DataFrame:
    rows = []
    for c in cases:
        t = g[g.case_id == c.case_id]
        perc, largest, d50, count = [], [], [], []
        for _, fr in t.groupby("step"):
            bed = fr["volume"].sum()
            counted = gsd.counted(fr["members"].to_numpy(), fr["percolating"].to_numpy(bool), 2)
            perc.append(bool(fr["percolating"].any()))
            largest.append(fr["volume"].max() / bed)
            d50.append(gsd.percentile_diameters(fr["volume"].to_numpy()[counted], (0.5,))[0])
            count.append(int(counted.sum()))
        rows.append({"case_id": c.case_id, "cg": c.cg, "replica": c.replica, "frames": len(perc),
                     "percolating_frames": float(np.mean(perc)),
                     "largest_share": float(np.mean(largest)),
                     "largest_share_max": float(np.max(largest)),
                     "d50_mm": 1e3 * float(np.nanmean(d50)), "granules": float(np.mean(count))})
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", type=Path)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--boot", type=int, default=1000)
    args = ap.parse_args(argv)
    study = Study.open(args.study)
    args.out.mkdir(parents=True, exist_ok=True)
    defs, pooled = [], []
    for name, definition in DEFINITIONS.items():
        g, cases = steady_tables(study, definition)
        d = per_case(g, cases)
        d.insert(0, "definition", name)
        defs.append(d)
        for volume in ("physical", "primary"):
            t = pooling_table(g, cases, AnalysisSettings(bootstrap=args.boot, gsd_volume=volume))
            t.insert(0, "volume", volume)
            t.insert(0, "definition", name)
            pooled.append(t)
        print(f"# {name}", file=sys.stderr)
    defs_df, pool_df = pd.concat(defs), pd.concat(pooled)
    summary = pd.concat([pooling_summary(t).assign(definition=dn, volume=vn)
                         for (dn, vn), t in pool_df.groupby(["definition", "volume"])])
    for name, df in (("definitions.csv", defs_df), ("pooling.csv", pool_df),
                     ("pooling_summary.csv", summary)):
        atomic_write_text(args.out / name, df.to_csv(index=False, float_format="%.6g"))
    pd.set_option("display.width", 250)
    pd.set_option("display.max_columns", 40)
    print(defs_df.to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    cols = ["definition", "volume", "condition", "rule", "k", "pools", "upper_limit_mean",
            "upper_limit_min", "upper_limit_max", "upper_limit_nan_pools",
            "error_below_upper_mean", "error_above_upper_mean", "lower_limit_mean",
            "error_below_lower_mean", "error_above_lower_mean"]
    print(summary[cols].to_string(index=False, float_format=lambda x: f"{x:.3g}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
