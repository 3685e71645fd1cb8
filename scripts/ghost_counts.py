#!/usr/bin/env python3
"""Per-rank atoms and ghosts of one turning bed on slabs and on 2-D grids (issue #24 item 4).

The scaling model (docs/results/performance/scaling_model.md) takes its halo depth and
checks its bed imbalance against these counts. A finished case's newest restart (a bed in
the turning drum) is continued for ``--steps`` steps by ``mpirun -np R liggghts`` with
ligwf's own resume input (``render_resume``) and each grid of ``--grids`` (``AxC``: A slabs
along the axis x C columns across, set with the input's ``-var ligwf_pa / ligwf_pu``); the
last run block of each log gives LIGGGHTS' ``Nlocal`` / ``Nghost`` average, max and min.
Beside each grid, what :func:`ligwf.engine.decomposition.grid_cost` predicts for it.

    LIGWF_MPIRUN_ARGS=--oversubscribe .venv/bin/python scripts/ghost_counts.py \\
        --case runs/we_vs_bo_controls/cg1-none-r0 --out /tmp/ghosts \\
        --grids 1x1 2x1 1x2 4x1 2x2 1x4 4x2 2x4

Counts are geometry (deterministic for a given state and grid); the loop seconds printed
on an oversubscribed, shared machine are not timing results.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ligwf.engine.decomposition import grid_cost, scene_bed  # noqa: E402
from ligwf.engine.ghosts import last_run_spread  # noqa: E402
from ligwf.engine.resume import render_resume, restart_files  # noqa: E402
from ligwf.study.layout import RESUME_INPUT  # noqa: E402
from ligwf.engine.site import EngineConfig  # noqa: E402
from ligwf.study.case import CaseFolder  # noqa: E402
from ligwf.study.layout import MESH_NAME  # noqa: E402

_RUN_RE = re.compile(r"^run \d+.*$", re.M)


def short_input(text: str, steps: int) -> str:
    """The resume input up to its first ``run`` line, which becomes ``run <steps>``; the
    restart and dump lines are dropped (nothing is written but the log)."""
    m = _RUN_RE.search(text)
    if m is None:
        raise SystemExit("the resume input has no run line")
    head = "\n".join(l for l in text[:m.start()].splitlines()
                     if not l.startswith(("restart ", "dump", "dump_modify")))
    return head + f"\nrun {steps}\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", type=Path, required=True)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--grids", nargs="+", default=["1x1", "2x1", "1x2", "4x1", "2x2", "1x4"])
    ap.add_argument("--steps", type=int, default=300)
    a = ap.parse_args(argv)
    case = CaseFolder.open(a.case)
    restart = max(restart_files(a.case), key=lambda r: r.step)
    text = short_input(render_resume(case.scaled, restart)[RESUME_INPUT], a.steps)
    engine = EngineConfig.from_site()
    s = case.scaled
    bed = scene_bed(s)
    print(f"{case.case_id}: {s.particles.count:,} particles, {s.drum.length * 1e3:g} mm slice, "
          f"d_max {s.d_max * 1e3:g} mm, restart at step {restart.step:,}, {a.steps} steps")
    print(f"{'grid AxC':>8} {'ranks':>5} {'atoms/rank':>10} {'max/avg':>7} {'min':>6} "
          f"{'ghosts avg':>10} {'max':>6} {'ghosts/atom':>11} {'model max/avg':>13} "
          f"{'model ghosts/atom':>17} {'loop s':>7}")
    for g in a.grids:
        axial, across = (int(x) for x in g.lower().split("x"))
        run_dir = a.out / f"grid_{axial}x{across}"
        run_dir.mkdir(parents=True, exist_ok=True)
        shutil.copy2(a.case / MESH_NAME, run_dir / MESH_NAME)
        src = Path(restart.path)
        src = src if src.is_absolute() else a.case / src
        shutil.copy2(src, run_dir / src.name)
        (run_dir / "in.ghosts").write_text(text.replace(str(restart.path), src.name))
        ranks = axial * across
        cmd = engine.command("in.ghosts", ranks, extra=["-var", "ligwf_pu", str(across),
                                                         "-var", "ligwf_pa", str(axial)])
        r = subprocess.run(cmd, cwd=run_dir, capture_output=True, text=True)
        log = (run_dir / "log.liggghts").read_text(errors="replace") \
            if (run_dir / "log.liggghts").exists() else r.stdout
        try:
            sp = last_run_spread(log)
        except ValueError:
            print(f"{g:>8}: engine exit {r.returncode}: {(r.stdout + r.stderr)[-400:]}")
            continue
        model = grid_cost(s.drum.length, s.d_max, s.drum.periodic, bed, axial, across)
        print(f"{g:>8} {sp.procs:>5} {sp.local_avg:>10.0f} {sp.imbalance:>7.2f} "
              f"{sp.local_min:>6.0f} {sp.ghost_avg:>10.0f} {sp.ghost_max:>6.0f} "
              f"{sp.ghosts_per_local:>11.3f} {model.imbalance:>13.2f} "
              f"{model.ghost_ratio:>17.3f} {sp.loop_seconds:>7.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
