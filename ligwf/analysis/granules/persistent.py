"""Granules that survive: components of the liquid bridges that held through a time window.

A frame alone cannot tell a granule from a patch of a dense bed: every particle of a wet
bed touches its neighbours through bridges, so components of one frame's bridges span the
bed, and any cut of that graph (CPM communities) tiles it at a size set by the cut, in a
cohesionless bed as in a wet one (docs/results/granule_definitions.md). What a granule has
and a patch has not is a history: its bridges hold while the bed around it moves.

:func:`persistent_labels` takes the frames of a window [t, t + W] and keeps a bridge only
when the same pair is bridged (gap below the engine's rupture distance, F > 0) in every
frame of it; granules at t are the connected components of those bridges, unwrapped and
tested for percolation along the periodic axis like any other granules
(:func:`ligwf.analysis.granules.bonds.components`). ``passage_speed`` (optional) keeps only the
bridges of which a partner moved faster than that relative to the drum's rigid rotation
in some frame of the window: contacts of the co-rotating plug then do not count until they
have been through the flowing layer, where a bed without cohesion loses them.

The result is deterministic (no optimiser; the order of the contact rows cannot matter),
and CG-neutral when W is a fixed physical time (the flow, not the particle, sets it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ligwf.analysis.granules.definitions import Motion, drum_frame_velocities
from ligwf.analysis.frames.dumps import ContactFrame, ParticleFrame
from ligwf.analysis.granules.bonds import BondCriterion, Identification, bonded_contacts, components
from ligwf.analysis.granules.bridge_law import Liquid

#: every bridge the engine still holds counts (no force or velocity-angle filter)
ALL_BRIDGES = BondCriterion(0.0, 180.0)


@dataclass(frozen=True)
class Frame:
    """One dumped frame: its particles (rows in id order) and contacts."""

    particles: ParticleFrame
    contacts: ContactFrame


def bridge_keys(frame: Frame, liquid: Liquid) -> np.ndarray:
    """Sorted unique keys min(i, j) * N + max(i, j) of the frame's bridges (particle rows)."""
    i, j, _ = bonded_contacts(frame.particles, frame.contacts, liquid, ALL_BRIDGES)
    n = len(frame.particles)
    lo, hi = np.minimum(i, j).astype(np.int64), np.maximum(i, j).astype(np.int64)
    keys = np.sort(lo * n + hi)
    # = np.unique(keys), whose hashing path in numpy 2.4 took 1.4 s at 1.2 M bridges
    # against 0.02 s for this sort and compare
    return keys[np.concatenate(([True], keys[1:] != keys[:-1]))] if len(keys) else keys


def held_through(keys: list[np.ndarray]) -> np.ndarray:
    """Keys present in every one of ``keys`` (the bridges that held through the window)."""
    if not keys:
        return np.zeros(0, dtype=np.int64)
    out = keys[0]
    for k in keys[1:]:
        out = np.intersect1d(out, k, assume_unique=True)
    return out


def presence_run(keys: np.ndarray, previous: np.ndarray | None,
                 previous_run: np.ndarray | None) -> np.ndarray:
    """Per key of a frame (sorted unique, :func:`bridge_keys`): in how many consecutive
    frames up to this one it is present, given the previous frame's keys and runs (None:
    this frame starts the count). The bridges held through the last s + 1 frames are
    ``keys[run >= s + 1]``, the same sorted set :func:`held_through` finds over those
    frames, at one search of one frame per frame instead of s intersections per frame."""
    run = np.ones(len(keys), dtype=np.int64)
    if previous is None or len(previous) == 0 or len(keys) == 0:
        return run
    at = np.minimum(np.searchsorted(previous, keys), len(previous) - 1)
    found = previous[at] == keys
    run[found] += previous_run[at[found]]
    return run


def passed_flowing_layer(frames: list[Frame], motion: Motion, speed: float) -> np.ndarray:
    """Per particle row: True where it moved faster than ``speed`` (m/s) relative to the
    drum's rigid rotation in any of ``frames``."""
    out = np.zeros(len(frames[0].particles), dtype=bool)
    for f in frames:
        v = drum_frame_velocities(f.particles, motion)
        out |= np.einsum("ij,ij->i", v, v) > speed * speed
    return out


def persistent_labels(frames: list[Frame], keys: list[np.ndarray], motion: Motion,
                      passage_speed: float | None = None) -> Identification:
    """Granules at ``frames[0]``: components of the bridges present in every frame of the
    window (``keys[k]``: :func:`bridge_keys` of ``frames[k]``), optionally only those of
    which a partner passed the flowing layer (:func:`passed_flowing_layer`)."""
    if len(frames) != len(keys) or not frames:
        raise ValueError(f"{len(frames)} frames and {len(keys)} key sets: one each, >= 1")
    first = frames[0].particles
    n = len(first)
    for f in frames[1:]:
        if len(f.particles) != n or not np.array_equal(f.particles.ids, first.ids):
            raise ValueError(f"{f.particles.path}: not the particles of {first.path} "
                             "(a persistence window needs the same particles in every frame)")
    held = held_through(keys)
    i, j = held // n, held % n
    if passage_speed is not None:
        passed = passed_flowing_layer(frames, motion, passage_speed)
        keep = passed[i] | passed[j]
        i, j = i[keep], j[keep]
    return components(first.positions, i, j, None, motion.periodic_column, motion.length)
