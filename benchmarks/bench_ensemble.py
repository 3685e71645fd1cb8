"""Ensemble throughput relative to independent runs.

The same P single-rank members (replicas of one small case) run (a) as P independent
``mpirun -np 1 --bind-to none liggghts`` processes side by side (without ``--bind-to none``
each separate mpirun binds its rank to core 0 and the baseline halves), and (b) as one ``ligwf run --ensemble P``
(one mpirun, mpi4py groups, libliggghts). Prints both wall times and throughput (b)/(a);
target >= 90 %. Usage: ``python benchmarks/bench_ensemble.py [--members 4] [--ranks 2]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ligwf.engine.site import EngineConfig

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--workflow", default=str(ROOT / "workflows" / "demo.yaml"))
    ap.add_argument("--members", type=int, default=4)
    ap.add_argument("--ranks", type=int, default=2)
    args = ap.parse_args()
    sets = ["--set", "sweep.cg_levels=[2]", "--set", "sweep.rules=[weber]",
            "--set", f"sweep.replicas={args.members}"]
    ligwf = [sys.executable, "-m", "ligwf.cli.main"]
    site = EngineConfig.from_site()
    # separate mpiruns each bind their one rank to core 0 by default, so side-by-side
    # independent runs would share a core; unbind them for a fair baseline
    engine = dataclasses.replace(site, mpirun_args=site.mpirun_args + ("--bind-to", "none"))
    work = Path(tempfile.mkdtemp(prefix="ligwf-bench-"))
    try:
        ind = work / "independent"
        subprocess.run(ligwf + ["render", args.workflow, "--out", str(ind)] + sets, check=True,
                       capture_output=True)
        cases = sorted(p for p in ind.iterdir() if (p / "in.liggghts").exists())
        t0 = time.perf_counter()
        running: list[subprocess.Popen] = []
        for case in cases:   # at most `ranks` at a time, like the ensemble's groups
            while len([p for p in running if p.poll() is None]) >= args.ranks:
                time.sleep(0.05)
            running.append(subprocess.Popen(engine.command("in.liggghts", 1), cwd=case,
                                            stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT))
        for p in running:
            p.wait()
        t_ind = time.perf_counter() - t0
        t0 = time.perf_counter()
        subprocess.run(ligwf + ["run", args.workflow, "--out", str(work / "ens"), "--ensemble",
                                str(args.ranks)] + sets, check=True, capture_output=True)
        t_ens = time.perf_counter() - t0
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"{args.members} members on {args.ranks} ranks")
    print(f"independent mpirun -np 1 runs: {t_ind:8.2f} s")
    print(f"ligwf run --ensemble {args.ranks}:     {t_ens:8.2f} s")
    print(f"ensemble throughput:           {t_ind / t_ens * 100:8.1f} % of independent runs "
          "(target >= 90 %)")


if __name__ == "__main__":
    main()
