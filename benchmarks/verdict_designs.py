"""Error rates of the verdict's rules on the designs users run (issue 45 item 2), the part of
``benchmarks/bench_coverage.py --designs`` (its pass criteria are registered in
``docs/results/verdict_rates/README.md`` before the run).

Runs are AR(1) frame series plus a replica offset, as in the coverage cells
(:func:`bench_coverage.ar1_runs`); a run's value is its window mean. Each design is decided
with the verdict's own functions (:mod:`ligwf.inference.equivalence`,
:mod:`ligwf.inference.shares`, Holm's step-down) under the single-look rules:
alpha 0.05, Welch's df for equal arms and Hsu's for unequal ones (``--df-rule``: or the
Behrens-Fisher distribution for unequal ones), two-sided fail tests.

* ``unequal``: CG-n / CG1 arms of 6 / 2 (the demo) and 24 / 3 (the ladder) runs, the CG-n
  seed offset 0.5, 1 or 2 times CG1's: the 95 % interval of CG-n - CG1 and the one-sided
  coverage of the 90 % interval's lower bound (interval cells), the wrong pass with the
  truth on the budget and the wrong fail with the truth on the budget or at 0.
* ``all-zero``: a rigid-block share that is 0 in most runs: a CG-n run has a share ``s``
  with probability q (else 0), CG1 runs read 0; the mean difference q s sits on the budget
  0.05. Wrong pass under this rule and under the registered one ("pass 0 [0, 0]").
* ``family``: a level with three signed criteria and the velocity profile, each exactly on
  its budget (any decision is wrong): how often the level meets or fails, with Holm over
  every tested criterion (this rule) and over the signed ones plus profile fails at p = 0
  with one-sided fail tests (the registered rule).
* ``levels``: four levels sharing their CG1 runs, each with one criterion exactly on its
  budget: how often some level meets (the cheapest-level sentence names one), against the
  bound 4 alpha the verdict discloses, and with each level tested at alpha / 4 (Bonferroni
  over levels).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy import stats

from benchmarks.bench_coverage import ar1_runs
from ligwf.inference import equivalence as eq
from ligwf.inference.shares import share_test

ALPHA = eq.ALPHA
LOW, HIGH = 0.92, 0.99
FRAMES, PHI = 50, 0.6
BINS = 8


def lower_bound(rate: float, trials: int) -> float:
    """Lower 95 % Clopper-Pearson bound of a share measured in ``trials`` trials: a rate
    cell fails its registered criterion when this is above its alpha."""
    k = round(rate * trials)
    return 0.0 if k == 0 else float(stats.beta.ppf(0.05, k, trials - k + 1))


def _means(rng, trials: int, runs: int, offset: float) -> np.ndarray:
    return ar1_runs(rng, trials, runs, FRAMES, PHI, offset).mean(axis=2)


def unequal_cells(rng, trials: int, rule: str = eq.WELCH_EQUAL) -> list[dict]:
    out = []
    for (nx, ny), scale, offset, budget in itertools.product(
            ((6, 2), (24, 3)), (0.5, 1.0, 2.0), (0.0, 1.0), (0.5, 1.0, 3.0)):
        x0 = _means(rng, trials, nx, offset * scale) if offset else (
            scale * _means(rng, trials, nx, 0.0))
        y = _means(rng, trials, ny, offset)
        diff = tost = wp = wf_on = wf_zero = 0
        for i in range(trials):
            d95 = eq.difference_estimate(x0[i], y[i], 0.025, rule)
            diff += d95.lo <= 0.0 <= d95.hi
            d90 = eq.difference_estimate(x0[i], y[i], ALPHA, rule)
            tost += d90.lo <= 0.0
            wf_zero += eq.equivalence(d90, budget).state == eq.FAIL
            on = eq.difference_estimate(x0[i] + budget, y[i], ALPHA, rule)
            state = eq.equivalence(on, budget).state
            wp += state == eq.PASS
            wf_on += state == eq.FAIL
        out.append({"design": f"{nx} vs {ny}", "scale": scale, "offset": offset,
                    "budget": budget, "diff": diff / trials, "tost": tost / trials,
                    "wrong pass": wp / trials,
                    "wrong fail": max(wf_on, wf_zero) / trials})
    return out


def all_zero_cells(rng, trials: int, budget: float = 0.05, rule: str = eq.WELCH_EQUAL
                   ) -> list[dict]:
    out = []
    for (nx, ny), s in itertools.product(((3, 3), (6, 2), (24, 3), (60, 60)), (1.0, 0.2)):
        q = budget / s
        x = (rng.random((trials, nx)) < q) * s
        y = np.zeros((trials, ny))
        new = old = 0
        for i in range(trials):
            zero = share_test(x[i], y[i], budget, ALPHA)
            if zero is not None:
                new += zero[1].state == eq.PASS
            else:
                e = eq.difference_estimate(x[i], y[i], ALPHA, rule)
                new += eq.equivalence(e, budget).state == eq.PASS
            old += eq.equivalence(eq.difference_estimate(x[i], y[i], ALPHA),
                                  budget).state == eq.PASS
        out.append({"design": f"{nx} vs {ny}", "share": s, "q": q,
                    "wrong pass": new / trials, "registered rule": old / trials})
    return out


def _profiles(rng, trials: int, runs: int, offset: float, shift: np.ndarray) -> np.ndarray:
    return ar1_runs(rng, trials, runs, FRAMES, PHI, offset, (BINS,)).mean(axis=2) + 1.0 + shift


def level_states(rng, trials: int, nx: int, ny: int, offset: float, alpha: float,
                 registered: bool = False, rule: str = eq.WELCH_EQUAL) -> list[str]:
    """The state of ``trials`` levels whose four criteria (three signed, the profile) sit
    exactly on their budgets (signed: 1 frame sd; profile: its true distance)."""
    shift = np.zeros(BINS)
    shift[0] = 0.3
    truth = float(np.sqrt(np.sum(shift ** 2)) / math.sqrt(BINS))
    signed = [(_means(rng, trials, nx, offset) + 1.0, _means(rng, trials, ny, offset))
              for _ in range(3)]
    px, py = (_profiles(rng, trials, nx, offset, shift),
              _profiles(rng, trials, ny, offset, np.zeros(BINS)))
    states = []
    for i in range(trials):
        tests, p = [], []
        for x, y in signed:
            e = eq.difference_estimate(x[i], y[i], alpha, eq.WELCH if registered else rule)
            t = eq.equivalence(e, 1.0, alpha, fail_sides=1 if registered else 2)
            tests.append(t.state)
            p.append(t.p_fail)
        n = eq.norm_estimate(px[i], py[i], alpha)
        tests.append(eq.norm_decision(n, truth))
        if registered:
            p.append(0.0 if tests[-1] == eq.FAIL else math.nan)
        else:
            p.append(eq.norm_fail_p(px[i], py[i], truth))
        kept = eq.holm_rejects(p, alpha)
        final = [eq.UNDECIDED if s == eq.FAIL and not k else s for s, k in zip(tests, kept)]
        states.append("fails" if eq.FAIL in final else
                      "meets" if all(s == eq.PASS for s in final) else "undecided")
    return states


def family_cells(rng, trials: int, rule: str = eq.WELCH_EQUAL) -> list[dict]:
    out = []
    for (nx, ny), offset in itertools.product(((3, 3), (6, 2), (24, 3)), (0.0, 1.0)):
        new = level_states(rng, trials, nx, ny, offset, ALPHA, rule=rule)
        old = level_states(rng, trials, nx, ny, offset, ALPHA, registered=True)
        out.append({"design": f"{nx} vs {ny}", "offset": offset,
                    "meets": new.count("meets") / trials, "fails": new.count("fails") / trials,
                    "wrong decision": (trials - new.count("undecided")) / trials,
                    "registered rule": (trials - old.count("undecided")) / trials})
    return out


def levels_cells(rng, trials: int, levels: int = 4, rule: str = eq.WELCH_EQUAL
                 ) -> list[dict]:
    """Some level of ``levels`` meets, each level with one signed criterion exactly on its
    budget (1 frame sd; the others far inside it, so the one decides the level): the worst
    case of the cheapest-level sentence, which names a level when any meets."""
    out = []
    for (nx, ny), offset in itertools.product(((3, 3), (6, 2), (24, 3)), (0.0, 1.0)):
        some = some_b = 0
        for i in range(trials):
            y = _means(rng, 1, ny, offset)[0]          # the levels share their CG1 runs
            meets = meets_b = False
            for _ in range(levels):
                x = _means(rng, 1, nx, offset)[0] + 1.0
                meets |= eq.equivalence(eq.difference_estimate(x, y, ALPHA, rule),
                                        1.0).state == eq.PASS
                meets_b |= eq.equivalence(eq.difference_estimate(x, y, ALPHA / levels, rule),
                                          1.0, ALPHA / levels).state == eq.PASS
            some += meets
            some_b += meets_b
        out.append({"design": f"{nx} vs {ny}", "offset": offset, "levels": levels,
                    "some level meets": some / trials, "disclosed bound": min(1.0, levels * ALPHA),
                    "at alpha / levels": some_b / trials})
    return out


def report(rng, trials: int, level_trials: int, rule: str = eq.WELCH_EQUAL) -> int:
    """Print every design's table and the registered checks; the number of failed checks."""
    failed = 0
    print(f"designs: {trials} studies a cell ({level_trials} for the family and levels "
          f"cells); AR(1) phi {PHI}, {FRAMES} frames a run; alpha {ALPHA}; a rate cell fails "
          f"when the lower 95 % Clopper-Pearson bound of its share is above its alpha"
          + ("" if rule == eq.WELCH_EQUAL else f"; df rule: {rule}"))
    print("unequal arms (CG-n vs CG1; scale: CG-n seed offset / CG1's; budget in frame sd)")
    print(f"{'design':>8} {'scale':>5} {'offset':>6} {'budget':>6} | {'diff':>6} {'tost':>6} | "
          f"{'wrong pass':>10} {'wrong fail':>10}")
    cells = unequal_cells(rng, trials, rule)
    for c in cells:
        print(f"{c['design']:>8} {c['scale']:5.1f} {c['offset']:6.1f} {c['budget']:6.1f} | "
              f"{c['diff']:6.3f} {c['tost']:6.3f} | {c['wrong pass']:10.4f} "
              f"{c['wrong fail']:10.4f}", flush=True)
    cover = [c[k] for c in cells for k in ("diff", "tost")]
    inside = sum(LOW <= v <= HIGH for v in cover)
    rates = [c[k] for c in cells for k in ("wrong pass", "wrong fail")]
    above = sum(lower_bound(v, trials) > ALPHA for v in rates)
    print(f"check unequal intervals: {inside} of {len(cover)} cells in [{LOW}, {HIGH}] "
          f"({min(cover):.3f}-{max(cover):.3f}): {'holds' if inside == len(cover) else 'FAILS'}")
    print(f"check unequal rates: at most {max(rates):.4f}; {above} of {len(rates)} shown above "
          f"{ALPHA}: {'holds' if above == 0 else 'FAILS'}")
    failed += inside < len(cover)                 # registered check 1
    rates_fail = above > 0                         # registered check 2 (with all-zero below)

    print("all-zero arms (CG1 reads 0; a CG-n run reads `share` with probability q, mean on "
          "the budget 0.05)")
    print(f"{'design':>8} {'share':>5} {'q':>6} | {'wrong pass':>10} {'registered rule':>15}")
    zero = all_zero_cells(rng, trials, rule=rule)
    for c in zero:
        print(f"{c['design']:>8} {c['share']:5.1f} {c['q']:6.3f} | {c['wrong pass']:10.4f} "
              f"{c['registered rule']:15.4f}", flush=True)
    above = sum(lower_bound(c["wrong pass"], trials) > ALPHA for c in zero)
    print(f"check all-zero wrong pass: at most {max(c['wrong pass'] for c in zero):.4f} "
          f"(registered rule: up to {max(c['registered rule'] for c in zero):.4f}); {above} of "
          f"{len(zero)} shown above {ALPHA}: {'holds' if above == 0 else 'FAILS'}")
    failed += rates_fail or above > 0

    print("a level's family: three signed criteria and the profile, each on its budget")
    print(f"{'design':>8} {'offset':>6} | {'meets':>6} {'fails':>6} {'wrong decision':>14} | "
          f"{'registered rule':>15}")
    fam = family_cells(rng, level_trials, rule)
    for c in fam:
        print(f"{c['design']:>8} {c['offset']:6.1f} | {c['meets']:6.4f} {c['fails']:6.4f} "
              f"{c['wrong decision']:14.4f} | {c['registered rule']:15.4f}", flush=True)
    above = sum(lower_bound(c["wrong decision"], level_trials) > ALPHA for c in fam)
    print(f"check family-wise wrong decision: at most "
          f"{max(c['wrong decision'] for c in fam):.4f}; {above} of {len(fam)} shown above "
          f"{ALPHA}: {'holds' if above == 0 else 'FAILS'}")
    failed += above > 0

    print("the cheapest level that meets: four levels, each with a criterion on the budget")
    print(f"{'design':>8} {'offset':>6} | {'some level meets':>16} {'disclosed bound':>15} | "
          f"{'at alpha / levels':>17}")
    lev = levels_cells(rng, level_trials, rule=rule)
    for c in lev:
        print(f"{c['design']:>8} {c['offset']:6.1f} | {c['some level meets']:16.4f} "
              f"{c['disclosed bound']:15.2f} | {c['at alpha / levels']:17.4f}", flush=True)
    above = sum(lower_bound(c["some level meets"], level_trials) > c["disclosed bound"]
                for c in lev)
    print(f"check cheapest level disclosed: at most {max(c['some level meets'] for c in lev):.4f}"
          f" against the disclosed bound; {above} of {len(lev)} shown above it: "
          f"{'holds' if above == 0 else 'FAILS'}")
    failed += above > 0
    print(f"summary: {4 - failed} of 4 registered checks hold")
    return failed
