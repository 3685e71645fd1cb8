"""How far a CG-n sample's granule size distribution is from CG1's, read against CG1's
distance from itself: the measurement behind the source study's GSD claim
(``docs/results/gsd_cg``, written by ``scripts/gsd_cg_claim.py``).

Samples (:func:`samples`): each CG1 replica against the other CG1 replicas (the **noise
floor**), and every CG-n condition in disjoint pools of K = 1, 2, 4 replicas against all
CG1 replicas. Each is compared without bins (:func:`distances`), on the volume-weighted
distribution of log10 granule volume: Wasserstein-1 (in decades of volume),
Kolmogorov-Smirnov, and the d10 / d50 / d90 ratios (equivalent-sphere diameters) to the
reference; 95 % bands from the hierarchical block bootstrap of the GSD stage
(:func:`ligwf.analysis.gsd.bins.bootstrap_means`: replicas, then frames in moving
blocks), sample and reference resampled together.

Pre-registered reading (:func:`verdicts`, written before any result was looked at): a CG
distance is **beyond** the floor when the lower end of its 95 % band is above the larger of
the two CG1-vs-CG1 values, **within** when the upper end of its band is at most that value,
and **undecided** otherwise (a ratio is read by its distance from 1, on a log scale).
:func:`flow_table` puts each sample's flow error beside its GSD error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np
import pandas as pd

from ligwf.analysis.gsd import bins as gsdmod
from ligwf.analysis.gsd.pooling import frame_histograms
from ligwf.study.condition import REFERENCE_CG

#: 95 % bands
CONFIDENCE = 0.95
#: bins of the bin-free distances per decade of volume (CDF resolution 0.05 decade)
FINE_PER_DECADE = 20
#: volume fractions of the diameter ratios
QUANTILES = (0.1, 0.5, 0.9)
#: the distances, in the order :func:`distances` returns them
DIST_NAMES = ("w1_decades", "ks", "d10_ratio", "d50_ratio", "d90_ratio")
#: the flow metrics put beside the GSD (flow table column: label)
FLOW_METRICS = {"angle_of_repose": "angle of repose (deg)",
                "rigid_frame_share": "rigid-block share",
                "flowing_layer_thickness_mean": "flowing layer (m)"}
#: the pool sizes K of a CG-n condition
POOL_SIZES = (1, 2, 4)
#: what ends the case id of a cohesionless twin (a control, not a sample)
TWIN_SUFFIX = "_cohesionless"


@dataclass(frozen=True)
class SampleCase:
    """One analysed case as the samples see it (a ``CaseLike``); a case of a longer-slice
    study carries ``@<label>`` in its id and ``<rule> <label>`` as its rule, so that slice is
    a condition of its own."""

    case_id: str
    cg: float
    rule: str
    replica: int
    group: str

    @property
    def is_twin(self) -> bool:
        return is_twin(self.case_id)


def is_twin(case_id: str) -> bool:
    """Whether ``case_id`` (``@label`` or not) is a cohesionless twin."""
    return case_id.split("@")[0].endswith(TWIN_SUFFIX)


def sample_cases(analysed: Iterable[dict], group: str, label: str | None = None) -> list[SampleCase]:
    """The cases of an analysis record's ``cases`` items, relabelled ``@label`` /
    ``<rule> <label>`` when ``label`` is given (a longer-slice study)."""
    return [SampleCase(c["case_id"] + ("" if label is None else f"@{label}"), float(c["cg"]),
                       c["rule"] if label is None else f"{c['rule']} {label}",
                       int(c["replica"]), group) for c in analysed]


Sample = tuple[str, str, int, list[SampleCase], list[SampleCase]]


def samples(cases: Sequence[SampleCase]) -> list[Sample]:
    """(sample, condition, K, members, reference) for the floor, then each CG-n rule's
    pools (rules in sorted order, pools in replica order)."""
    wet1 = sorted((c for c in cases if c.cg == REFERENCE_CG and not c.is_twin),
                  key=lambda c: c.replica)
    out: list[Sample] = []
    for c in wet1:
        out.append((f"CG1 r{c.replica} vs other CG1", "noise floor", 1, [c],
                    [o for o in wet1 if o is not c]))
    conds: dict[str, list[SampleCase]] = {}
    for c in cases:
        if c.cg != REFERENCE_CG:
            conds.setdefault(c.rule, []).append(c)
    for rule, members in sorted(conds.items()):
        members = sorted(members, key=lambda c: c.replica)
        for k in POOL_SIZES:
            for p in range(len(members) // k):
                pool = members[p * k:(p + 1) * k]
                name = f"CG{pool[0].cg:g} {rule} K={k} [{'+'.join(str(c.replica) for c in pool)}]"
                out.append((name, f"CG{pool[0].cg:g} {rule}", k, pool, wet1))
    return out


def counted_histograms(g: pd.DataFrame, edges: np.ndarray, column: str, min_particles: int,
                       replica_of: dict[str, int]) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame volume-weighted histograms (rows) and the replica of each frame, frames
    without a counted granule left out (their zero rows would not sum to a CDF)."""
    hists, reps = frame_histograms(g, edges, column, min_particles, replica_of)
    keep = hists.sum(axis=1) > 0
    return hists[keep], reps[keep]


def diameter_at(cdf: np.ndarray, log_edges: np.ndarray, q: float) -> np.ndarray:
    """Equivalent diameter (m) at volume fraction ``q`` of each CDF row (at the upper bin
    edges, ``log_edges`` log10 m^3), log-linear inside the bin; nan for an empty row."""
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


def distances(cdf_a: np.ndarray, cdf_b: np.ndarray, log_edges: np.ndarray) -> np.ndarray:
    """:data:`DIST_NAMES` of a against b, per row of the CDFs ((..., bins) at the upper bin
    edges ``log_edges``, log10 m^3): W1 in decades, KS, and the quantile diameter ratios."""
    cdf_a, cdf_b = np.atleast_2d(cdf_a), np.atleast_2d(cdf_b)
    width = np.diff(log_edges)
    out = [np.sum(np.abs(cdf_a - cdf_b) * width, axis=1), np.max(np.abs(cdf_a - cdf_b), axis=1)]
    for q in QUANTILES:
        out.append(diameter_at(cdf_a, log_edges, q) / diameter_at(cdf_b, log_edges, q))
    return np.column_stack(out)


def compare(h_a, r_a, h_b, r_b, log_edges, n_boot: int, rng: np.random.Generator) -> dict[str, float]:
    """The distances of sample a (frame histograms ``h_a``, replicas ``r_a``) from b, each
    with its bootstrap band (``<name>_lo``, ``<name>_hi``)."""
    point = distances(np.cumsum(h_a.mean(axis=0)), np.cumsum(h_b.mean(axis=0)), log_edges)[0]
    draws = distances(np.cumsum(gsdmod.bootstrap_means(h_a, r_a, n_boot, rng), axis=1),
                      np.cumsum(gsdmod.bootstrap_means(h_b, r_b, n_boot, rng), axis=1), log_edges)
    lo, hi = gsdmod.band(draws, CONFIDENCE)
    row: dict[str, float] = {}
    for k, name in enumerate(DIST_NAMES):
        row.update({name: float(point[k]), f"{name}_lo": float(lo[k]),
                    f"{name}_hi": float(hi[k])})
    return row


def distance_table(g: pd.DataFrame, cases: Sequence[SampleCase], column: str, n_boot: int,
                   min_particles: int, seed: int) -> pd.DataFrame:
    """One row per sample (:func:`samples`): its frames and :func:`compare`'s distances of
    the counted granules' ``column`` volumes (frames only, when either side is empty)."""
    use = gsdmod.counted(g["members"], g["percolating"].to_numpy(bool), min_particles)
    v = g[column][use]
    edges = gsdmod.log_edges(float(v.min()), float(v.max()), FINE_PER_DECADE)
    log_edges = np.log10(edges)
    replica_of = {c.case_id: c.replica for c in cases}
    rng = np.random.default_rng(seed)
    rows = []
    for name, cond, k, members, ref in samples(cases):
        ids_a, ids_b = {c.case_id for c in members}, {c.case_id for c in ref}
        h_a, r_a = counted_histograms(g[g.case_id.isin(ids_a)], edges, column, min_particles,
                                      replica_of)
        h_b, r_b = counted_histograms(g[g.case_id.isin(ids_b)], edges, column, min_particles,
                                      replica_of)
        row = {"sample": name, "condition": cond, "k": k, "frames": len(h_a)}
        if len(h_a) and len(h_b):
            row.update(compare(h_a, r_a, h_b, r_b, log_edges, n_boot, rng))
        rows.append(row)
    return pd.DataFrame(rows)


def verdicts(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` with, per distance, its floor (``<name>_floor``: the largest CG1-vs-CG1
    value, a ratio's as |log|) and the pre-registered reading (``<name>_verdict``: floor,
    beyond, within, undecided)."""
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


def flow_table(flow: pd.DataFrame, cases: Sequence[SampleCase]) -> pd.DataFrame:
    """Per sample the mean of each :data:`FLOW_METRICS` over its cases and its error
    against its reference's mean (``<metric>_error``); then each cohesionless twin against
    the mean of the CG1 cases."""
    twin = flow.case_id.map(is_twin)
    wet = flow[~twin]
    ref = wet[wet.cg == REFERENCE_CG]
    rows = []
    for name, cond, k, members, refs in samples(cases):
        sub = wet[wet.case_id.isin({c.case_id for c in members})]
        refsub = ref[ref.case_id.isin({c.case_id for c in refs})]
        row = {"sample": name, "condition": cond, "k": k}
        for col in FLOW_METRICS:
            row[col] = float(sub[col].mean())
            row[f"{col}_error"] = float(sub[col].mean() - refsub[col].mean())
        rows.append(row)
    for _, t in flow[twin].iterrows():
        row = {"sample": f"twin {t.case_id}", "condition": "cohesionless twin", "k": 1}
        for col in FLOW_METRICS:
            row[col] = float(t[col])
            row[f"{col}_error"] = float(t[col] - ref[col].mean())
        rows.append(row)
    return pd.DataFrame(rows)
