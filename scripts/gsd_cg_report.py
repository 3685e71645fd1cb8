"""The GSD claim of the source study measured on an analysed ligwf study (issue 11 item 6).

Usage (after ``ligwf study workflows/gsd_cg.yaml --out runs/gsd_cg``)::

    .venv/bin/python scripts/gsd_cg_report.py runs/gsd_cg --out docs/results/gsd_cg

For each granule definition of :data:`ligwf.analysis.gsd.definition_cases.DEFINITIONS` it
identifies the granules of every case's steady frames
(:func:`~ligwf.analysis.gsd.definition_cases.steady_granules`), then prints and writes:

* ``definitions.csv``: per case, percolating frames, largest granule (share of the bed),
  d50 and granule count (acceptance (a) of the issue);
* ``pooling.csv`` / ``pooling_summary.csv``: :mod:`ligwf.analysis.gsd.pooling` per
  definition and volume convention (physical, and primary = volume / n^3, the source
  study's), pool sizes K = 1, 2, 4, with the CG1-vs-CG1 noise floor.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

from ligwf.analysis.gsd.bins import VOLUME_COLUMNS
from ligwf.analysis.gsd.definition_cases import DEFINITIONS, definition_table, steady_granules
from ligwf.analysis.gsd.pooling import pooling_summary, pooling_table
from ligwf.api.results_folder import csv_text
from ligwf.fsio import atomic_write_text
from ligwf.scene.settings import AnalysisSettings
from ligwf.study.study import Study

#: the tables this script measures (named here, once)
DEFINITIONS_TABLE, POOLING, POOLING_SUMMARY = ("definitions.csv", "pooling.csv",
                                               "pooling_summary.csv")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", type=Path)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--boot", type=int, default=1000)
    args = ap.parse_args(argv)
    study = Study.open(args.study)
    defs, pooled = [], []
    for name, definition in DEFINITIONS.items():
        g, cases = steady_granules(study, definition)
        defs.append(definition_table(g, cases).assign(definition=name))
        for volume in VOLUME_COLUMNS:
            t = pooling_table(g, cases, AnalysisSettings(bootstrap=args.boot, gsd_volume=volume))
            pooled.append(t.assign(definition=name, volume=volume))
        print(f"# {name}", file=sys.stderr)
    first = ["definition", "volume"]
    defs_df = pd.concat(defs)[["definition", *defs[0].columns[:-1]]]
    pool_df = pd.concat(pooled)[[*first, *pooled[0].columns[:-2]]]
    summary = pd.concat([pooling_summary(t).assign(definition=dn, volume=vn)
                         for (dn, vn), t in pool_df.groupby(first)])
    args.out.mkdir(parents=True, exist_ok=True)
    for name, df in ((DEFINITIONS_TABLE, defs_df), (POOLING, pool_df), (POOLING_SUMMARY, summary)):
        atomic_write_text(args.out / name, csv_text(df))
    pd.set_option("display.width", 250)
    pd.set_option("display.max_columns", 40)
    print(defs_df.to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    print(summary.to_string(index=False, float_format=lambda x: f"{x:.3g}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
