"""The source study's GSD claim, measured at the regime map's closest point (issue "Granules
that exist", item 4), on the three studies of ``scripts/gsd_cg_study.sh``.

Usage::

    scripts/gsd_cg_study.sh runs/gsd_cg
    .venv/bin/python scripts/gsd_cg_claim.py runs/gsd_cg --out docs/results/gsd_cg

It reads only what ``ligwf study`` wrote (each study's ``analysis/``: the granule table of
the study's definition, the steady window in ``analysis.json``, ``flow.csv``,
``controls.csv``), keeps the steady frames, and writes (the measurement and its
pre-registered reading are :mod:`ligwf.analysis.gsd.sample_distances`):

* ``claim_limits.csv``: the source study's per-bin 15 % test and its located size limits
  (:func:`ligwf.analysis.gsd.pooling.pooling_table`, the code ``ligwf analyse`` uses) per
  pool, for physical granule volumes (ligwf's default) and volumes / n^3 (the source
  study's);
* ``claim_distances.csv``: the bin-free distances of the floor, the pools (K = 1, 2, 4) and
  the We-CG2 2x and 4x longer slices (studies ``L2``, ``L4``: their own conditions) from
  CG1, with their verdicts;
* ``claim_flow.csv``: each sample's flow error beside its GSD error;
* ``claim_controls.csv``: the granules against their cohesionless twin (if they do not beat
  it, every GSD number is a property of the definition, and the README says so);
* ``claim_gsd.png``: the GSD of CG1 and of each pooled CG2 rule with its band.
"""

from __future__ import annotations

import argparse
import io
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.gsd import bins as gsd
from ligwf.analysis.gsd import sample_distances as sd
from ligwf.analysis.gsd.pooling import pooling_summary, pooling_table
from ligwf.analysis.records.analysis_record import AnalysisRecord
from ligwf.api.results import open_study
from ligwf.api.results_folder import csv_text
from ligwf.fsio import atomic_write_bytes, atomic_write_text
from ligwf.scene.settings import AnalysisSettings

GROUP = "gsd_cg"
#: the tables this script measures (named here, once)
LIMITS, DISTANCES, FLOW, CONTROLS = ("claim_limits.csv", "claim_distances.csv",
                                     "claim_flow.csv", "claim_controls.csv")
FIGURE = "claim_gsd.png"
#: the longer-slice studies (folder under the runs folder: the label of their conditions)
SLICES = {"L2": "L2x", "L4": "L4x"}


def load(study: Path, label: str | None):
    """Steady-window granule table, cases and flow table of one study, relabelled ``label``
    (:func:`ligwf.analysis.gsd.sample_distances.sample_cases`) for a longer slice."""
    results = open_study(study)
    analysed = AnalysisRecord.load(results.analysis_dir).items("cases")
    g, flow = results.granules, results.flow
    steady = {c["case_id"]: c["steady_from_step"] for c in analysed}
    g = g[g["step"] >= g["case_id"].map(steady).astype(float)].copy()
    if label is not None:
        for table in (g, flow):
            table["case_id"] = table["case_id"] + f"@{label}"
            table["rule"] = table["rule"] + f" {label}"
    return g, sd.sample_cases(analysed, GROUP, label), flow


def figure(g: pd.DataFrame, cases, min_particles: int, n_boot: int, seed: int) -> bytes:
    """The GSD (physical volume, 5 bins per decade) of CG1 and of each pooled CG2 rule."""
    import matplotlib
    from matplotlib.figure import Figure

    matplotlib.rcParams.update({"font.size": 9})
    use = gsd.counted(g["members"], g["percolating"].to_numpy(bool), min_particles)
    v = g["volume"][use]
    edges = gsd.log_edges(float(v.min()), float(v.max()), 5)
    d_mid = 1e3 * (6.0 * np.sqrt(edges[:-1] * edges[1:]) / math.pi) ** (1 / 3)
    replica_of = {c.case_id: c.replica for c in cases}
    rng = np.random.default_rng(seed)
    groups = {"CG1 (2 replicas)": [c for c in cases if c.cg == 1 and not c.is_twin]}
    for c in cases:
        if c.cg != 1:
            groups.setdefault(f"CG2 {c.rule} (pooled)", []).append(c)
    fig = Figure(figsize=(7.0, 4.2))
    ax = fig.add_subplot()
    for label, members in groups.items():
        h, r = sd.counted_histograms(g[g.case_id.isin({c.case_id for c in members})], edges,
                                     "volume", min_particles, replica_of)
        if len(h) == 0:
            continue
        lo, hi = gsd.band(gsd.bootstrap_means(h, r, n_boot, rng), sd.CONFIDENCE)
        line, = ax.plot(d_mid, h.mean(axis=0), marker="o", ms=3, label=f"{label}, {len(h)} frames")
        ax.fill_between(d_mid, lo, hi, color=line.get_color(), alpha=0.2, lw=0)
    ax.set_xscale("log")
    ax.set_xlabel("granule equivalent diameter (mm), physical volume")
    ax.set_ylabel("volume fraction per bin (5 bins / decade of volume)")
    ax.set_title("held-1 s granules at St_v 0.35, Bo_g 3.4 (bands: 95 %, block bootstrap)")
    ax.legend(fontsize=7, loc="upper left", frameon=False)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=130, bbox_inches="tight")
    return buf.getvalue()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", type=Path, help="the folder scripts/gsd_cg_study.sh wrote")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--boot", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=12345)
    args = ap.parse_args(argv)
    parts = [load(args.runs / "main", None)] + [load(args.runs / folder, label)
                                                for folder, label in SLICES.items()
                                                if (args.runs / folder).is_dir()]
    g = pd.concat([p[0] for p in parts], ignore_index=True)
    cases = [c for p in parts for c in p[1]]
    flow = pd.concat([p[2] for p in parts], ignore_index=True)
    wet_g = g[~g.case_id.map(sd.is_twin)]
    wet_cases = [c for c in cases if not c.is_twin]
    min_particles = AnalysisSettings().min_particles
    limits, dists = [], []
    for volume, column in gsd.VOLUME_COLUMNS.items():
        settings = AnalysisSettings(bootstrap=args.boot, gsd_volume=volume, seed=args.seed)
        limits.append(pooling_summary(pooling_table(wet_g, wet_cases, settings))
                      .assign(volume=volume))
        d = sd.distance_table(wet_g, wet_cases, column, args.boot, min_particles, args.seed)
        dists.append(sd.verdicts(d).assign(volume=volume))
        print(f"# {volume}: done", file=sys.stderr)
    tables = {LIMITS: pd.concat(limits), DISTANCES: pd.concat(dists),
              FLOW: sd.flow_table(flow, cases), CONTROLS: open_study(args.runs / "main").controls}
    args.out.mkdir(parents=True, exist_ok=True)
    for name, table in tables.items():
        atomic_write_text(args.out / name, csv_text(table))
    atomic_write_bytes(args.out / FIGURE,
                       figure(wet_g, wet_cases, min_particles, args.boot, args.seed))
    pd.set_option("display.width", 250)
    pd.set_option("display.max_columns", 60)
    for table in tables.values():
        print(table.to_string(index=False, float_format=lambda x: f"{x:.3g}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
