#!/usr/bin/env python3
"""Where does ``steady_after: auto`` start the steady window, and should it? (issue 30)

The long prediction check (docs/results/prediction_check, ``workflows/prediction_check.yaml``,
6.4 s of production) had its automatic window start at the 50 % cap in 5 of 8 CG1 runs and
13 of 16 CG2 runs. The rule (:func:`ligwf.analysis.flow.steady.auto_fraction`) takes the last
frame whose 3-frame running mean leaves a band of 2 steady sds around the second half's level,
over the whole run, the reference half included. With correlated frames a chance crossing
somewhere is likely, and the more frames, the likelier. This measures it on synthetic runs
and beside it a standard truncation rule, MSER-5 (White 1997; batch means of 5 frames, the
truncation d minimising the remaining batch means' variance / (m - d)^2, d at most half the
run: :func:`ligwf.analysis.flow.steady.mser_index`; the later of the two signals, as the
current rule does).

Per cell: frames of production (40, 80, 160: 1.6, 3.2, 6.4 s at the demo's 0.04 s), AR(1)
phi of both signals (0.5, 0.8), an oscillation (none, or amplitude 1 sd with a period of 4
frames: the demo drum's 12 lifters at 30 rpm), and a start-up (none, or each signal starting
5 sds off and relaxing with a time constant of 4 frames: settled to 0.1 sd by frame 16).
Printed per rule: the share of runs whose window starts at the cap (>= 45 % of production),
the median start (fraction of production), and the bias of the window mean from the true
level in standard errors of that mean (mean over trials of (window mean - level) / se, se
from the true AR(1) variance of the window mean; 0 for a window free of start-up).

Registered before the first run (2026-12-06 03:30 UTC):

* H1: without a start-up, the current rule starts the window at the cap in >= 25 % of runs
  at 160 frames in every (phi, oscillation) cell, and that share grows from 40 to 160 frames.
* H2: MSER-5 starts it at the cap in <= 10 % of runs in every cell without a start-up, and
  with a start-up the bias of its window mean lies within +-0.5 standard errors in every cell.

    .venv/bin/python benchmarks/bench_steady.py            # ~1 min

The planner's extension rule (``--extension``, :func:`extension_check`; its hypotheses
H-ext1-3 registered in docs/results/steady/README.md on 2026-12-07 before their run; the
first run checked the first rule, a capped run's truncation taken as half its production,
the second the rule of :data:`~ligwf.analysis.records.steady_window.CAPPED_TRUNCATION`):

    .venv/bin/python -m benchmarks.bench_steady --extension --trials 20000 --seed 20261208 --capped-truncation 0.5
    .venv/bin/python -m benchmarks.bench_steady --extension --trials 20000 --seed 20261209

:func:`read_cells`, :func:`read_extension_cells` and :func:`hypotheses` read a printed run
back: the committed outputs in docs/results/steady, whose README scripts/kept_results.py
renders from them.
"""

from __future__ import annotations

import argparse
import itertools
import math
import re
import sys

import numpy as np

from benchmarks.bench_prediction import ar1_mean_variance
from ligwf.analysis.flow.steady import auto_fraction, mser_index
from ligwf.analysis.records.steady_window import (CAPPED_TRUNCATION, TARGET_SHARE, at_cap,
                                                  least_extension)

CAP_SHARE = 0.45        # a start at or after this fraction of production counts as capped
STARTUP_SDS, STARTUP_TAU = 5.0, 4.0
PERIOD = 4.0


def signal(rng, frames: int, phi: float, oscillation: float, startup: bool) -> np.ndarray:
    """One signal of unit stationary AR(1) sd around level 0, with an oscillation of random
    phase and a relaxing start-up offset (of random sign)."""
    x = np.empty(frames)
    x[0] = rng.standard_normal()
    e = rng.standard_normal(frames) * math.sqrt(1.0 - phi * phi)
    for t in range(1, frames):
        x[t] = phi * x[t - 1] + e[t]
    t = np.arange(frames)
    if oscillation:
        x += oscillation * np.sin(2.0 * math.pi * t / PERIOD + rng.uniform(0, 2 * math.pi))
    if startup:
        x += rng.choice((-1.0, 1.0)) * STARTUP_SDS * np.exp(-t / STARTUP_TAU)
    return x


def cell(rng, trials: int, frames: int, phi: float, oscillation: float, startup: bool):
    t = np.arange(frames, dtype=float)
    out = {"current": ([], []), "mser5": ([], [])}
    for _ in range(trials):
        sig = [signal(rng, frames, phi, oscillation, startup) for _ in range(2)]
        current = auto_fraction(t, sig, 0.0, float(frames))
        k_cur = int(math.ceil(current * frames - 1e-6))
        k_mser = max(mser_index(s) for s in sig)
        for name, k in (("current", k_cur), ("mser5", k_mser)):
            window = sig[0][k:]
            out[name][0].append(k / frames)
            # se of a stationary window's mean: its AR(1) part (an oscillation averages out)
            out[name][1].append(window.mean() / math.sqrt(ar1_mean_variance(len(window), phi)))
    return {name: (np.asarray(f), np.asarray(b)) for name, (f, b) in out.items()}


def extension_check(rng, trials: int, frames: int = 80, phi: float = 0.5,
                    tau: float = 16.0, capped_truncation: float = CAPPED_TRUNCATION) -> dict:
    """The planner's extension rule (``--extension``): runs of ``frames`` frames whose
    start-up (5 sds, relaxing with ``tau`` frames: settled to 0.1 sd only after ~4 tau)
    outlasts half of them, so ``auto`` starts their window at the cap; each capped run is
    continued by :func:`least_extension` (production >= 4 x the truncation, a capped run's
    truncation taken as ``capped_truncation`` of its production) and analysed again. Returned: the share capped before, the number of extended (capped) runs, the
    share of them still capped after, the median truncation after (fraction of the new
    production; the rule aims at <= TARGET_SHARE), the share of them truncated later than
    TARGET_SHARE, and the bias of the window mean after, in standard errors."""
    before, after, share, bias = [], [], [], []
    for _ in range(trials):
        longest = 6 * frames
        sig = []
        for _ in range(2):
            x = signal(rng, longest, phi, 0.0, False)
            x += rng.choice((-1.0, 1.0)) * STARTUP_SDS * np.exp(-np.arange(longest) / tau)
            sig.append(x)
        f = auto_fraction(np.arange(frames, dtype=float), [s[:frames] for s in sig], 0.0,
                          float(frames))
        before.append(at_cap(f))
        if not at_cap(f):
            continue
        n = frames + int(math.ceil(least_extension(f, float(frames), capped_truncation)))
        g = auto_fraction(np.arange(n, dtype=float), [s[:n] for s in sig], 0.0, float(n))
        after.append(at_cap(g))
        share.append(g)
        k = int(math.ceil(g * n - 1e-6))
        window = sig[0][k:n]
        bias.append(window.mean() / math.sqrt(ar1_mean_variance(len(window), phi)))
    nan = float("nan")
    return {"phi": phi, "tau": tau, "trials": trials, "before": float(np.mean(before)),
            "extended": len(after), "after": float(np.mean(after)) if after else nan,
            "median": float(np.median(share)) if share else nan,
            "late": float(np.mean(np.asarray(share) > TARGET_SHARE)) if share else nan,
            "bias": float(np.mean(bias)) if bias else nan}


#: registered 2026-12-07 (docs/results/steady/README.md), before the run with --seed 20261208
EXT_STILL_CAPPED = 0.05     # H-ext1: share of extended runs still at the cap, every cell
EXT_MEDIAN = TARGET_SHARE   # H-ext2: median truncation after, fraction of the new production
EXT_BIAS = 0.25             # H-ext3: |window-mean bias| after, standard errors


def extension_main(rng, trials: int, capped_truncation: float = CAPPED_TRUNCATION) -> None:
    """The extension check's table and its registered hypotheses (phi 0.5 cells; the phi 0.8
    cells are reported beside, without a criterion). The first run's rule (a capped run's
    truncation taken as 0.5 of production) prints the header it printed then."""
    taken = ("" if capped_truncation == 0.5 else
             f", a capped run's truncation taken as {capped_truncation:g} of its production")
    print(f"extension rule: 80 frames of production, {trials} trials a cell; capped = start "
          f">= {CAP_SHARE:.0%} of production; each capped run extended by least_extension "
          f"(production >= {1 / TARGET_SHARE:g} x the truncation{taken}) and analysed again; "
          f"median and late (share > {TARGET_SHARE:g}) of the truncation after, in the new "
          "production; bias = mean (window mean - level) / se")
    print(f"{'phi':>4} {'tau':>4} | {'trials':>6} {'capped':>6} | {'extended':>8} "
          f"{'capped':>6} {'median':>6} {'late':>6} {'bias':>6}")
    cells = []
    for phi in (0.5, 0.8):
        for tau in (12.0, 16.0, 24.0):
            c = extension_check(rng, trials, phi=phi, tau=tau,
                                capped_truncation=capped_truncation)
            cells.append(c)
            print(f"{phi:4.1f} {tau:4.0f} | {c['trials']:6d} {c['before']:6.3f} | "
                  f"{c['extended']:8d} {c['after']:6.3f} {c['median']:6.4f} {c['late']:6.3f} "
                  f"{c['bias']:6.2f}", flush=True)
    registered = [c for c in cells if c["phi"] == 0.5]
    verdict = {
        f"H-ext1 (phi 0.5: still at the cap after one extension <= {EXT_STILL_CAPPED:g} in "
        "every cell)": all(c["after"] <= EXT_STILL_CAPPED for c in registered),
        f"H-ext2 (phi 0.5: median truncation after <= {EXT_MEDIAN:g} of the new production "
        "in every cell)": all(c["median"] <= EXT_MEDIAN for c in registered),
        f"H-ext3 (phi 0.5: |window-mean bias| after <= {EXT_BIAS:g} se in every cell)":
            all(abs(c["bias"]) <= EXT_BIAS for c in registered),
    }
    for line, met in verdict.items():
        print(f"{line}: {'met' if met else 'not met'}")


#: a row of the main table as :func:`main` prints it
_CELL = re.compile(r"^\s*(\d+)\s+([\d.]+)\s+([\d.]+)\s+(yes|no) \|\s+([\d.]+)\s+[\d.]+\s+"
                   r"(-?[\d.]+) \|\s+([\d.]+)\s+[\d.]+\s+(-?[\d.]+)$")
#: a row of the extension table as :func:`extension_main` prints it
_EXTENSION_CELL = re.compile(r"^\s*([\d.]+)\s+(\d+) \|\s+(\d+)\s+([\d.]+) \|\s+(\d+)\s+"
                             r"([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+(-?[\d.]+)$")


def read_cells(text: str) -> list[dict]:
    """The cells of a printed :func:`main` run: frames, phi, start-up, and per rule the
    share capped and the bias (``current``, ``current_bias``, ``mser``, ``mser_bias``)."""
    rows = []
    for line in text.splitlines():
        m = _CELL.match(line)
        if m:
            rows.append({"frames": int(m.group(1)), "phi": float(m.group(2)),
                         "startup": m.group(4) == "yes",
                         "current": float(m.group(5)), "current_bias": float(m.group(6)),
                         "mser": float(m.group(7)), "mser_bias": float(m.group(8))})
    return rows


def read_extension_cells(text: str) -> list[dict]:
    """The cells of a printed :func:`extension_main` run: phi, tau and trials (numbers),
    and as printed (text): the share capped before, the runs extended (a number), the share
    still capped after, the median and late truncation and the bias."""
    rows = []
    for line in text.splitlines():
        m = _EXTENSION_CELL.match(line)
        if m:
            rows.append({"phi": float(m.group(1)), "tau": int(m.group(2)),
                         "trials": int(m.group(3)), "before": m.group(4),
                         "extended": int(m.group(5)), "after": m.group(6),
                         "median": m.group(7), "late": m.group(8), "bias": m.group(9)})
    return rows


def hypotheses(text: str) -> dict[str, bool]:
    """The verdict lines of a printed run: hypothesis -> holds (``holds`` / ``met``)."""
    found = re.findall(r"^(H[\w-]*) .*: (does not hold|holds|not met|met)$", text, re.M)
    return {name: verdict in ("holds", "met") for name, verdict in found}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=400)
    ap.add_argument("--seed", type=int, default=20261206)
    ap.add_argument("--extension", action="store_true",
                    help="check the planner's extension rule instead (extension_check)")
    ap.add_argument("--capped-truncation", type=float, default=CAPPED_TRUNCATION,
                    help="with --extension: the truncation taken for a capped run, as a "
                         "fraction of its production (0.5: the first rule's)")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    if args.extension:
        extension_main(rng, args.trials, args.capped_truncation)
        return 0
    print(f"steady-window start: {args.trials} trials a cell; capped = start >= "
          f"{CAP_SHARE:.0%} of production; bias = mean (window mean - level) / se")
    print(f"{'frames':>6} {'phi':>4} {'osc':>4} {'start-up':>8} | {'current':>7} {'median':>6} "
          f"{'bias':>6} | {'mser5':>7} {'median':>6} {'bias':>6}")
    h1 = h2 = True
    capped = {}
    for phi, osc, startup, frames in itertools.product((0.5, 0.8), (0.0, 1.0), (False, True),
                                                       (40, 80, 160)):
        c = cell(rng, args.trials, frames, phi, osc, startup)
        row = []
        for name in ("current", "mser5"):
            f, b = c[name]
            share = float(np.mean(f >= CAP_SHARE))
            row.append((share, float(np.median(f)), float(np.mean(b))))
            if name == "current" and not startup:
                capped[(phi, osc, frames)] = share
            if name == "mser5":
                h2 = h2 and (share <= 0.10 if not startup else abs(float(np.mean(b))) <= 0.5)
        print(f"{frames:6d} {phi:4.1f} {osc:4.1f} {'yes' if startup else 'no':>8} | "
              + " | ".join(f"{s:7.2f} {m:6.2f} {b:6.2f}" for s, m, b in row), flush=True)
    for phi, osc in itertools.product((0.5, 0.8), (0.0, 1.0)):
        at = [capped[(phi, osc, n)] for n in (40, 80, 160)]
        h1 = h1 and at[2] >= 0.25 and at[2] > at[0]
    print(f"H1 (current rule, no start-up: capped in >= 25 % at 160 frames, growing with "
          f"length): {'holds' if h1 else 'does not hold'}")
    print(f"H2 (MSER-5: capped in <= 10 % without a start-up, |bias| <= 0.5 se with one): "
          f"{'holds' if h2 else 'does not hold'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
