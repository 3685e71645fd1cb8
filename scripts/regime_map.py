"""Measure the regime-map runs of scripts/regime_map.sh with every candidate granule definition.

Usage: .venv/bin/python scripts/regime_map.py runs/regime docs/results/regime
Writes OUT/controls_rows.csv (one row per run, definition and start frame),
OUT/controls.csv (means per run and definition, with the run's dimensionless numbers) and
OUT/regime_map.png.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pandas as pd

from ligwf.analysis.control_run import control_rows, load_series, summarise
from ligwf.scene.regime import regime_numbers
from ligwf.study.case import CaseFolder


def main(run_root: Path, out: Path) -> int:
    out.mkdir(parents=True, exist_ok=True)
    rows, numbers = [], []
    for point in sorted(p for p in run_root.iterdir() if (p / ".done").exists()):
        for case_dir in sorted(d for d in point.iterdir() if (d / "scene.json").exists()):
            t0 = time.perf_counter()
            series = load_series(case_dir)
            r = control_rows(series)
            r.insert(0, "point", point.name)
            rows.append(r)
            nums = regime_numbers(CaseFolder.open(case_dir).scaled)
            numbers.append({"point": point.name, **nums})
            print(f"{point.name}: {len(series.frames)} frames, {time.perf_counter() - t0:.0f} s",
                  flush=True)
    all_rows = pd.concat(rows, ignore_index=True)
    all_rows.to_csv(out / "controls_rows.csv", index=False, float_format="%.4g")
    summary = summarise(all_rows.drop(columns=["point"]).assign(case_id=all_rows["point"]))
    summary = summary.rename(columns={"case_id": "point"}).merge(pd.DataFrame(numbers), on="point")
    summary.to_csv(out / "controls.csv", index=False, float_format="%.4g")
    with pd.option_context("display.width", 250, "display.max_columns", 30):
        print(summary.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]), Path(sys.argv[2])))
