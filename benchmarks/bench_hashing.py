"""The end-of-case hashing of the dump record against the case's wall time (#24).

The dump record (``dumps.json``: size and SHA-256 of every file in ``post/``) is written
with the done manifest. It used to hash every dump at that moment; now the runner's
background hasher (:mod:`ligwf.engine.dump_hasher`) hashes each dump while the engine runs,
once the next dump of its series appears, and the record hashes only the rest (the last
frame). Target: the end-of-case hashing adds <= 2 % to a case's wall time.

Two measurements, both printed as ratios to the case's wall time:

* ``--run`` (default): one real case of ``--workflow`` run by ``ligwf run`` in this
  process (the real runner and engine); the done-record write is timed as it happens
  (``CaseFolder.write_manifest`` with a done manifest), and afterwards hashing the whole
  ``post/`` (the old end-of-case cost) is timed on the same files;
* ``--case DIR`` (a finished case, e.g. a paper-scale CG1 run): hashing all of ``post/``
  (old) against hashing only its last dump of each series (what is left for the record
  now), over the wall time its manifest records.

Wall clock (the record is on the case's clock) and CPU seconds are printed; the machine
may be shared, so the ratio of one run is what it is: rerun on a quiet machine to compare.

Usage: python benchmarks/bench_hashing.py [--workflow tests/slurm/tiny_drum.yaml]
       [--set scene.process.run_time=0.5] | --case STUDY/CASE_ID
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ligwf.engine.dump_hasher import _DUMP  # noqa: E402
from ligwf.study import case as case_module  # noqa: E402
from ligwf.fsio import file_sha256 as file_digest  # noqa: E402
from ligwf.study.case import CaseFolder  # noqa: E402
from ligwf.study.manifest import DONE  # noqa: E402


def hash_all(files: list[Path]) -> tuple[float, float]:
    """(wall s, CPU s) of hashing ``files``."""
    w, c = time.perf_counter(), time.process_time()
    for p in files:
        file_digest(p)
    return time.perf_counter() - w, time.process_time() - c


def last_of_each_series(post: Path) -> list[Path]:
    series: dict[str, tuple[int, Path]] = {}
    others = []
    for p in post.iterdir():
        m = _DUMP.match(p.name)
        if not m:
            others.append(p)
        elif int(m.group("step")) > series.get(m.group("series"), (-1, None))[0]:
            series[m.group("series")] = (int(m.group("step")), p)
    return others + [p for _, p in series.values()]


def report(label: str, wall: float, before: tuple[float, float], after: tuple[float, float],
           files: int, size: int) -> None:
    print(f"{label}: {files} files, {size / 1e6:.1f} MB in post/, case wall {wall:.1f} s")
    print(f"  end-of-case hashing before (every dump): {before[0]:7.3f} s wall "
          f"({before[1]:.3f} s CPU) = {100 * before[0] / wall:6.2f} % of the case's wall time")
    print(f"  end-of-case hashing now (the rest)     : {after[0]:7.3f} s wall "
          f"({after[1]:.3f} s CPU) = {100 * after[0] / wall:6.2f} % of the case's wall time "
          f"(target <= 2 %)")


def run_case(workflow: Path, sets: list[str]) -> None:
    from ligwf.cli.main import main as ligwf_main

    timed: list[tuple[float, float]] = []
    hashed: list[int] = []
    original, digest = CaseFolder.write_manifest, case_module.file_sha256

    def counting(path):
        hashed[-1] += 1
        return digest(path)

    def timing(self, manifest, digests=case_module.NO_DIGESTS):
        if manifest.status != DONE:
            return original(self, manifest, digests)
        hashed.append(0)
        case_module.file_sha256 = counting
        w, c = time.perf_counter(), time.process_time()
        try:
            original(self, manifest, digests)
        finally:
            case_module.file_sha256 = digest
        timed.append((time.perf_counter() - w, time.process_time() - c))

    CaseFolder.write_manifest = timing
    out = Path(tempfile.mkdtemp(prefix="bench-hashing-")) / "study"
    args = ["run", str(workflow), "--out", str(out), "--np", "1",
            *[x for s in ["sweep.replicas=1", *sets] for x in ("--set", s)]]
    w = time.perf_counter()
    code = ligwf_main(args)
    total = time.perf_counter() - w
    CaseFolder.write_manifest = original
    if code != 0 or not timed:
        raise SystemExit(f"ligwf {' '.join(args)} exited {code} (done records: {len(timed)})")
    case = next(c for c in (out.iterdir()) if (c / "dumps.json").is_file())
    folder = CaseFolder.open(case)
    files = sorted(p for p in (case / "post").iterdir() if p.is_file())
    wall = folder.manifest().wall_seconds
    report(f"{case.name} (ligwf run, {total:.1f} s in all)", wall, hash_all(files), timed[-1],
           len(files), sum(p.stat().st_size for p in files))
    print(f"  files the done record hashed itself: {hashed[-1]} of {len(files)} (the rest "
          "were hashed by the runner's background hasher while the engine ran)")


def finished_case(path: Path) -> None:
    folder = CaseFolder.open(path)
    m = folder.manifest()
    if m is None or m.status != DONE:
        raise SystemExit(f"{path}: not a done case")
    post = path / "post"
    files = sorted(p for p in post.iterdir() if p.is_file())
    report(f"{path.name} (finished case)", m.wall_seconds, hash_all(files),
           hash_all(last_of_each_series(post)), len(files), sum(p.stat().st_size for p in files))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workflow", type=Path, default=ROOT / "tests" / "slurm" / "tiny_drum.yaml")
    ap.add_argument("--set", dest="sets", action="append", default=[])
    ap.add_argument("--case", type=Path, default=None)
    args = ap.parse_args()
    if args.case is not None:
        finished_case(args.case)
    else:
        run_case(args.workflow, args.sets)


if __name__ == "__main__":
    main()
