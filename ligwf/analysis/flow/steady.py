"""Steady window of a run: where the start-up of the production phase ends.

The study's ``analysis.steady_after`` is either a fraction of the production time (the
first ``steady_after`` of it is left out) or ``auto``: the window starts at the bed's
measured spin-up. Rule for ``auto`` (per case, on the production frames):

1. Signals: the signed flow angle (free-surface fit, deg) and the kinetic energy per unit
   mass of the bed (J/kg), one value per frame.
2. Their steady level and scatter are taken from the second half of the production time
   (assumed steady): mean m and standard deviation s per signal.
3. Runs of fewer than ``MSER_BATCH`` x ``MSER_MIN_BATCHES`` production frames: a running
   mean over ``RUNNING`` consecutive frames (ending at each frame) must stay within
   ``TOLERANCE`` x s of m from some frame on; the start of the steady window is the first
   frame k from which every later running mean stays within that band, for both signals
   (the later of the two).
   Longer runs: MSER-5 (White 1997; batch means of ``MSER_BATCH`` frames, the truncation
   that minimises the remaining batch means' sum of squares / (batches left)^2), the later
   of the two signals' points. Why not the band there: correlated frames cross it by chance
   somewhere, and the more frames, the likelier: on synthetic runs of 160 frames the band
   put the start of a stationary run at the cap in 0.20-0.89 of runs, MSER-5 in 0.02-0.05;
   below 16 batches MSER-5 is the worse rule (docs/results/steady).
4. The window never starts later than half the production time (the reference half), and
   a run with fewer than ``MIN_FRAMES`` production frames falls back to
   ``FALLBACK_FRACTION``.

The result is a fraction of the production time, so the flow metrics and the GSD use the
same steps (:meth:`ligwf.study.case.CaseFolder.steady_start_step` turns it into a step).

The start is tested, not assumed: a window that starts at the cap means the run is too
short to show a steady state; the verdict flags it and the planner sizes extensions by the
rule of :mod:`ligwf.analysis.records.steady_window` (production >= 4 x the truncation).
"""

from __future__ import annotations

import math

import numpy as np

from ligwf.analysis.records.steady_window import CAP

AUTO = "auto"
RUNNING = 3             # frames per running mean
TOLERANCE = 2.0         # band half-width in steady standard deviations
MIN_FRAMES = 6          # fewer production frames: use FALLBACK_FRACTION
FALLBACK_FRACTION = 0.25
MSER_BATCH = 5          # frames per batch mean of MSER-5
MSER_MIN_BATCHES = 16   # from this many batches on, MSER-5 instead of the running-mean band


def settled_index(signal: np.ndarray, running: int = RUNNING, tolerance: float = TOLERANCE) -> int:
    """First frame index from which the running mean of ``signal`` stays within
    ``tolerance`` steady standard deviations of the level of its second half."""
    x = np.asarray(signal, float)
    n = len(x)
    ref = x[n // 2:]
    ref = ref[np.isfinite(ref)]
    if len(ref) < 2:
        return 0
    level, scatter = float(np.mean(ref)), float(np.std(ref, ddof=1))
    filled = np.where(np.isfinite(x), x, level)
    kernel = np.ones(running) / running
    run = np.convolve(filled, kernel, mode="full")[:n]
    run[: running - 1] = [filled[: k + 1].mean() for k in range(min(running - 1, n))]
    outside = np.flatnonzero(np.abs(run - level) > tolerance * max(scatter, 1e-12 * abs(level)))
    return int(outside[-1] + 1) if len(outside) else 0


def mser_index(signal: np.ndarray, batch: int = MSER_BATCH) -> int:
    """MSER-``batch`` truncation point of ``signal`` in frames (a multiple of ``batch``, at
    most half the run): the d minimising sum((b_i - mean b)^2 over batches i >= d) /
    (batches - d)^2, b the batch means. Non-finite frames count at the second half's mean."""
    x = np.asarray(signal, float)
    ref = x[len(x) // 2:]
    ref = ref[np.isfinite(ref)]
    if len(ref) == 0:
        return 0
    x = np.where(np.isfinite(x), x, float(np.mean(ref)))
    m = len(x) // batch
    if m < 2:
        return 0
    b = x[: m * batch].reshape(m, batch).mean(axis=1)
    best, arg = np.inf, 0
    for d in range(0, min(m // 2, (len(x) // 2) // batch) + 1):
        rest = b[d:]
        stat = float(np.sum((rest - rest.mean()) ** 2)) / len(rest) ** 2
        if stat < best:
            best, arg = stat, d
    return arg * batch


def auto_fraction(times: np.ndarray, signals: list[np.ndarray], production_start: float,
                  production_time: float) -> float:
    """Steady start as a fraction of the production time (see the module docstring).

    ``times`` (s) of the production frames, ``signals`` one array per signal on those
    frames, ``production_start`` and ``production_time`` in s.
    """
    t = np.asarray(times, float)
    if len(t) < MIN_FRAMES or production_time <= 0:
        return FALLBACK_FRACTION
    if len(t) >= MSER_BATCH * MSER_MIN_BATCHES:
        k = max(mser_index(s) for s in signals)
    else:
        k = max(settled_index(s) for s in signals)
    k = min(k, len(t) // 2)
    frac = (t[k] - production_start) / production_time
    # just below the frame time, so the frame itself is inside the window
    return float(min(max(frac - 1e-9, 0.0), CAP))


def is_auto(steady_after) -> bool:
    """True for the ``auto`` setting (a number is a fixed fraction)."""
    return isinstance(steady_after, str) and steady_after == AUTO


def describe(steady_after, fraction: float) -> str:
    """One line for the report: the rule and the fraction it gave."""
    if is_auto(steady_after):
        return (f"auto: {100 * fraction:.0f} % of production left out (measured spin-up, "
                "ligwf.analysis.flow.steady)")
    return f"fixed: {100 * fraction:.0f} % of production left out"

