"""Does a second ``ligwf analyse`` compile its kernels again? (numba cache across processes)

Usage: ``.venv/bin/python benchmarks/bench_kernel_cache.py STUDY_DIR [--runs 3] [--np P]``
(prints, never asserts; a test of the same promise is tests/test_numba_cache.py).

Runs ``ligwf analyse STUDY_DIR --out <tmp> --no-vtu`` ``--runs`` times one after the other
(under ``mpirun -np P`` with ``--np``), all with one fresh ``NUMBA_CACHE_DIR``, so the first
process starts from an empty cache exactly like the first analysis after an install or an
edit of a kernel. numba's own cache log (``NUMBA_DEBUG_CACHE=1``) says, per process, how
many compiled kernels it wrote (compiled) and how many it loaded; the wall time of each
run is printed beside it. Before the bond kernels were cached, every process (and every
MPI rank) compiled the liquid-law kernels again: a few seconds each.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from quiet import busy_cores  # noqa: E402

LIGWF = Path(sys.executable).with_name("ligwf")


def analyse_once(study: Path, out: Path, cache: Path, nprocs: int) -> tuple[float, int, int]:
    """(wall s, kernels compiled and saved, kernels loaded) of one ``ligwf analyse``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), NUMBA_DEBUG_CACHE="1")
    cmd = [str(LIGWF), "analyse", str(study), "--out", str(out), "--no-vtu"]
    if nprocs > 1:
        cmd = ["mpirun", "-np", str(nprocs), *(["--allow-run-as-root"] if os.getuid() == 0
                                               else []), *cmd]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, text=True, capture_output=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"ligwf analyse failed:\n{proc.stderr[-3000:]}")
    log = proc.stdout.splitlines()
    return (wall, sum("[cache] data saved" in ln for ln in log),
            sum("[cache] data loaded" in ln for ln in log))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", type=Path)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--np", type=int, default=1)
    args = ap.parse_args()
    busy = busy_cores()
    if busy is not None and busy > 0.3:
        print(f"warning: {busy:.1f} cores busy before the runs: wall times are inflated")
    with tempfile.TemporaryDirectory(prefix="ligwf-kernel-cache-") as tmp:
        cache = Path(tmp) / "numba"
        print(f"ligwf analyse {args.study} (np {args.np}), fresh NUMBA_CACHE_DIR")
        print(f"{'run':>4} {'wall s':>8} {'compiled':>9} {'loaded':>7}")
        for k in range(args.runs):
            wall, saved, loaded = analyse_once(args.study, Path(tmp) / f"out{k}", cache,
                                               args.np)
            print(f"{k + 1:>4} {wall:8.2f} {saved:9d} {loaded:7d}")


if __name__ == "__main__":
    main()
