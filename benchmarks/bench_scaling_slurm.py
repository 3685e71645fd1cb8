#!/usr/bin/env python3
"""Strong scaling of the paper-scale case on a real Slurm cluster (issue #24 item 4).

The scaling model (docs/results/performance/scaling_model.md) estimates the efficiency of
the planner's grids at 64-256 ranks from measurements at 1-8 ranks on a 2-core machine;
this is the command that measures it where the ranks exist:

    # submit one job per rank count (the same case, the planner's grid for each count)
    .venv/bin/python benchmarks/bench_scaling_slurm.py submit --out runs/scaling \\
        --ranks 16 32 64 128 --cores-per-node 64 --partition P --time 04:00:00
    # when they have ended: seconds per step, per-rank atoms and ghosts, efficiency
    .venv/bin/python benchmarks/bench_scaling_slurm.py collect --out runs/scaling
    # what the model predicts for the same case (no run; --out is not used)
    .venv/bin/python benchmarks/bench_scaling_slurm.py model --out - --ranks 15 64 128 256

``submit`` runs ``ligwf slurm submit`` once per rank count into ``OUT/np<R>`` with
``--ntasks R`` (every case of that study on R ranks) and ``--no-analysis``: the
``workflows/paper_scale.yaml`` CG1 case (``--cg`` for another level), one seed, a short
production (``--run-time``, default 0.2 s; the fill and settling are run but not timed).
``--dry-run`` passes ``--dry-run`` on (scripts and sbatch lines printed, nothing submitted).
``collect`` reads each ``OUT/np<R>/<case>/log.liggghts``: the last ``Loop time`` block
(the production run) gives seconds per step, its Comm share and LIGGGHTS' per-rank
``Nlocal`` / ``Nghost`` (average, max); it prints per rank count the processor grid, the
imbalance, ghosts per particle, the speed-up over the smallest rank count and the
efficiency = speed-up / (R / R_smallest), beside the planner's modelled efficiency. Timing
is wall time of the engine's loop: run it on otherwise idle nodes (``--exclusive`` in the
site's ``extra``) or the ratios measure the neighbours.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ligwf.engine.ghosts import RankSpread, last_run_spread  # noqa: E402
from ligwf.engine.plan import case_grid, case_load, efficiency, estimated_seconds  # noqa: E402
from ligwf.study.case import CaseFolder  # noqa: E402

WORKFLOW = ROOT / "workflows" / "paper_scale.yaml"
_GRID_RE = re.compile(r"(\d+) by (\d+) by (\d+) MPI processor grid")


def ligwf() -> list[str]:
    return [sys.executable, "-m", "ligwf.cli.main"]


def submit_commands(out: Path, ranks: list[int], workflow: Path, cg: int, run_time: float,
                    settle_time: float, extra: list[str], dry_run: bool) -> list[list[str]]:
    """One ``ligwf slurm submit`` command per rank count (pure: nothing runs)."""
    sets = [f"sweep.cg_levels=[{cg}]", "sweep.rules=[weber]", "sweep.replicas=1",
            "sweep.per_cg={}", "sweep.controls=[]", f"scene.process.run_time={run_time:g}",
            f"scene.process.settle_time={settle_time:g}", "scene.analysis.contact_dumps=false"]
    cmds = []
    for r in sorted(set(ranks)):
        cmd = ligwf() + ["slurm", "submit", str(workflow), "--out", str(out / f"np{r}"),
                         "--ntasks", str(r), "--no-analysis"]
        cmd += [a for s in sets for a in ("--set", s)] + extra
        cmds.append(cmd + (["--dry-run"] if dry_run else []))
    return cmds


@dataclass(frozen=True)
class ScalingRow:
    """One finished rank count: its case folder, grid and production block."""

    ranks: int
    case: Path
    grid: tuple[int, int, int]
    spread: RankSpread
    modelled: float            # the planner's efficiency for this case at these ranks

    @property
    def seconds_per_step(self) -> float:
        return self.spread.loop_seconds / self.spread.steps


def collect(out: Path) -> list[ScalingRow]:
    """The rank counts under ``out`` (``np<R>`` folders) whose case logged a finished
    production run, smallest first; the others are named on stderr."""
    rows = []
    for folder in sorted(out.glob("np*"), key=lambda p: int(p.name[2:] or 0)):
        if not folder.name[2:].isdigit():
            continue
        cases = [p for p in sorted(folder.iterdir()) if (p / "scene.json").exists()]
        log = cases[0] / "log.liggghts" if cases else None
        try:
            text = log.read_text(errors="replace") if log else ""
            spread = last_run_spread(text)
        except (OSError, ValueError) as exc:
            print(f"{folder}: no finished production run ({exc})", file=sys.stderr)
            continue
        case = CaseFolder.open(cases[0])
        if spread.steps != case.scaled.numerics.run_steps:
            print(f"{folder}: the last run block has {spread.steps} steps, not the "
                  f"production's {case.scaled.numerics.run_steps} (still running?)", file=sys.stderr)
            continue
        grid = _GRID_RE.findall(text)
        rows.append(ScalingRow(spread.procs, cases[0],
                               tuple(int(g) for g in grid[-1]) if grid else (0, 0, 0),
                               spread, efficiency(case_load(case.case_id, case.scaled),
                                                  spread.procs)))
    return rows


def table(rows: list[ScalingRow]) -> str:
    """The strong-scaling table: speed-up and efficiency against the smallest rank count."""
    if not rows:
        return "no finished rank count to compare"
    base = rows[0]
    lines = [f"{'ranks':>6} {'grid':>10} {'s/step':>9} {'Comm %':>7} {'atoms/rank':>10} "
             f"{'max/avg':>7} {'ghosts/atom':>11} {'speed-up':>8} {'efficiency':>10} "
             f"{'modelled':>8}"]
    for r in rows:
        speedup = base.seconds_per_step / r.seconds_per_step
        eff = speedup * base.ranks / r.ranks
        comm = 100 * r.spread.seconds.get("Comm", float("nan")) / r.spread.loop_seconds
        modelled = r.modelled / base.modelled
        lines.append(f"{r.ranks:>6} {'x'.join(map(str, r.grid)):>10} "
                     f"{r.seconds_per_step:>9.3e} {comm:>7.1f} {r.spread.local_avg:>10.0f} "
                     f"{r.spread.imbalance:>7.2f} {r.spread.ghosts_per_local:>11.2f} "
                     f"{speedup:>8.2f} {eff:>10.2f} {modelled:>8.2f}")
    lines.append(f"(speed-up and efficiency against {base.ranks} rank(s); 'modelled': the "
                 "planner's efficiency at R over its efficiency at the smallest count)")
    return "\n".join(lines)


def model_table(workflow: Path, cg: int, ranks: list[int]) -> str:
    """What the planner's model says for the workflow's case at each rank count: grid,
    imbalance, ghosts per particle, efficiency and estimated wall time (no run)."""
    from ligwf.scene.workflow import load_workflow
    wf = load_workflow(workflow, [f"sweep.cg_levels=[{cg}]", "sweep.rules=[weber]",
                                  "sweep.replicas=1", "sweep.per_cg={}", "sweep.controls=[]"])
    case = wf.cases[0]
    load = case_load(case.case_id, case.scaled())
    lines = [f"{case.case_id}: {load.particles:,} particles, {load.steps:,} steps",
             f"{'ranks':>6} {'axial x across':>14} {'max/avg':>7} {'ghosts/atom':>11} "
             f"{'efficiency':>10} {'est. wall h':>11} {'core-h':>7}"]
    for r in ranks:
        try:
            g = case_grid(load, r)
        except Exception as exc:                # ConfigError: no grid of r ranks fits
            lines.append(f"{r:>6} {'-':>14}  {exc}")
            continue
        hours = estimated_seconds(load, r) / 3600
        lines.append(f"{r:>6} {f'{g.axial} x {g.across}':>14} {g.imbalance:>7.2f} "
                     f"{g.ghost_ratio:>11.2f} {efficiency(load, r):>10.2f} {hours:>11.2f} "
                     f"{hours * r:>7.1f}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("what", choices=("submit", "collect", "model"))
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--ranks", type=int, nargs="+", default=[16, 32, 64, 128])
    ap.add_argument("--workflow", type=Path, default=WORKFLOW)
    ap.add_argument("--cg", type=int, default=1)
    ap.add_argument("--run-time", type=float, default=0.2, help="production seconds (timed)")
    ap.add_argument("--settle-time", type=float, default=0.1)
    ap.add_argument("--dry-run", action="store_true")
    a, extra = ap.parse_known_args(argv)      # the rest goes to 'ligwf slurm submit'
    if a.what == "collect":
        print(table(collect(a.out)))
        return 0
    if a.what == "model":
        print(model_table(a.workflow, a.cg, a.ranks))
        return 0
    if any(r < 1 for r in a.ranks):
        print(f"--ranks = {a.ranks}: every rank count must be >= 1", file=sys.stderr)
        return 2
    code = 0
    for cmd in submit_commands(a.out, a.ranks, a.workflow, a.cg, a.run_time, a.settle_time,
                               extra, a.dry_run):
        print("$ ligwf", " ".join(cmd[3:]), flush=True)
        code = max(code, subprocess.run(cmd).returncode)
    return code


if __name__ == "__main__":
    sys.exit(main())
