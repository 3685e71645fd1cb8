"""The source study's GSD claim, measured at the regime map's closest point (issue "Granules
that exist", item 4), on the three studies of ``scripts/gsd_cg_study.sh``.

Usage::

    scripts/gsd_cg_study.sh runs/gsd_cg
    .venv/bin/python scripts/gsd_cg_claim.py runs/gsd_cg --out docs/results/gsd_cg

It reads only what ``ligwf study`` wrote (each study's ``analysis/``: the granule table of
the study's definition, the steady window in ``analysis.json``, ``flow.csv``,
``controls.csv``) and compares samples of steady frames with the CG1 reference (both CG1
replicas pooled):

* samples: each CG1 replica against the other (the **noise floor**), We-CG2 and Bo-CG2
  pools of K = 1, 2, 4 replicas (disjoint pools), and We-CG2 in a 2x and a 4x longer
  slice (2 replicas each: K = 1 and the pair);
* the source study's per-bin 15 % test and its located size limits (both ends, through
  :func:`ligwf.analysis.gsd.pooling.pooling_table`, the code ``ligwf analyse`` uses), for
  physical granule volumes (ligwf's default) and volumes / n^3 (the source study's);
* bin-free distances of the volume-weighted distribution of log10 granule volume:
  Wasserstein-1 (in decades of volume), Kolmogorov-Smirnov, and d10 / d50 / d90 ratios
  (equivalent-sphere diameters) to CG1; 95 % bands from the hierarchical block bootstrap
  of ligwf's GSD stage (replicas, then frames in moving blocks), sample and reference
  resampled together;
* each sample's flow error beside its GSD error: angle of repose, rigid-block share and
  flowing-layer thickness against CG1, with the CG1-vs-CG1 difference as the floor.

Pre-registered reading (written with this script, before any result of these studies was
looked at): a CG distance is **beyond** the floor when the lower end of its 95 % band is
above the larger of the two CG1-vs-CG1 values, **within** when the upper end of its band is
at most that value, and **undecided** otherwise. The per-bin test "holds below a size
limit" when the source study's upper limit exists (not nan) in the pooled sample, and the
claim "pooling or more CG particles helps" holds when K = 4 (or the 4x slice) is within the
floor where K = 1 is beyond it. The granules themselves are first checked against their
cohesionless twin (``controls.csv``): if they do not beat it, every GSD number is a
property of the definition, and the text says so.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.gsd import bins as gsd
from ligwf.analysis.gsd.pooling import frame_histograms, pooling_summary, pooling_table
from ligwf.analysis.records.analysis_record import AnalysisRecord
from ligwf.api.results import open_study
from ligwf.fsio import atomic_write_bytes, atomic_write_text
from ligwf.scene.settings import AnalysisSettings

GROUP = "gsd_cg"
CONFIDENCE = 0.95
FINE_PER_DECADE = 20          # bins of the bin-free distances (CDF resolution: 0.05 decade)
QUANTILES = (0.1, 0.5, 0.9)
FLOW_METRICS = {"angle_of_repose": "angle of repose (deg)",
                "rigid_frame_share": "rigid-block share",
                "flowing_layer_thickness_mean": "flowing layer (m)"}


@dataclass(frozen=True)
class CaseRecord:
    """One analysed case as the pooling code sees it (``CaseLike``)."""

    case_id: str
    cg: float
    rule: str
    replica: int
    group: str = GROUP


def _load(study: Path, label: str | None) -> tuple[pd.DataFrame, list[CaseRecord], pd.DataFrame]:
    """Steady-window granule table, case records and flow table of one study; CG-n rules of
    a longer-slice study are relabelled ``<rule> <label>`` (its own condition)."""
    results = open_study(study)
    analysed = AnalysisRecord.load(results.analysis_dir).items("cases")
    g, flow = results.granules, results.flow
    steady = {c["case_id"]: c["steady_from_step"] for c in analysed}
    g = g[g["step"] >= g["case_id"].map(steady).astype(float)].copy()
    cases = []
    for c in analysed:
        rule = c["rule"] if label is None else f"{c['rule']} {label}"
        cases.append(CaseRecord(c["case_id"] + ("" if label is None else f"@{label}"),
                                float(c["cg"]), rule, int(c["replica"])))
    if label is not None:
        g["case_id"] = g["case_id"] + f"@{label}"
        g["rule"] = g["rule"] + f" {label}"
        flow["case_id"] = flow["case_id"] + f"@{label}"
        flow["rule"] = flow["rule"] + f" {label}"
    return g, cases, flow


def is_twin(case_id: str) -> bool:
    return case_id.split("@")[0].endswith("_cohesionless")


# -- bin-free distances --------------------------------------------------------------


def frame_hists(g: pd.DataFrame, edges: np.ndarray, column: str, min_particles: int,
                replica_of: dict[str, int]) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame volume-weighted histograms (rows) and the replica of each frame, frames
    without a counted granule left out (their zero rows would not sum to a CDF)."""
    hists, reps = frame_histograms(g, edges, column, min_particles, replica_of)
    keep = hists.sum(axis=1) > 0
    return hists[keep], reps[keep]


def distances(cdf_a: np.ndarray, cdf_b: np.ndarray, log_edges: np.ndarray) -> np.ndarray:
    """(W1 in decades, KS, d10 ratio, d50 ratio, d90 ratio) of a against b, per row of the
    CDFs ((..., bins) at the upper bin edges)."""
    cdf_a, cdf_b = np.atleast_2d(cdf_a), np.atleast_2d(cdf_b)
    width = np.diff(log_edges)
    w1 = np.sum(np.abs(cdf_a - cdf_b) * width, axis=1)
    ks = np.max(np.abs(cdf_a - cdf_b), axis=1)
    out = [w1, ks]
    for q in QUANTILES:
        out.append(_diameter(cdf_a, log_edges, q) / _diameter(cdf_b, log_edges, q))
    return np.column_stack(out)


def _diameter(cdf: np.ndarray, log_edges: np.ndarray, q: float) -> np.ndarray:
    """Equivalent diameter (m) at volume fraction q, log-linear inside the bin."""
    out = np.full(len(cdf), np.nan)
    for r, c in enumerate(cdf):
        if not np.all(np.isfinite(c)) or c[-1] <= 0:
            continue
        c = c / c[-1]
        full = np.concatenate([[0.0], c])
        k = int(np.searchsorted(full, q, side="left"))
        k = min(max(k, 1), len(full) - 1)
        lo, hi = full[k - 1], full[k]
        t = 0.0 if hi <= lo else (q - lo) / (hi - lo)
        logv = log_edges[k - 1] + t * (log_edges[k] - log_edges[k - 1])
        out[r] = (6.0 * 10.0 ** logv / math.pi) ** (1.0 / 3.0)
    return out


DIST_NAMES = ("w1_decades", "ks", "d10_ratio", "d50_ratio", "d90_ratio")


def _compare(h_a, r_a, h_b, r_b, log_edges, n_boot, rng) -> dict[str, float]:
    mean_a, mean_b = np.cumsum(h_a.mean(axis=0)), np.cumsum(h_b.mean(axis=0))
    point = distances(mean_a, mean_b, log_edges)[0]
    draws = distances(np.cumsum(gsd.bootstrap_means(h_a, r_a, n_boot, rng), axis=1),
                      np.cumsum(gsd.bootstrap_means(h_b, r_b, n_boot, rng), axis=1), log_edges)
    lo, hi = gsd.band(draws, CONFIDENCE)
    row: dict[str, float] = {}
    for k, name in enumerate(DIST_NAMES):
        row.update({name: float(point[k]), f"{name}_lo": float(lo[k]),
                    f"{name}_hi": float(hi[k])})
    return row


def samples(cases: list[CaseRecord]) -> list[tuple[str, str, int, list[CaseRecord], list[CaseRecord]]]:
    """(sample, condition, K, members, reference) for the floor, the pools and the slices."""
    wet1 = sorted((c for c in cases if c.cg == 1 and not is_twin(c.case_id)),
                  key=lambda c: c.replica)
    out = []
    for c in wet1:
        out.append((f"CG1 r{c.replica} vs other CG1", "noise floor", 1, [c],
                    [o for o in wet1 if o is not c]))
    conds: dict[str, list[CaseRecord]] = {}
    for c in cases:
        if c.cg != 1:
            conds.setdefault(c.rule, []).append(c)
    for rule, members in sorted(conds.items()):
        members = sorted(members, key=lambda c: c.replica)
        for k in (1, 2, 4):
            for p in range(len(members) // k):
                pool = members[p * k:(p + 1) * k]
                name = f"CG2 {rule} K={k} [{'+'.join(str(c.replica) for c in pool)}]"
                out.append((name, f"CG2 {rule}", k, pool, wet1))
    return out


def distance_table(g: pd.DataFrame, cases: list[CaseRecord], column: str, n_boot: int,
                   min_particles: int, seed: int) -> pd.DataFrame:
    use = gsd.counted(g["members"], g["percolating"].to_numpy(bool), min_particles)
    v = g[column][use]
    edges = gsd.log_edges(float(v.min()), float(v.max()), FINE_PER_DECADE)
    log_edges = np.log10(edges)
    replica_of = {c.case_id: c.replica for c in cases}
    rng = np.random.default_rng(seed)
    rows = []
    for name, cond, k, members, ref in samples(cases):
        ids_a, ids_b = {c.case_id for c in members}, {c.case_id for c in ref}
        h_a, r_a = frame_hists(g[g.case_id.isin(ids_a)], edges, column, min_particles, replica_of)
        h_b, r_b = frame_hists(g[g.case_id.isin(ids_b)], edges, column, min_particles, replica_of)
        if len(h_a) == 0 or len(h_b) == 0:
            rows.append({"sample": name, "condition": cond, "k": k, "frames": len(h_a)})
            continue
        rows.append({"sample": name, "condition": cond, "k": k, "frames": len(h_a),
                     **_compare(h_a, r_a, h_b, r_b, log_edges, n_boot, rng)})
    return pd.DataFrame(rows)


def verdicts(table: pd.DataFrame) -> pd.DataFrame:
    """The pre-registered beyond / within / undecided reading of every CG distance."""
    floor_rows = table[table.condition == "noise floor"]
    out = table.copy()
    for name in DIST_NAMES:
        ratio = name.endswith("_ratio")
        dev = (lambda s: (np.log(s)).abs()) if ratio else (lambda s: s)
        floor = float(dev(floor_rows[name]).max()) if len(floor_rows) else float("nan")
        out[f"{name}_floor"] = floor
        if ratio:   # a band of the ratio excludes 1 by more than the floor's deviation
            lo_dev = np.where((out[f"{name}_lo"] > 1) | (out[f"{name}_hi"] < 1),
                              np.minimum(np.log(out[f"{name}_lo"]).abs(),
                                         np.log(out[f"{name}_hi"]).abs()), 0.0)
            hi_dev = np.maximum(np.log(out[f"{name}_lo"]).abs(), np.log(out[f"{name}_hi"]).abs())
        else:
            lo_dev, hi_dev = out[f"{name}_lo"], out[f"{name}_hi"]
        out[f"{name}_verdict"] = np.where(
            out.condition == "noise floor", "floor",
            np.where(lo_dev > floor, "beyond", np.where(hi_dev <= floor, "within", "undecided")))
    return out


# -- flow beside GSD -----------------------------------------------------------------


def flow_table(flow: pd.DataFrame, cases: list[CaseRecord]) -> pd.DataFrame:
    wet = flow[~flow.case_id.map(is_twin)]
    ref = wet[wet.cg == 1]
    rows = []
    for name, cond, k, members, refs in samples(cases):
        ids = {c.case_id for c in members}
        sub = wet[wet.case_id.isin(ids)]
        refsub = ref[ref.case_id.isin({c.case_id for c in refs})]
        row = {"sample": name, "condition": cond, "k": k}
        for col in FLOW_METRICS:
            row[col] = float(sub[col].mean())
            row[f"{col}_error"] = float(sub[col].mean() - refsub[col].mean())
        rows.append(row)
    twins = flow[flow.case_id.map(is_twin)]
    for _, t in twins.iterrows():
        row = {"sample": f"twin {t.case_id}", "condition": "cohesionless twin", "k": 1}
        for col in FLOW_METRICS:
            row[col] = float(t[col])
            row[f"{col}_error"] = float(t[col] - ref[col].mean())
        rows.append(row)
    return pd.DataFrame(rows)


# -- figure --------------------------------------------------------------------------


def figure(g: pd.DataFrame, cases: list[CaseRecord], column: str, min_particles: int,
           n_boot: int, seed: int) -> bytes:
    import io

    import matplotlib
    from matplotlib.figure import Figure

    matplotlib.rcParams.update({"font.size": 9})
    use = gsd.counted(g["members"], g["percolating"].to_numpy(bool), min_particles)
    v = g[column][use]
    edges = gsd.log_edges(float(v.min()), float(v.max()), 5)
    d_mid = 1e3 * (6.0 * np.sqrt(edges[:-1] * edges[1:]) / math.pi) ** (1 / 3)
    replica_of = {c.case_id: c.replica for c in cases}
    rng = np.random.default_rng(seed)
    wet1 = [c for c in cases if c.cg == 1 and not is_twin(c.case_id)]
    groups = {"CG1 (2 replicas)": wet1}
    for c in cases:
        if c.cg != 1:
            groups.setdefault(f"CG2 {c.rule} (pooled)", []).append(c)
    fig = Figure(figsize=(7.0, 4.2))
    ax = fig.add_subplot()
    for label, members in groups.items():
        h, r = frame_hists(g[g.case_id.isin({c.case_id for c in members})], edges, column,
                           min_particles, replica_of)
        if len(h) == 0:
            continue
        lo, hi = gsd.band(gsd.bootstrap_means(h, r, n_boot, rng), CONFIDENCE)
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
    parts = [_load(args.runs / "main", None)]
    for k in (2, 4):
        if (args.runs / f"L{k}").is_dir():
            parts.append(_load(args.runs / f"L{k}", f"L{k}x"))
    g = pd.concat([p[0] for p in parts], ignore_index=True)
    cases = [c for p in parts for c in p[1]]
    flow = pd.concat([p[2] for p in parts], ignore_index=True)
    wet_g = g[~g.case_id.map(is_twin)]
    wet_cases = [c for c in cases if not is_twin(c.case_id)]
    min_particles = AnalysisSettings().min_particles
    args.out.mkdir(parents=True, exist_ok=True)
    limits, dists = [], []
    for volume, column in gsd.VOLUME_COLUMNS.items():
        settings = AnalysisSettings(bootstrap=args.boot, gsd_volume=volume, seed=args.seed)
        t = pooling_table(wet_g, wet_cases, settings)
        limits.append(pooling_summary(t).assign(volume=volume))
        d = verdicts(distance_table(wet_g, wet_cases, column, args.boot, min_particles, args.seed))
        dists.append(d.assign(volume=volume))
        print(f"# {volume}: done", file=sys.stderr)
    limits_df, dist_df = pd.concat(limits), pd.concat(dists)
    flow_df = flow_table(flow, cases)
    controls = open_study(args.runs / "main").controls
    for name, df in (("claim_limits.csv", limits_df), ("claim_distances.csv", dist_df),
                     ("claim_flow.csv", flow_df), ("claim_controls.csv", controls)):
        atomic_write_text(args.out / name, df.to_csv(index=False, float_format="%.6g"))
    atomic_write_bytes(args.out / "claim_gsd.png",
                       figure(wet_g, wet_cases, "volume", min_particles, args.boot, args.seed))
    pd.set_option("display.width", 250)
    pd.set_option("display.max_columns", 60)
    fmt = lambda x: f"{x:.3g}"   # noqa: E731
    print(controls[["case_id", "definition", "passes", "share_10", "twin_share_10",
                    "persist_quarter", "twin_persist_quarter", "comove_ratio",
                    "percolating_frames"]].to_string(index=False, float_format=fmt))
    print(limits_df[["volume", "condition", "rule", "k", "pools", "upper_limit_mean",
                     "upper_limit_nan_pools", "error_below_upper_mean", "error_above_upper_mean",
                     "lower_limit_mean", "error_above_lower_mean"]].to_string(index=False,
                                                                             float_format=fmt))
    cols = ["volume", "sample", "frames"] + [c for n in DIST_NAMES
                                             for c in (n, f"{n}_lo", f"{n}_hi", f"{n}_verdict")]
    print(dist_df[cols].to_string(index=False, float_format=fmt))
    print(flow_df.to_string(index=False, float_format=fmt))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
