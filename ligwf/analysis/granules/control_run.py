"""The granule controls of one run: every candidate definition, measured by the same code.

For each start frame t of the steady window and each definition, :func:`control_rows`
gives the granules at t and measures them (:mod:`ligwf.analysis.granules.controls`): share of the
bed in granules of >= 2 and >= 10 particles, granule count, d50, pair persistence after
``short_dt`` and after a quarter revolution, co-movement over a quarter revolution and whether a
granule percolates (``percolating_frames``: 1 or 0 in a row of one frame, so that the mean
over the rows is the share of frames holding a percolating granule). Survival and
co-movement start when the definition's window ends: a held granule at t is selected by
bridges present through [t, t + W], so its pairs are together until t + W by construction;
its persistence compares it with the granules of the window that starts at t + W + T/4,
and its co-movement is measured over [t + W, t + W + T/4] (W = 0 for a definition of one
frame); for definitions with an optimiser or an order dependence, the adjusted
Rand index across seeds and across a shuffled contact order. :func:`summarise` averages
the rows per definition. The same table of a wet bed beside its cohesionless twin says
whether a definition finds granules or a tiling.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from ligwf.analysis.granules.case import RunFacts
from ligwf.analysis.granules.controls import (adjusted_rand_index, bed_share, comovement, granule_count,
                                     granule_sizes, pair_persistence, volume_d50)
from ligwf.analysis.granules.definitions import identify_granules
from ligwf.analysis.frames.dumps import ContactFrame, read_contacts, read_particles
from ligwf.analysis.frames.checks import plan_frames
from ligwf.analysis.granules.bonds import Identification
from ligwf.analysis.granules.persistent import Frame, bridge_keys, persistent_labels
from ligwf.errors import DumpReadError
from ligwf.scene.settings import AnalysisSettings
from ligwf.study.case import CaseFolder

#: definitions measured by default: name -> (kind, parameter)
DEFAULT_CANDIDATES = (
    ("communities", "frame", AnalysisSettings(granules="communities")),
    ("source_components_angle30", "frame",
     AnalysisSettings(granules="components", max_velocity_angle=30.0)),
    ("bridge_components", "frame", AnalysisSettings(granules="components")),
    ("held_0.1s", "window", (0.1, None)),
    ("held_0.25s", "window", (0.25, None)),
    ("held_0.5s", "window", (0.5, None)),
    ("held_0.5s_flowing", "window", (0.5, 0.5)),
    ("held_1s", "window", (1.0, None)),
)


@dataclass(frozen=True)
class Series:
    """The production frames of one run, in time order."""

    facts: RunFacts
    frames: tuple[Frame, ...]
    times: np.ndarray            # s since production start
    wall_speed: float            # m/s, omega R of the drum shell
    diameter: float              # m, mean particle diameter

    @property
    def interval(self) -> float:
        """s between frames."""
        return float(np.median(np.diff(self.times))) if len(self.times) > 1 else float("nan")

    def frames_in(self, seconds: float) -> int:
        """Frames spanning ``seconds`` (at least one interval)."""
        return max(1, int(round(seconds / self.interval)))


def load_series(case_dir: Path) -> Series:
    """Every planned production frame of a ligwf case, read and checked like the granule
    analysis reads them (frames refused by the plan are left out)."""
    case = CaseFolder.open(case_dir)
    plan = plan_frames(case)
    facts = RunFacts.of_case(case, plan)
    frames, steps = [], []
    for ff in plan.frames:
        if ff.contacts is None:
            raise DumpReadError(f"{ff.particles}: no contact dump (controls need bridges)")
        p = read_particles(ff.particles, ff.step, facts.dt)
        c = read_contacts(ff.contacts, ff.step)
        frames.append(Frame(p, c))
        steps.append(ff.step)
    start = case.production_start_step
    times = (np.asarray(steps) - start) * facts.dt
    s = case.scaled
    return Series(facts, tuple(frames), times, float(s.drum.omega) * 0.5 * float(s.drum.diameter),
                  float(2.0 * np.mean(frames[0].particles.radii)))


def _shuffled(c: ContactFrame, seed: int) -> ContactFrame:
    order = np.random.default_rng(seed).permutation(len(c))
    return replace(c, id1=c.id1[order], id2=c.id2[order], delta=c.delta[order])


def labeller(series: Series, kind: str, param,
             keys: dict[tuple[int, bool], np.ndarray] | None = None
             ) -> Callable[[int, bool, int], Identification | None]:
    """granules(k, shuffled, seed): the granules at frame k (None when the window runs past
    the last frame); ``shuffled``: the contact rows in another order; ``seed``: the
    optimiser seed (communities only). ``keys``: bridge keys per (frame, shuffled), shared
    by every windowed definition of one series (each frame's bridges are found once)."""
    facts = series.facts
    motion = facts.motion
    if kind == "frame":
        def frame_labels(k: int, shuffled: bool = False, seed: int = 0):
            f = series.frames[k]
            contacts = _shuffled(f.contacts, 1 + seed) if shuffled else f.contacts
            d = (param.model_copy(update={"community_seed": seed})
                 if param.granules == "communities" else param)
            return identify_granules(f.particles, contacts, facts.liquid, d, facts.cg, motion)
        return frame_labels
    window, passage = param
    span = series.frames_in(window)
    keys = {} if keys is None else keys

    def key(k: int, shuffled: bool) -> np.ndarray:
        if (k, shuffled) not in keys:
            f = series.frames[k]
            frame = Frame(f.particles, _shuffled(f.contacts, 1)) if shuffled else f
            keys[(k, shuffled)] = bridge_keys(frame, facts.liquid)
        return keys[(k, shuffled)]

    def window_labels(k: int, shuffled: bool = False, seed: int = 0):
        if k + span >= len(series.frames):
            return None
        ks = list(range(k, k + span + 1))
        speed = None if passage is None else passage * series.wall_speed
        return persistent_labels([series.frames[q] for q in ks], [key(q, shuffled) for q in ks],
                                 motion, speed)
    return window_labels


def growth_rates(labels: np.ndarray, later: np.ndarray | None, dt: float,
                 min_particles: int = 10) -> dict[str, float]:
    """Accretion and erosion rates, 1/s: the particles that join granules of >=
    ``min_particles`` between t and t + dt (``accretion``) or leave them (``erosion``), per
    particle in such granules at t and per second (nan without granules or a later frame)."""
    if later is None:
        return {"accretion_rate": np.nan, "erosion_rate": np.nan}
    inside_t = granule_sizes(labels) >= min_particles
    inside_u = granule_sizes(later) >= min_particles
    n = int(inside_t.sum())
    if n == 0:
        return {"accretion_rate": np.nan, "erosion_rate": np.nan}
    return {"accretion_rate": float((~inside_t & inside_u).sum()) / n / dt,
            "erosion_rate": float((inside_t & ~inside_u).sum()) / n / dt}


def control_rows(series: Series, candidates=DEFAULT_CANDIDATES, steady_from: float = 0.5,
                 stride: float = 0.1, short_dt: float = 0.05,
                 determinism_frames: int = 2) -> pd.DataFrame:
    """One row per (definition, start frame): the measures of the module docstring."""
    facts = series.facts
    quarter = 0.25 * 2.0 * np.pi / facts.omega if facts.omega else float("nan")
    d_short, d_quarter = series.frames_in(short_dt), series.frames_in(quarter)
    starts = [k for k in range(len(series.frames)) if series.times[k] >= steady_from - 1e-9]
    starts = starts[::series.frames_in(stride)]
    volumes = series.frames[0].particles.volumes
    axis, length = facts.periodic_column, facts.box_length
    rows = []
    shared_keys: dict[tuple[int, bool], np.ndarray] = {}
    for name, kind, param in candidates:
        labels_of = labeller(series, kind, param, shared_keys)
        # frames the definition's own window spans (0 for one-frame definitions)
        span = series.frames_in(param[0]) if kind == "window" else 0
        cache: dict[int, Identification | None] = {}

        def lab(k: int) -> np.ndarray | None:
            if k >= len(series.frames):
                return None
            if k not in cache:
                cache[k] = labels_of(k, False, 0)
            return None if cache[k] is None else cache[k].labels

        for n_start, k in enumerate(starts):
            labels = lab(k)
            if labels is None:
                continue
            row = {"definition": name, "case_id": facts.case_id, "time": series.times[k],
                   "share_2": bed_share(labels, volumes, 2),
                   "share_10": bed_share(labels, volumes, 10),
                   "count_10": granule_count(labels, 10),
                   "d50_mm": 1e3 * volume_d50(labels, volumes, 10),
                   "largest_share": float(np.bincount(labels, weights=volumes).max() / volumes.sum()),
                   "percolating_frames": float(np.any(cache[k].percolating))}
            for tag, dk in (("persist_short", d_short), ("persist_quarter", d_quarter)):
                later = lab(k + span + dk)
                row[tag] = pair_persistence(labels, later) if later is not None else np.nan
                if tag == "persist_short":
                    row.update(growth_rates(labels, later, (span + dk) * series.interval))
            if k + span + d_quarter < len(series.frames):
                cm = comovement(labels, series.frames[k + span].particles.positions,
                                series.frames[k + span + d_quarter].particles.positions,
                                series.diameter, axis, length)
                row["comove_ratio"] = cm.ratio
            else:
                row["comove_ratio"] = np.nan
            if n_start < determinism_frames:
                row["ari_order"] = adjusted_rand_index(labels, labels_of(k, True, 0).labels)
                if kind == "frame" and param.granules == "communities":
                    row["ari_seed"] = adjusted_rand_index(labels, labels_of(k, False, 1).labels)
            rows.append(row)
    return pd.DataFrame(rows)


def summarise(rows: pd.DataFrame) -> pd.DataFrame:
    """Means per (case, definition) of every measure."""
    cols = [c for c in rows.columns if c not in ("definition", "case_id", "time")]
    out = rows.groupby(["case_id", "definition"], sort=False)[cols].mean(numeric_only=True)
    out["frames"] = rows.groupby(["case_id", "definition"], sort=False).size()
    return out.reset_index()
