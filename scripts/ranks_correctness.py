#!/usr/bin/env python3
"""Correctness at more ranks than cores (issue #24 item 2): one tiny wet case on 1, 2, 4, 8 ranks.

The criterion was registered before the runs: ``docs/results/performance/ranks_criterion.md``.
This script runs the case with ligwf's own runner (``ligwf run``) and writes the table:

    LIGWF_MPIRUN_ARGS="--oversubscribe --bind-to none" \
        .venv/bin/python scripts/ranks_correctness.py run --out /tmp/ranks
    .venv/bin/python scripts/ranks_correctness.py table --out /tmp/ranks \
        --write docs/results/performance/ranks.md --marker table2

``run``: study ``OUT/seeds`` (replicas r0-r7 of the demo CG1, 1 rank each, side by side as the
planner packs them) and ``OUT/np{K}`` (replicas r0-r2 on K ranks, ``--np K``, one after the other) for each ``--ranks``.
``table``: per run the atom counts, the processor grid and per-rank atoms/ghosts LIGGGHTS
printed after the production run, the flow statistics (``case_flow``, fixed steady window)
and the bond statistics of the same frames; each K-rank value against the 1-rank seeds'
floor (the second registration's t rule). Exit 1 when a rank count fails.
Wall times on an oversubscribed, shared 2-core machine are not timing results.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ligwf.analysis.flow.stage import case_flow  # noqa: E402
from ligwf.analysis.frames.dumps import discover_frames, read_contacts, read_particles  # noqa: E402
from ligwf.engine.ghosts import last_run_spread  # noqa: E402
from ligwf.study.case import CaseFolder  # noqa: E402

WORKFLOW = ROOT / "workflows" / "granules.yaml"   # the demo scene until 2026-12-04
#: the registered case (ranks_criterion.md): demo CG1, no twin, 0.1 s settle, 0.8 s turning
SETS = ("sweep.cg_levels=[1]", "sweep.controls=[]", "scene.process.settle_time=0.1",
        "scene.process.run_time=0.8", "scene.numerics.dump_interval=0.025")
SEEDS = 8                   # the second registration: 8 one-rank seeds
REPLICAS = 3                # ... and 3 replicas on each rank count
STEADY_AFTER = 0.4          # fixed: the last 60 % of production
FLOW = ("angle_of_repose", "com_angle", "rms_speed", "rigid_fraction",
        "flowing_layer_thickness")
BONDS = ("bridges_per_particle", "bridges_touching")
#: two-sided t quantile, 7 degrees of freedom, per-comparison 0.05/7 (Bonferroni over the
#: seven statistics of one rank count): the second registration's rule
T_QUANTILE = 3.753


def ligwf() -> list[str]:
    exe = Path(sys.executable).with_name("ligwf")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "ligwf.cli.main"]


def run(out: Path, ranks: list[int]) -> None:
    """The registered runs (see the module docstring), all started at once so that they
    share the machine's load; a finished study is skipped by ``ligwf run`` itself."""
    sets = [a for s in SETS for a in ("--set", s)]
    jobs = [("seeds", sets + ["--set", f"sweep.replicas={{1: {SEEDS}}}", "--cores", "2"])]
    jobs += [(f"np{k}", sets + ["--set", f"sweep.replicas={{1: {REPLICAS}}}", "--np", str(k)])
             for k in ranks if k > 1]
    out.mkdir(parents=True, exist_ok=True)
    procs = []
    for name, args in jobs:
        cmd = ligwf() + ["run", str(WORKFLOW), "--out", str(out / name)] + args
        print("$", " ".join(cmd), flush=True)
        with open(out / f"{name}.out", "w") as log:
            procs.append((name, subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT)))
    failed = [name for name, p in procs if p.wait() != 0]
    if failed:
        raise SystemExit(f"ligwf run failed for {', '.join(failed)} (see {out}/<name>.out)")


def bond_means(case: CaseFolder, first_step: float) -> dict[str, float]:
    """Bridges per particle and the share of bridges in contact, frame means over the
    window (production frames from ``first_step``)."""
    per, touching = [], []
    for f in discover_frames(case.path):
        if f.step < first_step or f.contacts is None:
            continue
        c = read_contacts(f.contacts)
        n = len(read_particles(f.particles))
        per.append(2.0 * len(c) / n)
        touching.append(float(np.mean(np.asarray(c.delta) > 0)) if len(c) else 0.0)
    return {"bridges_per_particle": float(np.mean(per)),
            "bridges_touching": float(np.mean(touching))}


def measure(case_dir: Path) -> dict:
    """Atoms, grid, per-rank spread and the statistics of one finished case folder."""
    case = CaseFolder.open(case_dir)
    man = case.manifest()
    flow, _ = case_flow(case, STEADY_AFTER)
    row = {"case": case.case_id, "status": man.status, "nprocs": man.nprocs,
           "atoms_after_settle": man.atoms_after_settle, "atoms_end": man.atoms_end,
           "wall_s": man.wall_seconds, "expected": case.scaled.particles.count}
    # steady-window means (the flow summary names the angle's mean angle_of_repose)
    row.update({m: float(flow.summary[m if m == "angle_of_repose" else f"{m}_mean"])
                for m in FLOW})
    row.update(bond_means(case, flow.steady_from_step))
    log = (case_dir / "log.liggghts").read_text(errors="replace")
    row["spread"] = last_run_spread(log)
    grid = re.findall(r"(\d+) by (\d+) by (\d+) MPI processor grid", log)
    row["grid"] = "x".join(grid[-1]) if grid else "?"
    return row


def table(out: Path, ranks: list[int]) -> tuple[str, bool]:
    """The registered table (second registration, ranks_criterion.md): per run its atoms,
    grid and per-rank spread; per statistic the K-rank replicas' mean against the one-rank
    seeds' mean, in units of the seeds' standard deviation s_1, passing at
    |m_K - m_1| <= t s_1 sqrt(1/n_K + 1/n_1)."""
    def cases(name: str) -> list[dict]:
        return [measure(p) for p in sorted((out / name).glob("cg1-*")) if p.is_dir()]
    seeds = cases("seeds")
    runs = {k: cases(f"np{k}") for k in ranks if k > 1}
    stats = FLOW + BONDS
    n1 = len(seeds)
    floor = {m: (float(np.mean([s[m] for s in seeds])),
                 float(np.std([s[m] for s in seeds], ddof=1))) for m in stats}
    lines = ["| run | ranks | grid (x y z) | status | atoms settle / end (of) | "
             "atoms/rank max/avg | ghosts/rank avg (max) | wall s |",
             "|---|---|---|---|---|---|---|---|"]
    every = [(s["case"] + " (1 rank)", s) for s in seeds]
    every += [(f"{r['case']} on {k}", r) for k, rs in runs.items() for r in rs]
    for label, r in every:
        sp = r["spread"]
        lines.append(f"| {label} | {r['nprocs']} | {r['grid']} | {r['status']} | "
                     f"{r['atoms_after_settle']} / {r['atoms_end']} ({r['expected']}) | "
                     f"{sp.imbalance:.3f} | {sp.ghost_avg:.0f} ({sp.ghost_max:.0f}) | "
                     f"{r['wall_s']:.0f} |")
    lines += ["", f"| statistic | 1 rank: mean of {n1} | s_1 | "
              + " | ".join(f"{k} ranks: mean of {len(rs)}, diff/s_1, limit/s_1"
                           for k, rs in runs.items()) + " |",
              "|---|---|---|" + "---|" * len(runs)]
    verdict = {k: len(rs) == REPLICAS and all(
        r["status"] == "done" and r["atoms_after_settle"] == r["expected"] == r["atoms_end"]
        for r in rs) for k, rs in runs.items()}
    for m in stats:
        mean, sd = floor[m]
        cells = []
        for k, rs in runs.items():
            mk = float(np.mean([r[m] for r in rs]))
            limit = T_QUANTILE * np.sqrt(1.0 / len(rs) + 1.0 / n1)
            z = (mk - mean) / sd if sd > 0 else float("inf")
            ok = abs(z) <= limit
            verdict[k] &= ok
            cells.append(f"{mk:.4g}, {z:+.2f}, {limit:.2f} {'pass' if ok else 'FAIL'}")
        lines.append(f"| {m} | {mean:.4g} | {sd:.3g} | " + " | ".join(cells) + " |")
    lines += ["", f"Verdict per rank count (registered rule: exact atoms in every replica, "
              f"every |m_K - m_1| <= {T_QUANTILE} s_1 sqrt(1/n_K + 1/n_1)): "
              + ", ".join(f"{k} ranks **{'holds' if v else 'FAILS'}**"
                          for k, v in verdict.items())]
    return "\n".join(lines) + "\n", all(verdict.values())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("what", choices=("run", "table"))
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 4, 8])
    ap.add_argument("--write", type=Path, help="(table) also write the table into this file "
                    "between its '<!-- MARKER -->' and '<!-- /MARKER -->' lines")
    ap.add_argument("--marker", default="table2", help="(table) the markers' name (table2: "
                    "the second registration's table; the first one's, 'table', stays as run)")
    a = ap.parse_args(argv)
    if a.what == "run":
        if "--oversubscribe" not in os.environ.get("LIGWF_MPIRUN_ARGS", ""):
            print("note: LIGWF_MPIRUN_ARGS has no --oversubscribe: more ranks than cores "
                  "will be refused by mpirun", file=sys.stderr)
        run(a.out, a.ranks)
        return 0
    text, ok = table(a.out, a.ranks)
    print(text)
    if a.write:
        doc = a.write.read_text()
        head, sep, rest = doc.partition(f"<!-- {a.marker} -->\n")
        _, sep2, tail = rest.partition(f"<!-- /{a.marker} -->\n")
        if not (sep and sep2):
            print(f"{a.write}: no '<!-- {a.marker} -->' ... '<!-- /{a.marker} -->' markers",
                  file=sys.stderr)
            return 2
        a.write.write_text(head + sep + text + sep2 + tail)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
