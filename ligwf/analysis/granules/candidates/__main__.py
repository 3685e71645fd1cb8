"""``python -m ligwf.analysis.granules.candidates``: measure the candidates on the cases
given and print the tables of docs/results/granule_definitions.md (usage and definitions:
:mod:`ligwf.analysis.granules.candidates`)."""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from ligwf.analysis.granules import candidates
from ligwf.analysis.granules.candidates.criteria import Measurement, common_cut, measure
from ligwf.analysis.granules.candidates.frames import load_case, rotation_check
from ligwf.analysis.granules.candidates.specs import CANDIDATES, Evaluator


def fmt(x, p=3):
    """A number as the tables print it (nan, inf, or ``p`` significant digits)."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "nan"
    return "inf" if math.isinf(x) else f"{x:.{p}g}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=candidates.__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", type=Path, required=True)
    ap.add_argument("--series", type=Path, nargs="*", default=[])
    ap.add_argument("--cg-series", type=Path, nargs="*", default=[])
    ap.add_argument("--tiles", type=int, nargs="*", default=[2, 4])
    ap.add_argument("--steady", type=float, default=0.25)
    ap.add_argument("--boot", type=int, default=1000)
    ap.add_argument("--community-stride", type=int, default=2,
                    help="use every k-th steady frame for community methods on tiled frames")
    ap.add_argument("--speed-tiles", type=int, nargs="*", default=[1, 4, 16])
    ap.add_argument("--only", nargs="*", default=None, help="candidate names to run")
    args = ap.parse_args(argv)
    specs = [s for s in CANDIDATES if args.only is None or s.name in args.only]
    how = Measurement(args.boot, tuple(args.tiles), args.community_stride)

    t_load = time.perf_counter()
    base = load_case(args.base, args.steady, flow_radii=(3.0, 2.4, 3.6))
    series = [load_case(p, args.steady) if p.resolve() != args.base.resolve() else base for p in args.series]
    cgs = [load_case(p, args.steady) for p in args.cg_series]
    print(f"# loaded in {time.perf_counter() - t_load:.1f} s")
    for c in [base] + [c for c in series if c is not base] + cgs:
        nb = np.mean([len(c.frames[k].i) / c.frames[k].n for k in c.steady])
        fr = c.frames[c.steady[0]]
        print(f"# case {c.path.name}: CG{c.cg:g} {c.rule}, {fr.n} particles, liquid {c.liquid_content}, "
              f"{len(c.frames)} production dumps, {len(c.steady)} steady, bridges/particle {nb:.2f}, "
              f"dump interval {(c.frames[1].step - c.frames[0].step)} steps")
    rp, rm = rotation_check(base)
    print(f"# drum frame check: mean|v - w x r| / mean|v| = {rp:.3f} (+omega), {rm:.3f} (-omega)")
    cut = common_cut([base] + series + cgs)
    print(f"# (e) common cut: granules >= {cut:.3g} m^3 (2 particles of the coarsest level) at every level")
    ev = {id(base): Evaluator(base)}
    for c in series + cgs:
        ev.setdefault(id(c), Evaluator(c))
    rows = []
    for spec in specs:
        rows.append(measure(spec, ev, base, series, cgs, cut, how))
        print(f"# done {spec.name}", file=sys.stderr, flush=True)

    d_p = base.diameter
    yn = {True: "yes", False: "NO", None: "-"}
    print("\n## Summary (d50 in CG1 particle diameters d_p, 95 % bootstrap band)\n")
    print("| candidate | (a) perc. frames | (a) largest | d50/d_p [band] | (b) worst x | (c) d50 2x / 4x | "
          "(d) d50 by liquid | (e) CGn/CG1 d50: own cut / common cut | a | b | c | d | e |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        d = r["d50"]
        tl = " / ".join(fmt(r["tiles"][m][0] / d_p) for m in sorted(r["tiles"]))
        ds = " -> ".join(fmt(x[0][0] / d_p) for x in r["series"])
        cr = ", ".join(fmt(x, 2) for x in r.get("cg_ratio_plain", [])) + " / " + ", ".join(
            fmt(x, 2) for x in r["cg_ratio"])
        print(f"| {r['spec'].name} | {r['perc_frac']:.0%} | {r['largest']:.1%} | {fmt(d[0]/d_p)} "
              f"[{fmt(d[1]/d_p)}, {fmt(d[2]/d_p)}] | {fmt(r['b_worst'])} | {tl} | {ds} | {cr} | "
              f"{yn[r['a']]} | {yn[r['b']]} | {yn[r['c']]} | {yn[r['d']]} | {yn[r['e']]} |")

    print("\n## (b) d50 ratio to the base value per perturbed threshold\n")
    for r in rows:
        print(f"- {r['spec'].name}: " + ", ".join(f"{lab} {fmt(x)}" for lab, x in r["sens"]))

    print("\n## (c) tiling: d50/d_p, worst GSD bin change / half 95 % band (<= 1 passes; inf: a bin empty in every 1x frame filled), "
          "mean granule size (particles), largest share\n")
    for r in rows:
        d1 = r["d50_1x"]
        print(f"- {r['spec'].name}: 1x {fmt(d1[0]/d_p)} [{fmt(d1[1]/d_p)}, {fmt(d1[2]/d_p)}], "
              f"size {r['mean_size']:.1f}; " +
              "; ".join(f"{m}x {fmt(v[0]/d_p)}, change/half-band {fmt(v[1])}, size {v[2]:.1f}, largest {v[3]:.1%}"
                        for m, v in sorted(r["tiles"].items())))

    print("\n## (d)/(e) per condition: d50/d_p [band], largest share, percolating frames\n")
    for r in rows:
        parts = []
        for lab, lst in (("CG1", r["series"]), ("CGn", r["cg"])):
            parts.append(lab + " " + "; ".join(
                f"{fmt(x[0][0]/d_p)} [{fmt(x[0][1]/d_p)},{fmt(x[0][2]/d_p)}] {x[1]:.1%} {x[2]:.0%}" for x in lst))
        print(f"- {r['spec'].name}: " + " | ".join(parts) + "; common-cut d50/d_p CG1 "
              + ", ".join(fmt(x[3][0] / d_p) for x in r["series"]) + " CGn "
              + ", ".join(fmt(x[3][0] / d_p) for x in r["cg"]) + "; plain CGn/CG1 d50 "
              + ", ".join(fmt(x, 2) for x in r.get("cg_ratio_plain", [])))

    # speed of the community algorithms (and components for scale)
    print("\n## speed: median s per frame on one core (bond mask + partition + percolation test; frames tiled along the axis for the larger N)\n")
    speed_specs = [s for s in specs if s.name in ("cc rot 10", "cc persist k5", "louvain",
                                                  "leiden modularity", "leiden cpm 0.05")]
    idx = base.steady[len(base.steady) // 2: len(base.steady) // 2 + 3]
    e0 = ev[id(base)]
    print("| method | " + " | ".join(f"N={base.frames[idx[0]].n * m}" for m in args.speed_tiles)
          + " | extrapolated 360k (linear in N) | frames/s at 360k |")
    print("|---|" + "---|" * (len(args.speed_tiles) + 2))
    for s in speed_specs:
        ts = []
        for m in args.speed_tiles:
            use = idx if m <= 4 else idx[:1]
            tt = []
            for k in use:
                t0 = time.perf_counter()
                e0.partition(k, s, m)
                tt.append(time.perf_counter() - t0)
            ts.append(float(np.median(tt)))
        nmax = base.frames[idx[0]].n * args.speed_tiles[-1]
        t360 = ts[-1] * 360000 / nmax
        print(f"| {s.name} | " + " | ".join(f"{t:.3g}" for t in ts) + f" | {t360:.3g} s | {1/t360:.2g} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
