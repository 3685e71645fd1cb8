#!/usr/bin/env python3
"""CG speedup on one scene: wall-time ratios CG1/CG2 and CG1/CG3 against the ideal n^4.

Renders the We-vs-Bo drum (workflows/we_vs_bo.yaml; by default on the 9 mm slice of the
hand-written reference measurement: 6,075 particles at CG1), runs CG1, CG2 and CG3
(weber, one seed each) with ligwf's own runner under ``mpirun -np NP``, and prints each
level's wall and core-seconds from its manifest and the ratios measured in this one run.
Reference (hand-written inputs, 2 cores, 0.5 s settle + 1 revolution): CG2 14.4x, CG3 54x
wall. Target for ligwf's rendered inputs: CG2 >= 14x, CG3 >= 50x.

    .venv/bin/python benchmarks/bench_cg_speedup.py            # full scene, ~15 min
    .venv/bin/python benchmarks/bench_cg_speedup.py --run-time 0.5 --settle-time 0.2
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import threading
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ligwf.study.prepare import render_workflow, write_study  # noqa: E402
from ligwf.engine.site import EngineConfig  # noqa: E402
from ligwf.engine.health import DONE  # noqa: E402
from ligwf.engine.launch import run_case  # noqa: E402
from ligwf.scene.workflow import load_workflow  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--np", type=int, default=2, help="MPI ranks per case (default 2)")
    ap.add_argument("--length", type=float, default=0.009, help="periodic slice, m (default 0.009)")
    ap.add_argument("--settle-time", type=float, default=0.5)
    ap.add_argument("--run-time", type=float, default=2.0, help="s of rotation (2.0 = 1 revolution)")
    ap.add_argument("--granules", action="store_true", help="also write contact dumps")
    ap.add_argument("--out", type=Path, default=None, help="keep the runs here")
    args = ap.parse_args()

    out = args.out or Path(tempfile.mkdtemp(prefix="bench_cg_"))
    wf = load_workflow(ROOT / "workflows" / "we_vs_bo.yaml", [
        "sweep.cg_levels=[1,2,3]", "sweep.rules=[weber]", "sweep.replicas=1", "sweep.per_cg={}",
        f"scene.drum.length={args.length}", f"scene.process.settle_time={args.settle_time}",
        f"scene.process.run_time={args.run_time}",
        f"scene.analysis.granules={'true' if args.granules else 'false'}"])
    rendered = render_workflow(wf)
    cases = write_study(wf, rendered, out).cases
    engine = EngineConfig.from_site()
    stop = threading.Event()
    rows = []
    for rc, case in zip(rendered, cases):
        print(f"running {rc.case.case_id}: {rc.scaled.particle_count} particles, "
              f"{rc.scaled.total_steps} steps ...", flush=True)
        man = run_case(case, args.np, engine, None, stop) or case.manifest()
        if man.status != DONE:
            print(f"  {rc.case.case_id} ended {man.status}: {man.reason}")
            return 1
        rows.append((rc.scaled.cg, rc.scaled.particle_count, rc.scaled.total_steps,
                     man.wall_seconds, man.core_seconds))
    cg1 = rows[0]
    print(f"\nscene: we_vs_bo slice {args.length * 1000:g} mm, settle {args.settle_time:g} s, "
          f"run {args.run_time:g} s, -np {args.np}; runs in {out}")
    print(f"{'CG':>3} {'particles':>9} {'steps':>8} {'wall s':>8} {'core-s':>8} "
          f"{'wall x':>7} {'core x':>7} {'ideal n^4':>9}")
    for cg, n, steps, wall, core in rows:
        print(f"{cg:>3g} {n:>9} {steps:>8} {wall:>8.1f} {core:>8.1f} {cg1[3] / wall:>7.1f} "
              f"{cg1[4] / core:>7.1f} {cg**4:>9g}")
    targets = {2.0: 14.0, 3.0: 50.0}
    for cg, *_rest in rows[1:]:
        ratio = cg1[3] / _rest[2]
        verdict = "meets" if ratio >= targets[cg] else "MISSES"
        print(f"CG{cg:g}/CG1 wall ratio {ratio:.1f}x {verdict} the target {targets[cg]:g}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
