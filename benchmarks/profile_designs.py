"""Error rates of the velocity profile's bounds when depth bins share their errors (issue 45
item 2), the part of ``benchmarks/bench_coverage.py --profiles`` (its pass criteria are
registered in ``docs/results/verdict_rates/README.md`` before the run).

Real profiles share a seed's error between neighbouring depth bins: on the source drum's
studies neighbouring bins correlate at 0.91-0.92, bins 4 apart at 0.60, 8 apart at about 0
(``docs/results/profile_correlation/correlation.csv``). Here that is a triangular
correlation 1 - k / W between bins k apart (the correlation of a moving sum of W independent
series), W read from the committed table (:func:`kernel_width`), on 16 bins: both the
replica offsets and the AR(1) frame noise of a run are moving sums over bins of independent
series, so a run's window mean keeps the triangular correlation. Independent bins (W = 1)
are measured beside it with the same designs.

Each cell: ``trials`` studies of a CG-n arm and a CG1 arm (equal arms 2 / 3 / 4 / 6, and 6 vs
2 and 24 vs 3), the CG-n profile shifted by 0.3 frame sd in its 4 top bins; the budget sits
exactly on the true relative distance, so ``pass`` (upper bound <= budget) and ``fail``
(lower bound > budget) are both wrong. Per rule of counting bins
(:data:`ligwf.inference.equivalence.BINS_INDEPENDENT` / ``BINS_CORRELATED``): the upper
bound's coverage, the wrong pass and the wrong fail.
"""

from __future__ import annotations

import csv
import itertools
import math
from pathlib import Path

import numpy as np

from benchmarks.bench_coverage import ar1_runs
from benchmarks.verdict_designs import lower_bound
from ligwf.inference import equivalence as eq

ALPHA = eq.ALPHA
LOW, HIGH = 0.92, 0.99
FRAMES, PHI = 50, 0.6
BINS = 16
SHIFT, SHIFTED_BINS = 0.3, 4
DESIGNS = ((2, 2), (3, 3), (4, 4), (6, 6), (6, 2), (24, 3))
OFFSETS = (0.0, 1.0, 3.0)
CORRELATION = (Path(__file__).resolve().parents[1] / "docs" / "results" / "profile_correlation"
               / "correlation.csv")
RULES = (eq.BINS_CORRELATED, eq.BINS_INDEPENDENT)
#: the second run's rules (profiles_2.txt): the rule checked first, the first run's beside
RULES_2 = (eq.BINS_SIMULATED, eq.BINS_CORRELATED)
#: the third run's rule (profiles_3.txt): the simulated fail test with the smaller upper
#: bound, alone (the second run's rule is in profiles_2.txt; one rule keeps the run short)
RULES_3 = (eq.BINS_SIMULATED_UPPER,)
#: the fourth run's rule (profiles_4.txt): the simulated fail test with the upper bound
#: lowered to the one simulated along fiducial directions, alone
RULES_4 = (eq.BINS_SIMULATED_FIDUCIAL,)
#: the second run counts a design in its checks from this many runs of both arms together
#: (the verdict decides a profile from there: ligwf.inference.profile.MIN_PROFILE_RUNS)
COUNTED_FROM = 6


def kernel_width(path: Path = CORRELATION) -> int:
    """W of the triangular correlation 1 - k / W that the measured profiles give: the mean
    of k / (1 - r_k) over the committed lags k = 1, 2, 4 of every study (lag 8 is past the
    kernel's reach, where 1 - k / W would be negative), rounded."""
    widths = []
    with path.open() as f:
        for row in csv.DictReader(f):
            for k in (1, 2, 4):
                widths.append(k / (1.0 - float(row[f"mean_corr_lag{k}"])))
    return int(round(float(np.mean(widths))))


def profile_runs(rng, trials: int, runs: int, offset: float, width: int) -> np.ndarray:
    """(trials, runs, BINS) window means of runs whose noise (AR(1) frames plus a replica
    offset) is a moving sum of ``width`` independent series over bins: correlation
    1 - k / width between bins k apart, unit frame sd."""
    raw = ar1_runs(rng, trials, runs, FRAMES, PHI, offset, (BINS + width - 1,)).mean(axis=2)
    c = np.concatenate([np.zeros(raw.shape[:-1] + (1,)), np.cumsum(raw, axis=-1)], axis=-1)
    return (c[..., width:] - c[..., :-width]) / math.sqrt(width)


def shifted_studies(rng, trials: int, nx: int, ny: int, offset: float, width: int
                    ) -> tuple[np.ndarray, np.ndarray, float]:
    """``trials`` studies of ``nx`` CG-n against ``ny`` CG1 runs (:func:`profile_runs`)
    whose true profiles differ by SHIFT in the top SHIFTED_BINS bins, and the true
    distance (relative to the reference's true mean profile, all ones)."""
    shift = np.zeros(BINS)
    shift[:SHIFTED_BINS] = SHIFT
    a = profile_runs(rng, trials, nx, offset, width) + 1.0 + shift
    b = profile_runs(rng, trials, ny, offset, width) + 1.0
    return a, b, float(np.sqrt(np.sum(shift ** 2)) / math.sqrt(BINS))


def profile_cells(rng, trials: int, width: int, rules: tuple[str, ...] = RULES) -> list[dict]:
    """One row per (bins' correlation, design, offset) with each rule's coverage and errors;
    both rules decide the same studies."""
    out = []
    for w, (nx, ny), offset in itertools.product((width, 1), DESIGNS, OFFSETS):
        a, b, truth = shifted_studies(rng, trials, nx, ny, offset, w)
        row = {"bins": "correlated" if w > 1 else "independent", "design": f"{nx} vs {ny}",
               "offset": offset}
        for rule in rules:
            cover = wrong_pass = wrong_fail = 0
            for i in range(trials):
                e = eq.norm_estimate(a[i], b[i], ALPHA, bins=rule)
                cover += e.hi >= truth
                state = eq.norm_decision(e, truth)
                wrong_pass += state == eq.PASS
                wrong_fail += state == eq.FAIL
            row[rule] = {"cover": cover / trials, "wrong pass": wrong_pass / trials,
                         "wrong fail": wrong_fail / trials}
        out.append(row)
    return out


def report(rng, trials: int) -> int:
    """Print every cell and the registered checks; the number of checks that fail."""
    width = kernel_width()
    print(f"profile bounds with shared bin errors: {BINS} bins, triangular correlation "
          f"1 - k / {width} (from {CORRELATION.relative_to(CORRELATION.parents[3])}), "
          f"{trials} studies a cell, budget on the true distance")
    print(f"{'bins':>11} {'design':>8} {'offset':>6} | rule correlated: {'cover':>6} "
          f"{'w.pass':>7} {'w.fail':>7} | rule independent: {'cover':>6} {'w.pass':>7} "
          f"{'w.fail':>7}")
    cells = profile_cells(rng, trials, width)
    for c in cells:
        n, i = c[eq.BINS_CORRELATED], c[eq.BINS_INDEPENDENT]
        print(f"{c['bins']:>11} {c['design']:>8} {c['offset']:6.1f} | {'':16} "
              f"{n['cover']:6.3f} {n['wrong pass']:7.4f} {n['wrong fail']:7.4f} | "
              f"{'':17} {i['cover']:6.3f} {i['wrong pass']:7.4f} {i['wrong fail']:7.4f}",
              flush=True)
    failed = 0
    for bins, number in (("correlated", 1), ("independent", 3)):
        rows = [c[eq.BINS_CORRELATED] for c in cells if c["bins"] == bins]
        cover = [r["cover"] for r in rows]
        inside = sum(LOW <= v <= HIGH for v in cover)
        rates = [r[k] for r in rows for k in ("wrong pass", "wrong fail")]
        above = sum(lower_bound(v, trials) > ALPHA for v in rates)
        ok_cover, ok_rates = inside == len(cover), above == 0
        print(f"check {number} ({bins} bins, rule correlated) coverage: {inside} of "
              f"{len(cover)} cells in [{LOW}, {HIGH}] ({min(cover):.3f}-{max(cover):.3f}): "
              f"{'holds' if ok_cover else 'FAILS'}")
        print(f"check {number + 1} ({bins} bins, rule correlated) wrong pass and fail: at most "
              f"{max(rates):.4f}; {above} of {len(rates)} shown above {ALPHA}: "
              f"{'holds' if ok_rates else 'FAILS'}")
        failed += (not ok_cover) + (not ok_rates)
    old = [c[eq.BINS_INDEPENDENT]["cover"] for c in cells if c["bins"] == "correlated"]
    print(f"beside (not a check): rule independent on correlated bins covers "
          f"{min(old):.3f}-{max(old):.3f}")
    print(f"summary: {4 - failed} of 4 registered checks hold")
    return failed


def report_2(rng, trials: int) -> int:
    """The second profile run (registered in docs/results/verdict_rates/README.md before it):
    the simulated fail test (:data:`RULES_2`, first) beside the first run's correlated rule,
    on the same designs and draws; checks over designs of at least :data:`COUNTED_FROM` runs
    of both arms together (2 vs 2 printed, not counted). The number of checks that fail."""
    return _report_counted(rng, trials, RULES_2, ("simulated", "correlated"))


def report_3(rng, trials: int) -> int:
    """The third profile run (registered in docs/results/verdict_rates/README.md before it):
    the simulated fail test with the smaller upper bound (:data:`RULES_3`) alone, the second
    run's designs and checks. The number of checks that fail."""
    return _report_counted(rng, trials, RULES_3, ("smaller upper",))


def report_4(rng, trials: int) -> int:
    """The fourth profile run (registered in docs/results/verdict_rates/README.md before it):
    the simulated fail test with the upper bound simulated along fiducial directions
    (:data:`RULES_4`) alone, the second run's designs and checks. The number of checks that
    fail."""
    return _report_counted(rng, trials, RULES_4, ("fiducial upper",))


def _report_counted(rng, trials: int, rules: tuple[str, ...], names: tuple[str, ...]) -> int:
    """Every cell of ``rules`` (the first is checked, a second printed beside it) and the
    four checks over designs of at least :data:`COUNTED_FROM` runs; the number that fail."""
    width = kernel_width()
    new = rules[0]
    label = f"rule {names[0]}:"
    print(f"profile bounds with shared bin errors: {BINS} bins, triangular correlation "
          f"1 - k / {width} (from {CORRELATION.relative_to(CORRELATION.parents[3])}), "
          f"{trials} studies a cell, budget on the true distance")
    head = (f"{'bins':>11} {'design':>8} {'offset':>6} | {label}  {'cover':>6} "
            f"{'w.pass':>7} {'w.fail':>7}")
    if len(rules) > 1:
        head += (f" | rule {names[1]}:  {'cover':>6} {'w.pass':>7} "
                 f"{'w.fail':>7}")
    print(head)
    cells = profile_cells(rng, trials, width, rules)
    for c in cells:
        line = f"{c['bins']:>11} {c['design']:>8} {c['offset']:6.1f}"
        for rule in rules:
            n = c[rule]
            line += (f" | {'':16} {n['cover']:6.3f} {n['wrong pass']:7.4f} "
                     f"{n['wrong fail']:7.4f}")
        print(line, flush=True)

    def counted(c: dict) -> bool:
        return sum(int(r) for r in c["design"].split(" vs ")) >= COUNTED_FROM

    failed = 0
    for bins, number in (("correlated", 1), ("independent", 3)):
        rows = [c[new] for c in cells if c["bins"] == bins and counted(c)]
        cover = [r["cover"] for r in rows]
        inside = sum(LOW <= v <= HIGH for v in cover)
        rates = [r[k] for r in rows for k in ("wrong pass", "wrong fail")]
        above = sum(lower_bound(v, trials) > ALPHA for v in rates)
        ok_cover, ok_rates = inside == len(cover), above == 0
        print(f"check {number} ({bins} bins, rule {names[0]}, designs of >= {COUNTED_FROM} "
              f"runs) coverage: {inside} of {len(cover)} cells in [{LOW}, {HIGH}] "
              f"({min(cover):.3f}-{max(cover):.3f}): {'holds' if ok_cover else 'FAILS'}")
        print(f"check {number + 1} ({bins} bins, rule {names[0]}, designs of >= "
              f"{COUNTED_FROM} runs) wrong pass and fail: at most {max(rates):.4f} (pass "
              f"{max(r['wrong pass'] for r in rows):.4f}, fail "
              f"{max(r['wrong fail'] for r in rows):.4f}); {above} of {len(rates)} shown "
              f"above {ALPHA}: {'holds' if ok_rates else 'FAILS'}")
        failed += (not ok_cover) + (not ok_rates)
    for bins in ("correlated", "independent"):
        two = [c[new] for c in cells if c["bins"] == bins and not counted(c)]
        print(f"beside (not a check): {bins} bins, 2 vs 2 (never decided): cover "
              f"{min(r['cover'] for r in two):.3f}-{max(r['cover'] for r in two):.3f}, wrong "
              f"pass at most {max(r['wrong pass'] for r in two):.4f}, wrong fail at most "
              f"{max(r['wrong fail'] for r in two):.4f}")
    if len(rules) > 1:
        rows = [c[rules[1]] for c in cells if c["bins"] == "correlated" and counted(c)]
        print(f"beside (not a check): rule {names[1]} on correlated bins, designs of >= "
              f"{COUNTED_FROM} runs: wrong fail at most "
              f"{max(r['wrong fail'] for r in rows):.4f}, "
              f"{sum(lower_bound(r['wrong fail'], trials) > ALPHA for r in rows)} of "
              f"{len(rows)} shown above {ALPHA}")
    print(f"summary: {4 - failed} of 4 registered checks hold")
    return failed
