#!/usr/bin/env python3
"""Paper scale, measured: the source study's drum at CG3 for one revolution on this machine,
and what that rate says about CG1 on a cluster.

Runs ``workflows/paper_scale.yaml`` (0.2 m drum, 0.06 m periodic slice, 48 lifters, 360,000
particles of 1 mm at CG1) at CG3 (13,333 particles of 3 mm, Weber rule, one seed) for one
revolution (3 s at 20 rpm) with ``ligwf run`` and the rank planner (no ``--np``), then prints
from the case's manifest, per phase, wall and core-seconds and the rate in particle-steps
per core-second -- the number that scales a cluster estimate -- and finally the planner's
Slurm plan for CG1 (``ligwf slurm submit --dry-run``: ranks, nodes, estimated wall time).

    .venv/bin/python benchmarks/bench_paper_scale.py --out runs/paper_scale_cg3   # ~25 min
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.quiet import check_quiet  # noqa: E402
from ligwf.study.manifest import DONE  # noqa: E402
from ligwf.study.study import Study  # noqa: E402

WORKFLOW = ROOT / "workflows" / "paper_scale.yaml"
ONE_CASE = ["sweep.rules=[weber]", "sweep.replicas=1", "sweep.per_cg={}"]


def ligwf(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ligwf.cli.main", *args],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def sets(values: list[str]) -> list[str]:
    return sum([["--set", v] for v in values], [])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, required=True, help="study folder (kept)")
    ap.add_argument("--run-time", type=float, default=3.0, help="s turning (3.0 = 1 rev.)")
    ap.add_argument("--cores-per-node", type=int, default=64,
                    help="cluster node size for the CG1 plan (default 64)")
    args = ap.parse_args()
    check_quiet("the rates below")
    cg3 = sets(["sweep.cg_levels=[3]", *ONE_CASE, f"scene.process.run_time={args.run_time}"])
    t0 = time.perf_counter()
    run = ligwf("run", str(WORKFLOW), "--out", str(args.out), *cg3)
    wall = time.perf_counter() - t0
    if run.returncode:
        print(run.stdout[-4000:])
        return 1
    case = Study.open(args.out).case(0)
    man, s = case.manifest(), case.scaled
    if man is None or man.status != DONE:
        print(f"{case.case_id} not done: {getattr(man, 'reason', 'no manifest')}")
        return 1
    print(f"paper scale CG3: {s.particles.count:,} particles, dt {s.numerics.dt:.3g} s, "
          f"{s.total_steps:,} steps ({s.numerics.run_steps:,} turning = {s.numerics.run_steps * s.numerics.dt:g} s, "
          f"{s.numerics.run_steps * s.numerics.dt / s.drum.rotation_period:.2f} revolution), {man.nprocs} rank(s); "
          f"'ligwf run' wall {wall:.0f} s")
    print(f"{'phase':>10} {'steps':>8} {'wall s':>8} {'core-s':>8} {'particle-steps/core-s':>22}")
    for phase in ("fill", "settle", "production"):
        rec = man.phases.get(phase, {})
        steps, core = int(rec.get("steps", 0)), rec.get("core_seconds", float("nan"))
        rate = s.particles.count * steps / core if core else float("nan")
        print(f"{phase:>10} {steps:>8,} {rec.get('wall_seconds', float('nan')):>8.1f} "
              f"{core:>8.1f} {rate:>22.3e}")
    prod = man.phases["production"]
    per_sim_s = prod["core_seconds"] / (s.numerics.run_steps * s.numerics.dt)
    print(f"production: {per_sim_s:.0f} core-s per simulated second "
          f"({per_sim_s / 3600:.2f} core-h)")
    cg1 = sets(["sweep.cg_levels=[1]", *ONE_CASE])
    plan = ligwf("slurm", "submit", str(WORKFLOW), "--out", str(args.out) + "_cg1_plan",
                 "--dry-run", "--cores-per-node", str(args.cores_per_node), *cg1)
    print("\n$ ligwf slurm submit workflows/paper_scale.yaml --out runs/paper_scale_cg1 "
          f"--dry-run --cores-per-node {args.cores_per_node} " + " ".join(cg1))
    print("\n".join(l for l in plan.stdout.splitlines()
                    if not l.startswith(("#SBATCH", "#!", "set ", "srun", "exec"))))
    return plan.returncode


if __name__ == "__main__":
    sys.exit(main())
