"""Granules followed in time: measures that a plug or a tiling cannot pass by construction.

The granules at a start frame t are the held granules of a window [t, t + W]
(:func:`ligwf.analysis.granules.persistent.persistent_labels`), but the window's frames are
taken at a fixed ``cadence`` (s), not at every dumped frame: a bridge must be present at
t, t + c, t + 2c, ... t + W. Sampled so, the definition does not depend on how often the
run dumped (0.01 s or 0.05 s give the same granules when both divide c); the same measure at
another cadence is the check of how much it would have depended.

What a granule must show, and when it is measured (docs/results/granule_growth/criterion.md):

- **survival**: of the particle pairs that share a granule of >= ``min_particles`` at t, the
  share that share a granule at t' = t + W + T/4, whose window [t', t' + W] does not overlap
  the first one (inside the first window every held pair is together by definition);
- **co-movement**: member pairs against non-member pairs at the same initial distance, over
  [t + W, t + W + T/4], after the window that selected them;
- **wall share**: the share of the granules' volume within ``wall_band`` CG1 diameters of the
  shell, against the bed's own share there (a plug that turns with the drum leaves held
  fragments along the wall);
- **percolation**: a granule that wraps the periodic slice;
- **growth**: share and size against time (:func:`hac_slope`), and the events between
  successive start frames (:func:`track`): accretion, erosion, breakage, coalescence.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from ligwf.analysis.granules.controls import bed_share, comovement, granule_count, granule_sizes
from ligwf.analysis.granules.control_run import Series
from ligwf.analysis.granules.persistent import bridge_keys, persistent_labels
from ligwf.errors import ConfigError


@dataclass(frozen=True)
class GrowthSettings:
    """How the granules of a run are followed (times in s, physical: the same at every CG)."""

    hold_time: float = 0.5        # W: a bridge must hold through [t, t + W]
    cadence: float = 0.05         # s between the frames a window is sampled at
    stride: float = 0.1           # s between start frames
    start_after: float = 0.5      # s of production before the first start frame
    min_particles: int = 10       # a granule has at least this many particles
    wall_band: float = 1.5        # CG1 diameters from the shell: the wall layer

    def __post_init__(self) -> None:
        for name in ("hold_time", "cadence", "stride"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ConfigError(f"growth.{name} = {value!r}: must be a finite time > 0 s")
        if self.cadence > self.hold_time:
            raise ConfigError(f"growth.cadence = {self.cadence!r}: must be <= hold_time "
                              f"{self.hold_time!r} (a window needs two frames at least)")
        if self.min_particles < 2:
            raise ConfigError(f"growth.min_particles = {self.min_particles!r}: must be >= 2")


def frames_spanning(series: Series, seconds: float) -> int:
    """Frames spanning ``seconds``; refuses a time that is not a whole number of intervals
    (a cadence of 0.05 s on frames every 0.02 s would sample unevenly)."""
    exact = seconds / series.interval
    k = int(round(exact))
    if k < 1 or abs(exact - k) > 1e-3 * max(1.0, exact):
        raise ConfigError(f"{series.facts.case_id}: {seconds:g} s is not a whole number of "
                          f"the run's {series.interval:g} s frame intervals")
    return k


class HeldAt:
    """Held granules at a frame index, each window sampled at the cadence; bridge keys are
    found once per frame and shared by every window that uses it."""

    def __init__(self, series: Series, hold_time: float, cadence: float):
        self.series = series
        self.step = frames_spanning(series, cadence)
        self.span = frames_spanning(series, hold_time)
        if self.span % self.step:
            raise ConfigError(f"growth.hold_time = {hold_time:g} s: not a whole number of "
                              f"cadences of {cadence:g} s")
        self._keys: dict[int, np.ndarray] = {}
        self._labels: dict[int, object] = {}

    def _key(self, k: int) -> np.ndarray:
        if k not in self._keys:
            self._keys[k] = bridge_keys(self.series.frames[k], self.series.facts.liquid)
        return self._keys[k]

    def __call__(self, k: int):
        """The :class:`~ligwf.analysis.granules.bonds.Identification` at frame k, or None when
        its window runs past the last frame."""
        if k + self.span >= len(self.series.frames):
            return None
        if k not in self._labels:
            ks = list(range(k, k + self.span + 1, self.step))
            frames = [self.series.frames[q] for q in ks]
            self._labels[k] = persistent_labels(frames, [self._key(q) for q in ks],
                                                self.series.facts.motion)
        return self._labels[k]


def big_labels(labels: np.ndarray, min_particles: int) -> np.ndarray:
    """The labels with every granule smaller than ``min_particles`` split into singletons
    (negative labels, one per particle): pairs then share a label only inside a big granule."""
    labels = np.asarray(labels, dtype=np.int64)
    small = granule_sizes(labels) < min_particles
    out = labels.copy()
    out[small] = -1 - np.flatnonzero(small)
    return out


def survival(labels_t: np.ndarray, labels_u: np.ndarray, min_particles: int) -> float:
    """Of the pairs sharing a granule of >= ``min_particles`` at t, the share sharing any
    granule at u (rows the same particles; nan without such a granule at t)."""
    big = granule_sizes(labels_t) >= min_particles
    if not big.any():
        return float("nan")
    a = np.asarray(labels_t)[big]
    b = np.asarray(labels_u)[big]
    _, n_a = np.unique(a, return_counts=True)
    pairs_t = float(np.sum(n_a * (n_a - 1) / 2.0))
    joint = a.astype(np.int64) * (int(b.max()) + 1) + (b.astype(np.int64) - int(b.min()))
    _, n_ab = np.unique(joint, return_counts=True)
    return float(np.sum(n_ab * (n_ab - 1) / 2.0)) / pairs_t


def wall_shares(positions: np.ndarray, volumes: np.ndarray, labels: np.ndarray,
                rotation_axis: int, radius: float, band: float, min_particles: int
                ) -> tuple[float, float]:
    """(granule, bed): the share of granule volume (granules of >= ``min_particles``) and of
    the whole bed's volume whose centres lie within ``band`` (m) of the shell of ``radius``
    (m) about ``rotation_axis`` through the origin (nan granule share without granules)."""
    plane = [a for a in range(3) if a != rotation_axis]
    r = np.hypot(positions[:, plane[0]], positions[:, plane[1]])
    near = (radius - r) < band
    bed = float(volumes[near].sum() / volumes.sum())
    big = granule_sizes(labels) >= min_particles
    if not big.any():
        return float("nan"), bed
    return float(volumes[big & near].sum() / volumes[big].sum()), bed


def volume_d50_particles(labels: np.ndarray, volumes: np.ndarray, min_particles: int = 2
                         ) -> float:
    """Volume-weighted median granule size in particles (granules of >= ``min_particles``;
    nan without one): half the granule volume is in granules at least this large."""
    labels = np.asarray(labels, dtype=np.int64)
    uniq, inverse, counts = np.unique(labels, return_inverse=True, return_counts=True)
    keep = counts >= min_particles
    if not keep.any():
        return float("nan")
    vol = np.bincount(inverse, weights=volumes)[keep]
    size = counts[keep].astype(float)
    order = np.argsort(size)
    cum = np.cumsum(vol[order]) / vol.sum()
    return float(size[order][np.searchsorted(cum, 0.5)])


def growth_rows(series: Series, settings: GrowthSettings = GrowthSettings(),
                radius: float | None = None) -> pd.DataFrame:
    """One row per start frame: the measures of the module docstring. ``radius``: the drum
    radius, m (None: no wall test)."""
    facts = series.facts
    if not facts.omega:
        raise ConfigError(f"{facts.case_id}: the drum's rotation rate is unknown; the growth "
                          "measures are timed in revolutions")
    period = 2.0 * np.pi / abs(facts.omega)
    held = HeldAt(series, settings.hold_time, settings.cadence)
    quarter = max(1, int(round(0.25 * period / series.interval)))
    after = held.span + quarter            # t' = t + W + T/4: its window starts after ours ends
    stride = frames_spanning(series, settings.stride)
    starts = [k for k in range(len(series.frames))
              if series.times[k] >= settings.start_after - 1e-9][::stride]
    volumes = series.frames[0].particles.volumes
    d_cg1 = series.diameter / facts.cg
    rows = []
    previous = None
    for k in starts:
        ident = held(k)
        if ident is None:
            break
        labels = ident.labels
        sizes = granule_sizes(labels)
        row = {"case_id": facts.case_id, "time": float(series.times[k]),
               "revolutions": float(series.times[k] / period),
               "share_2": bed_share(labels, volumes, 2),
               "share_10": bed_share(labels, volumes, settings.min_particles),
               "count_10": granule_count(labels, settings.min_particles),
               "d50_particles": volume_d50_particles(labels, volumes, 2),
               "largest": int(sizes.max()) if len(sizes) else 0,
               "spanning": bool(np.any(ident.percolating))}
        later = held(k + after)
        row["survival"] = (survival(labels, later.labels, settings.min_particles)
                           if later is not None else np.nan)
        k0, k1 = k + held.span, k + held.span + quarter
        if k1 < len(series.frames):
            cm = comovement(big_labels(labels, settings.min_particles),
                            series.frames[k0].particles.positions,
                            series.frames[k1].particles.positions, series.diameter,
                            facts.periodic_column, facts.box_length)
            row["comove_ratio"] = cm.ratio
        else:
            row["comove_ratio"] = np.nan
        if radius is not None:
            row["wall_share"], row["bed_wall_share"] = wall_shares(
                series.frames[k].particles.positions, volumes, labels, facts.rotation_axis.index,
                radius, settings.wall_band * d_cg1, settings.min_particles)
        events = (track(previous.labels, labels, settings.min_particles)
                  if previous is not None else None)
        for name in Events.__dataclass_fields__:
            row[name] = getattr(events, name) if events is not None else np.nan
        previous = ident
        rows.append(row)
    return pd.DataFrame(rows)


@dataclass(frozen=True)
class Events:
    """What happened to the granules between two start frames (:func:`track`)."""

    continued: int      # granules with exactly one successor that has exactly one predecessor
    born: int           # granules at u without a predecessor
    died: int           # granules at t without a successor
    broke: int          # granules at t with two or more successors
    coalesced: int      # granules at u with two or more predecessors
    accreted: int       # particles in a granule at u that were in none of its predecessors
    eroded: int         # particles of a granule at t that are in none of its successors
    dispersed: int      # particles of the granules at t without a successor


def track(labels_t: np.ndarray, labels_u: np.ndarray, min_particles: int) -> Events:
    """Match the granules (>= ``min_particles``) at t to those at u by shared members: g at t
    and h at u are linked when they share at least half the members of the smaller one."""
    a = big_labels(labels_t, min_particles)
    b = big_labels(labels_u, min_particles)
    ga, na = np.unique(a[a >= 0], return_counts=True)
    gb, nb = np.unique(b[b >= 0], return_counts=True)
    size_a, size_b = dict(zip(ga.tolist(), na.tolist())), dict(zip(gb.tolist(), nb.tolist()))
    both = (a >= 0) & (b >= 0)
    pairs, shared = np.unique(np.stack([a[both], b[both]], axis=1), axis=0, return_counts=True)
    links = [(int(g), int(h)) for (g, h), s in zip(pairs, shared)
             if 2 * s >= min(size_a[int(g)], size_b[int(h)])]
    succ: dict[int, list[int]] = {g: [] for g in size_a}
    pred: dict[int, list[int]] = {h: [] for h in size_b}
    for g, h in links:
        succ[g].append(h)
        pred[h].append(g)
    continued = sum(1 for g, hs in succ.items() if len(hs) == 1 and len(pred[hs[0]]) == 1)
    accreted = eroded = dispersed = 0
    for h, gs in pred.items():
        members_h = b == h
        accreted += int(np.sum(members_h & ~np.isin(a, gs))) if gs else 0
    for g, hs in succ.items():
        members_g = a == g
        if hs:
            eroded += int(np.sum(members_g & ~np.isin(b, hs)))
        else:
            dispersed += int(np.sum(members_g))
    return Events(continued=continued, born=sum(1 for gs in pred.values() if not gs),
                  died=sum(1 for hs in succ.values() if not hs),
                  broke=sum(1 for hs in succ.values() if len(hs) >= 2),
                  coalesced=sum(1 for gs in pred.values() if len(gs) >= 2),
                  accreted=accreted, eroded=eroded, dispersed=dispersed)


@dataclass(frozen=True)
class Slope:
    """An ordinary least-squares slope with a 95 % interval from Newey-West standard errors."""

    slope: float
    low: float
    high: float
    points: int


def hac_slope(t: np.ndarray, y: np.ndarray, lag: int, level: float = 0.95) -> Slope:
    """Slope of y against t with an interval robust to autocorrelation up to ``lag`` points
    (Newey-West, Bartlett weights; t quantile on n - 2 degrees of freedom). Overlapping
    windows make successive start frames correlated; an OLS interval would be too narrow."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    ok = np.isfinite(t) & np.isfinite(y)
    t, y = t[ok], y[ok]
    n = len(t)
    if n < 3:
        return Slope(float("nan"), float("nan"), float("nan"), n)
    x = np.column_stack([np.ones(n), t])
    xtx_inv = np.linalg.inv(x.T @ x)
    beta = xtx_inv @ x.T @ y
    e = y - x @ beta
    xe = x * e[:, None]
    s = xe.T @ xe
    for lag_k in range(1, min(lag, n - 1) + 1):
        w = 1.0 - lag_k / (lag + 1.0)
        g = xe[lag_k:].T @ xe[:-lag_k]
        s += w * (g + g.T)
    cov = xtx_inv @ s @ xtx_inv
    se = math.sqrt(max(cov[1, 1], 0.0))
    q = float(stats.t.ppf(0.5 + level / 2.0, n - 2))
    return Slope(float(beta[1]), float(beta[1] - q * se), float(beta[1] + q * se), n)
