"""ligwf's own overhead (render + launch + monitoring + manifest) vs the engine's run time.

Runs one case of the demo scene (default: its CG1 case, the one that dominates the demo)
through ``ligwf run`` and splits the wall time in the same run, so a busy shared machine
slows both parts alike:

* engine time  = wall seconds of the ``mpirun`` process (the attempt in manifest.json);
* outside      = ligwf's wall time before and after it (start-up, render, pre-flight,
                 health assessment, manifest);
* monitor CPU  = CPU seconds of the ligwf process itself (not its children), sampled from
                 /proc until it exits -- the live monitor's cost while the engine runs.

Overhead = (outside + monitor CPU) / engine time; target <= 3 %.
Usage: ``python benchmarks/bench_overhead.py [--np 2] [--set k=v ...]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ligwf.study.study import Study

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_SET = ["sweep.cg_levels=[1]"]


def own_cpu_seconds(pid: int) -> float | None:
    """utime + stime of one process (children excluded), s."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--workflow", default=str(ROOT / "workflows" / "demo.yaml"))
    ap.add_argument("--np", type=int, default=2)
    ap.add_argument("--set", action="append", default=None)
    args = ap.parse_args()
    sets = sum([["--set", s] for s in (args.set or DEFAULT_SET)], [])
    work = Path(tempfile.mkdtemp(prefix="ligwf-bench-"))
    try:
        out = work / "study"
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "ligwf.cli.main", "run", args.workflow,
                                 "--out", str(out), "--np", str(args.np)] + sets,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        cpu = 0.0
        while proc.poll() is None:
            cpu = own_cpu_seconds(proc.pid) or cpu
            time.sleep(0.2)
        t_total = time.perf_counter() - t0
        if proc.returncode:
            sys.exit(f"ligwf run failed (exit {proc.returncode})")
        manifests = [c.manifest() for c in Study.open(out).cases if c.manifest() is not None]
        t_engine = sum(a.wall_seconds for m in manifests for a in m.attempts)
        steps = sum(m.steps_done for m in manifests)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    outside = t_total - t_engine
    print(f"cases: {len(manifests)}, steps: {steps:,}, ranks: {args.np}")
    print(f"engine (mpirun) wall:        {t_engine:8.2f} s")
    print(f"ligwf outside the engine:    {outside:8.2f} s  (start-up, render, pre-flight, manifest)")
    print(f"ligwf own CPU (incl. live monitor): {cpu:6.2f} s")
    print(f"overhead: {(outside + cpu) / t_engine * 100:6.2f} % of the engine's run time "
          "(target <= 3 %)")


if __name__ == "__main__":
    main()
