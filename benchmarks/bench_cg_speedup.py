#!/usr/bin/env python3
"""CG speedup on one footing: production core-seconds per simulated second, CG1 / CG-n.

Renders the We-vs-Bo drum (workflows/we_vs_bo.yaml, its own 18 mm slice: 11,963 particles
at CG1, 1,495 at CG2, 443 at CG3; Weber rule, one seed each) and runs every level with
ligwf's own runner, one case at a time (a quiet machine: cases side by side would share
memory bandwidth and make the ratios lie), in two rank modes:

* ``single``: every level on one rank;
* ``planner``: every level on the ranks ``ligwf run`` would give it on this machine
  (:func:`ligwf.engine.plan.plan_ranks`: slab rule and particles per rank).

The cost of a level is the core-seconds its production phase (the drum turning) took per
simulated second, per 1,000 particles of the original system (the manifest's phase times,
the report's ``production_core_rate_k``); fill and settle are printed but not in the ratio,
because their length is a choice of the scene, not of the CG level. Ideal: n^4 (n^3 fewer
particles, an n times larger time step). Targets (issue 15): CG2 >= 15x, CG3 >= 60x.

    .venv/bin/python benchmarks/bench_cg_speedup.py                  # ~25 min, both modes
    .venv/bin/python benchmarks/bench_cg_speedup.py --modes single   # ~15 min
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import threading
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.quiet import check_quiet  # noqa: E402
from ligwf.study.manifest import DONE  # noqa: E402
from ligwf.engine.launch import run_case  # noqa: E402
from ligwf.engine.cores import machine_cores  # noqa: E402
from ligwf.engine.plan import case_load, plan_ranks  # noqa: E402
from ligwf.engine.site import EngineConfig  # noqa: E402
from ligwf.scene.workflow import load_workflow  # noqa: E402
from ligwf.pipeline.prepare import render_workflow, write_study  # noqa: E402

TARGETS = {2.0: 15.0, 3.0: 60.0}
PHASES = ("fill", "settle", "production")


def run_mode(mode: str, wf, out: Path, cores: int) -> list[dict]:
    """Render the study into ``out`` and run its cases one after the other."""
    rendered = render_workflow(wf)
    cases = write_study(wf, rendered, out).cases
    engine = EngineConfig.from_site()
    stop = threading.Event()
    rows = []
    for rc, case in zip(rendered, cases):
        s = rc.scaled
        ranks = 1 if mode == "single" else plan_ranks(case_load(rc.case.case_id, s),
                                                      cores).ranks
        print(f"[{mode}] {rc.case.case_id}: {s.particles.count} particles, {s.total_steps} "
              f"steps, {ranks} rank(s), skin {s.numerics.skin / s.d_min:.3f} d ...", flush=True)
        man = run_case(case, ranks, engine, None, stop) or case.manifest()
        if man is None or man.status != DONE:
            sys.exit(f"{rc.case.case_id} ended {getattr(man, 'status', 'without a manifest')}: "
                     f"{getattr(man, 'reason', '')}")
        phases = man.phases or {}
        if "production" not in phases:
            sys.exit(f"{rc.case.case_id}: the manifest has no production phase times")
        prod_core = phases["production"]["core_seconds"]
        rows.append({"cg": s.cg, "particles": s.particles.count, "ranks": ranks,
                     "steps": s.total_steps, "wall": man.wall_seconds,
                     "core": man.core_seconds,
                     **{f"{p}_core": phases.get(p, {}).get("core_seconds", float("nan"))
                        for p in PHASES},
                     "rate_k": prod_core / (s.numerics.run_steps * s.numerics.dt)
                     / s.particles.original_count * 1000.0})
    return rows


def report(mode: str, rows: list[dict]) -> bool:
    """Print one mode's table and verdicts; True when every target is met."""
    cg1 = rows[0]
    print(f"\n== {mode}: production core-s per simulated s per 1,000 original particles ==")
    print(f"{'CG':>3} {'particles':>9} {'ranks':>5} {'fill cs':>8} {'settle cs':>9} "
          f"{'prod cs':>8} {'rate_k':>8} {'speedup':>8} {'ideal':>6}")
    ok = True
    for r in rows:
        speed = cg1["rate_k"] / r["rate_k"]
        print(f"{r['cg']:>3g} {r['particles']:>9} {r['ranks']:>5} {r['fill_core']:>8.1f} "
              f"{r['settle_core']:>9.1f} {r['production_core']:>8.1f} {r['rate_k']:>8.3f} "
              f"{speed:>7.1f}x {r['cg'] ** 4:>6g}")
    for r in rows[1:]:
        speed = cg1["rate_k"] / r["rate_k"]
        target = TARGETS.get(r["cg"])
        if target is not None:
            verdict = "meets" if speed >= target else "MISSES"
            ok &= speed >= target
            print(f"[{mode}] CG{r['cg']:g}/CG1 {speed:.1f}x {verdict} the target {target:g}x "
                  f"({100 * speed / r['cg'] ** 4:.0f} % of ideal)")
    return ok


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--modes", default="single,planner",
                    help="comma list of single, planner (default both)")
    ap.add_argument("--length", type=float, default=None,
                    help="periodic slice, m (default: the workflow's 18 mm)")
    ap.add_argument("--settle-time", type=float, default=0.2,
                    help="s at rest before turning (default 0.2)")
    ap.add_argument("--run-time", type=float, default=0.5,
                    help="s of production (default 0.5 = a quarter revolution)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="more workflow overrides, e.g. scene.numerics.skin_ratio=0.5")
    ap.add_argument("--out", type=Path, default=None, help="keep the runs here")
    args = ap.parse_args()
    modes = [m.strip() for m in args.modes.split(",") if m.strip()]
    if not modes or any(m not in ("single", "planner") for m in modes):
        ap.error(f"--modes = {args.modes!r}: allowed single, planner (comma-separated)")
    check_quiet("the ratios below")
    overrides = ["sweep.cg_levels=[1,2,3]", "sweep.rules=[weber]", "sweep.replicas=1",
                 "sweep.per_cg={}", f"scene.process.settle_time={args.settle_time}",
                 f"scene.process.run_time={args.run_time}", "scene.analysis.contact_dumps=true"]
    if args.length is not None:
        overrides.append(f"scene.drum.length={args.length}")
    wf = load_workflow(ROOT / "workflows" / "we_vs_bo.yaml", overrides + args.set)
    cores, source = machine_cores()
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_cg_"))
    results = {m: run_mode(m, wf, out / m, cores) for m in modes}
    length = wf.cases[0].scene.drum.length
    print(f"\nscene: we_vs_bo, slice {length * 1000:g} mm, settle {args.settle_time:g} s, "
          f"production {args.run_time:g} s, granule dumps on; {cores} cores ({source}); "
          f"runs in {out}")
    ok = all([report(m, rows) for m, rows in results.items()])
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
