#!/usr/bin/env python3
"""Does a planned study keep the machine's cores busy? Wall time vs core-seconds / cores.

Runs ``ligwf run WORKFLOW`` WITHOUT ``--np`` / ``--ensemble`` (the rank planner decides:
ranks per case, single-rank cases side by side in one ensemble) and compares, in this one
run, the wall time of the whole command with the sum of its cases' core-seconds (each
case's attempts: wall x ranks, from the manifests) divided by the cores the planner filled.
A ratio of 1.00 means no core was idle and ligwf added nothing between cases; target
(issue 15) <= 1.10 on the CG2/CG3 part of the We-vs-Bo study:

    .venv/bin/python benchmarks/bench_study_fill.py            # we_vs_bo CG2+CG3, ~15 min
    .venv/bin/python benchmarks/bench_study_fill.py --set 'sweep.cg_levels=[3]'
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.quiet import check_quiet  # noqa: E402
from ligwf.study.manifest import DONE  # noqa: E402
from ligwf.engine.cores import machine_cores  # noqa: E402
from ligwf.study.study import Study  # noqa: E402

TARGET = 1.10


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--workflow", default=str(ROOT / "workflows" / "we_vs_bo.yaml"))
    ap.add_argument("--set", action="append", default=None, metavar="KEY=VALUE",
                    help="workflow overrides (default: sweep.cg_levels=[2,3])")
    ap.add_argument("--cores", type=int, default=None, help="cores to plan for (default: "
                    "this machine's)")
    ap.add_argument("--keep", type=Path, default=None, help="keep the study folder here")
    args = ap.parse_args()
    sets = args.set if args.set is not None else ["sweep.cg_levels=[2,3]"]
    cores, source = machine_cores(args.cores)
    check_quiet("the wall time below")
    work = Path(tempfile.mkdtemp(prefix="ligwf-fill-"))
    out = args.keep or work / "study"
    cmd = [sys.executable, "-m", "ligwf.cli.main", "run", args.workflow, "--out", str(out),
           "--cores", str(cores)] + sum([["--set", s] for s in sets], [])
    print("running:", " ".join(cmd[2:]), flush=True)
    try:
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        wall = time.perf_counter() - t0
        if proc.returncode:
            print(proc.stdout[-3000:])
            return f"ligwf run failed (exit {proc.returncode})"
        plan = [l for l in proc.stdout.splitlines() if l.startswith(("phase ", "estimated "))]
        mans = [(c.case_id, c.manifest()) for c in Study.open(out).cases]
        bad = [cid for cid, m in mans if m is None or m.status != DONE]
        if bad:
            return f"cases not done: {bad}"
        core = sum(m.core_seconds for _, m in mans)
        ranks = {m.nprocs for _, m in mans}
    finally:
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)
    ideal = core / cores
    ratio = wall / ideal
    print("\n".join(plan))
    print(f"{len(mans)} cases on {sorted(ranks)} rank(s) each; {cores} cores ({source})")
    print(f"wall of 'ligwf run':            {wall:9.1f} s")
    print(f"sum of case core-seconds:       {core:9.1f} core-s")
    print(f"core-seconds / {cores} cores:          {ideal:9.1f} s")
    print(f"wall / (core-s / cores):        {ratio:9.3f}  "
          f"({'meets' if ratio <= TARGET else 'MISSES'} the target <= {TARGET:.2f})")
    return 0 if ratio <= TARGET else 1


if __name__ == "__main__":
    sys.exit(main())
