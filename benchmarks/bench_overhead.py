#!/usr/bin/env python3
"""ligwf's overhead: ``ligwf run`` of one case against the same input run by hand (issue #15).

Target: the median wall-time ratio over >= 5 pairs is <= 1.03 (3 % overhead), on the CG3
case and on the CG1 case. Run it on a quiet machine: the script warns when the load
average is above 0.5 at the start.

    .venv/bin/python benchmarks/bench_overhead.py            # CG3: 10 runs of ~40 s
    .venv/bin/python benchmarks/bench_overhead.py --cg 1     # CG1: 10 runs of a few min
    .venv/bin/python benchmarks/bench_overhead.py --pairs 1 --settle-time 0.05 --run-time 0.05

The case: workflows/we_vs_bo.yaml, weber rule, replica 0. CG3 is 443 particles, the
workflow's own times (0.5 s settle, 4 s = 2 revolutions; about 40 s on one rank); CG1 is
11,963 particles, shortened by default to 0.1 s settle + 0.2 s turning (a few minutes per
run; the filling phase does not shrink). ``--settle-time`` / ``--run-time`` override
either; both sides run the same rendered input, so they always change alike.

What is timed (perf_counter, launch to exit of the subprocess):

* ligwf   ``python -m ligwf.cli.main run <workflow> --out <fresh> --np N --set ...``: Python
          start-up, render, pre-flight, writing the study, the engine under ligwf's live
          monitor, the health assessment and the manifest;
* hand    the ``mpirun`` command ligwf's runner builds (same -np, site launcher arguments,
          ``-var ligwf_pu/ligwf_pa`` processor grid, environment), run on the same
          in.liggghts in a fresh copy of the rendered case folder, screen to run.log.

Both sides start from an empty case folder every time, so they write the same dumps and
restarts. Pairs alternate the order (pair k: ligwf first when k is even), which cancels a
slow drift of the machine to first order. Every run must succeed (exit 0; ligwf's manifest
``done``; the hand run's log.liggghts ends the production run with its "Loop time" line),
and ligwf must have run the same command on the same input, or the benchmark aborts.
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.quiet import check_quiet  # noqa: E402
from ligwf.engine.guard import engine_env  # noqa: E402
from ligwf.study.manifest import DONE  # noqa: E402
from ligwf.engine.render import grid_vars  # noqa: E402
from ligwf.study.layout import INPUT_NAME  # noqa: E402
from ligwf.engine.site import EngineConfig  # noqa: E402
from ligwf.engine.thermo import parse_screen  # noqa: E402
from ligwf.scene.workflow import load_workflow  # noqa: E402
from ligwf.study.case import CaseFolder  # noqa: E402
from ligwf.study.layout import SCREEN_FILE  # noqa: E402
from ligwf.pipeline.prepare import render_workflow, write_study  # noqa: E402
from ligwf.study.study import Study  # noqa: E402
from ligwf.yamlio import read_yaml_mapping  # noqa: E402

WORKFLOW = ROOT / "workflows" / "we_vs_bo.yaml"
#: the issue's acceptance: median ligwf / hand wall ratio at most 1 + this
TARGET_OVERHEAD = 0.03
#: default (settle, run) times per CG level, s; None keeps the workflow's
DEFAULT_TIMES = {3: (None, None), 1: (0.1, 0.2)}
LOG_FILE = "log.liggghts"       # the -log name of EngineConfig.command
LIGWF_OUTPUT = "ligwf.out"      # ligwf's own stdout+stderr, next to its study folder


class BenchFailed(SystemExit):
    """A run failed or did not match the other side: no ratio is printed."""


def overrides(workflow: Path, cg: int, settle_time: float | None,
              run_time: float | None) -> list[str]:
    """The ``--set`` values selecting one case (weber, replica 0) at ``cg``. The workflow's
    ``sweep.per_cg`` entry of that level becomes scene values (the entries of the other
    levels would be refused once they are no longer swept); given times replace its own."""
    raw = read_yaml_mapping(workflow, "workflow file")
    per_cg = (raw.get("sweep") or {}).get("per_cg") or {}
    level = per_cg.get(cg, per_cg.get(float(cg))) or {}
    scene = {path.removeprefix("scene."): value for path, value in level.items()}
    if settle_time is not None:
        scene["process.settle_time"] = settle_time
    if run_time is not None:
        scene["process.run_time"] = run_time
    return [f"sweep.cg_levels=[{cg}]", "sweep.rules=[weber]", "sweep.replicas=1",
            "sweep.per_cg={}"] + [f"scene.{path}={json.dumps(v)}" for path, v in scene.items()]


def render_case(workflow: Path, sets: list[str], out: Path, mesh_cache: Path) -> CaseFolder:
    """Render the workflow with ``sets`` into ``out``; it must give exactly one case."""
    wf = load_workflow(workflow, sets)
    rendered = render_workflow(wf)
    if len(rendered) != 1:
        raise BenchFailed(f"{workflow} with {sets} gives {len(rendered)} cases, need exactly 1")
    return write_study(wf, rendered, out, mesh_cache).cases[0]


def tail(path: Path, lines: int = 15) -> str:
    try:
        return "\n".join(path.read_text(errors="replace").splitlines()[-lines:])
    except OSError:
        return f"({path} missing)"


def production_problem(log: Path, run_steps: int) -> str | None:
    """Why ``log`` does not show a finished production run of ``run_steps`` steps."""
    try:
        runs = parse_screen(log.read_text(errors="replace")).runs
    except OSError as exc:
        return f"cannot read {log}: {exc}"
    if not runs or runs[-1].phase != "production":
        return f"{log}: no production run"
    last = runs[-1]
    if last.loop_seconds is None:
        return f"{log}: the production run has no final 'Loop time' line"
    if last.steps != run_steps:
        return f"{log}: production ran {last.steps} steps, the input asks {run_steps}"
    return None


def run_by_hand(template: CaseFolder, folder: Path, command: list[str]) -> float:
    """Copy the rendered case to ``folder`` and run ``command`` there; wall seconds."""
    shutil.copytree(template.path, folder)
    with open(folder / SCREEN_FILE, "wb") as screen:
        t0 = time.perf_counter()
        code = subprocess.call(command, cwd=folder, stdout=screen, stderr=subprocess.STDOUT,
                               stdin=subprocess.DEVNULL, env=engine_env())
        wall = time.perf_counter() - t0
    if code != 0:
        raise BenchFailed(f"by-hand run in {folder} exited {code}:\n{tail(folder / SCREEN_FILE)}")
    problem = production_problem(folder / LOG_FILE, template.scaled.numerics.run_steps)
    if problem:
        raise BenchFailed(f"by-hand run: {problem}\n{tail(folder / SCREEN_FILE)}")
    return wall


def run_ligwf(workflow: Path, sets: list[str], study: Path, nprocs: int, mesh_cache: Path,
              template: CaseFolder, command: list[str]) -> tuple[float, float]:
    """``ligwf run`` into the fresh folder ``study``; (wall seconds, engine wall seconds
    from the manifest). Checks it ran ``command`` on the template's input."""
    cli = [sys.executable, "-m", "ligwf.cli.main", "run", str(workflow), "--out", str(study),
           "--np", str(nprocs), "--mesh-cache", str(mesh_cache)]
    cli += [arg for s in sets for arg in ("--set", s)]
    output = study.with_name(LIGWF_OUTPUT)
    with open(output, "wb") as out:
        t0 = time.perf_counter()
        code = subprocess.call(cli, stdout=out, stderr=subprocess.STDOUT,
                               stdin=subprocess.DEVNULL)
        wall = time.perf_counter() - t0
    if code != 0:
        raise BenchFailed(f"ligwf run exited {code}: {' '.join(cli)}\n{tail(output)}")
    case = Study.open(study).cases[0]
    manifest = case.manifest()
    if manifest is None or manifest.status != DONE:
        status = "no manifest" if manifest is None else f"{manifest.status}: {manifest.reason}"
        raise BenchFailed(f"ligwf run of {case.path} did not end done ({status})")
    if len(manifest.attempts) != 1 or manifest.attempts[0].command != command:
        raise BenchFailed(f"ligwf ran {[a.command for a in manifest.attempts]}, "
                          f"the hand side runs {command}")
    if (case.path / INPUT_NAME).read_bytes() != (template.path / INPUT_NAME).read_bytes():
        raise BenchFailed(f"{case.path / INPUT_NAME} differs from the rendered "
                          f"{template.path / INPUT_NAME}")
    return wall, manifest.attempts[0].wall_seconds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cg", type=int, choices=sorted(DEFAULT_TIMES), default=3,
                    help="CG level of the case (default 3)")
    ap.add_argument("--np", type=int, default=1, help="MPI ranks, both sides (default 1)")
    ap.add_argument("--pairs", type=int, default=5, help="ligwf/hand pairs (default 5)")
    ap.add_argument("--settle-time", type=float, default=None,
                    help="s at rest (default: workflow's for CG3, 0.1 for CG1)")
    ap.add_argument("--run-time", type=float, default=None,
                    help="s turning (default: workflow's for CG3, 0.2 for CG1)")
    ap.add_argument("--workflow", type=Path, default=WORKFLOW)
    ap.add_argument("--keep", action="store_true", help="keep the run folders")
    args = ap.parse_args()
    if args.pairs < 1 or args.np < 1:
        ap.error("--pairs and --np must be >= 1")
    default_settle, default_run = DEFAULT_TIMES[args.cg]
    settle = args.settle_time if args.settle_time is not None else default_settle
    run = args.run_time if args.run_time is not None else default_run
    sets = overrides(args.workflow, args.cg, settle, run)

    check_quiet("the timings below")
    work = Path(tempfile.mkdtemp(prefix="ligwf-overhead-"))
    mesh_cache = work / "meshes"
    rows = []
    try:
        template = render_case(args.workflow, sets, work / "rendered", mesh_cache)
        engine = EngineConfig.from_site()
        command = engine.command(INPUT_NAME, args.np, extra=grid_vars(template.scaled, args.np))
        s = template.scaled
        print(f"case {template.case_id}: {s.particles.count:,} particles, {s.total_steps:,} "
              f"steps (settle {s.numerics.settle_steps:,}, run {s.numerics.run_steps:,}), -np {args.np}")
        print(f"ligwf: ligwf run {args.workflow} --np {args.np} " +
              " ".join(f"--set {x}" for x in sets))
        print(f"hand:  {' '.join(command)}")
        print(f"runs in {work}\n")
        print(f"{'pair':>4} {'first':>6} {'ligwf s':>9} {'(engine s)':>10} {'hand s':>9} "
              f"{'ratio':>7}", flush=True)
        for k in range(args.pairs):
            pair = work / f"pair{k}"
            (pair / "ligwf").mkdir(parents=True)
            ligwf_first = k % 2 == 0
            if not ligwf_first:
                hand = run_by_hand(template, pair / "hand", command)
            ours, engine_wall = run_ligwf(args.workflow, sets, pair / "ligwf" / "study",
                                          args.np, mesh_cache, template, command)
            if ligwf_first:
                hand = run_by_hand(template, pair / "hand", command)
            rows.append((ours, hand))
            print(f"{k:>4} {'ligwf' if ligwf_first else 'hand':>6} {ours:>9.2f} "
                  f"{engine_wall:>10.2f} {hand:>9.2f} {ours / hand:>7.4f}", flush=True)
            if not args.keep:
                shutil.rmtree(pair)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)

    ratios = [ours / hand for ours, hand in rows]
    median = statistics.median(ratios)
    overhead = (median - 1.0) * 100.0
    print(f"\nmedian ratio {median:.4f} over {len(ratios)} pair(s): overhead {overhead:+.2f} % "
          f"(min {(min(ratios) - 1) * 100:+.2f} %, max {(max(ratios) - 1) * 100:+.2f} %)")
    verdict = "meets" if median <= 1.0 + TARGET_OVERHEAD else "MISSES"
    print(f"{verdict} the target of <= {TARGET_OVERHEAD * 100:g} % (CG{args.cg}, -np {args.np})")
    if args.keep:
        print(f"run folders kept in {work}")


if __name__ == "__main__":
    main()
