#!/usr/bin/env python3
"""Neighbour skin from the physics (issue #15): bonds and forces as with the old skin, less time.

Before #15 every case ran ``neighbor <0.5 x smallest diameter> bin``; an unset
``scene.numerics.skin_ratio`` now takes the skin from the physics (ligwf.scene.neighbour:
about 0.15 d on this scene while settling and turning; the fill phase keeps a free-fall
skin). The engine rebuilds the lists once a particle has moved half a skin (``neigh_modify
delay 0``, check yes) and the bridges' reach is in its contact distance factor, so the skin
may change the cost, never the physics. This benchmark shows both on a real case:

    .venv/bin/python benchmarks/bench_skin.py                     # CG2, 0.3 s + 1 s, ~6 min
    .venv/bin/python benchmarks/bench_skin.py --run-time 0.5      # ~4 min
    .venv/bin/python benchmarks/bench_skin.py --cg 3 --keep       # keep the run folders
    .venv/bin/python benchmarks/bench_skin.py --new-skin-ratio 0.2   # NEW = a fixed ratio

The case: workflows/we_vs_bo.yaml, weber, replica 0 at ``--cg`` (default 2), ``sweep.per_cg={}``,
``--settle-time`` (default 0.3 s) and ``--run-time`` (default 1.0 s), granules on. It runs
twice with ligwf's runner (``run_case``), OLD then NEW (``--side-by-side``: both at once,
each ``mpirun --bind-to none``):

* OLD  ``--set scene.numerics.skin_ratio=0.5`` (the input before #15, exactly);
* NEW  the default, no override (``--new-skin-ratio R`` sets one instead).

Both render with a template folder of the benchmark's whose ``_contacts.j2`` is ligwf's with
``force force_normal`` added to ``compute pair/gran/local``, so the contact dumps carry the
engine's pair forces (alike in OLD and NEW; nothing else changes).

1. Cost per run: the production run's engine seconds (the last "Loop time" block of
   log.liggghts) with its Pair and Neigh seconds, "Ave neighs/atom", "Neighbor list builds"
   and "Dangerous builds"; the manifest's seconds per phase and in all; the time saved NEW vs
   OLD in %. One pair of runs on a shared machine: a few % is noise (load average printed).
2. Bond statistics over the production frames (``post/contacts_*.vtu`` through
   ``ligwf.analysis.frames.dumps.read_contacts``, forces of the same rows through
   ``ligwf.analysis.frames.vtu.read_vtu``): per frame the bridges per particle (2 x pairs /
   particles), the share of bridges in contact (overlap > 0), the median and 90th percentile
   of |F_n| (Hertz + capillary + viscous, N), the 10th/50th/90th percentiles of the overlap
   delta / d_min (negative: a gap). NEW vs OLD: z = difference of the frame means / combined
   standard error sqrt(s_old^2/n_old + s_new^2/n_new), s the frame-to-frame std; "same within
   noise" when |z| < 3. The runs diverge chaotically (another neighbour order sums forces in
   another order), so only statistics over time can agree; frames 0.02 s apart are
   correlated, so the standard error is if anything too small and a pass is conservative.
3. Exact forces: the newest production restart of the OLD run is continued by hand
   (``mpirun -np 1 liggghts``) with ligwf's resume input (``render_resume``; restarts and
   particle dump dropped, contacts dumped every step, ``run --exact-steps``, default 100),
   once per skin: the OLD and NEW inputs differ in one ``neighbor`` line. Pairs are matched
   by (id1, id2), forces turned onto the lower id; per step: pairs, pairs in one run only,
   max and median |dF|/|F| of the pair force, max of its normal part, pairs off by > 1e-8
   (of them across the periodic boundary); and the list builds of each run.

   (a) The verdict: both runs first go ``--warm-up`` steps (default 10) with the OLD skin,
       then ``neighbor <OLD or NEW skin> bin``. Step 0 is one state with lists rebuilt with
       each skin (forces must be bit for bit equal); after one step positions differ by the
       summation order only (round-off, <= ~1e-10); the growth over the window, with the NEW
       run's rebuilds in it, is the chaotic divergence.
   (b) For information: the resume input's own ``neighbor`` line changed, so each skin builds
       the first list after ``read_restart``. Measured: at the restart state one or two
       pairs across the periodic boundary already differ (0.5 % of |F| at CG3; 57 % for a
       separated bridge at CG2; which pairs depends on the skin; the OLD skin against itself
       is bit for bit equal) while (a) shows none: an effect of the first list built after a
       restart on the bridges across the boundary, not of the skin on the dynamics.
       (Resuming with the same skin is not bit for bit the uninterrupted run either: median
       |dF|/|F| 0.3 % 25 steps after a CG3 restart.)

Exit code 0 when (a) agrees to 1e-8 at steps 0 and 1 with identical pair sets, no run has a
dangerous build and every bond statistic is the same within noise; 1 otherwise.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ligwf.analysis.frames.dumps import discover_frames, read_contacts, read_particles  # noqa: E402
from ligwf.analysis.dumps_numba import first_of_each_pair  # noqa: E402
from ligwf.analysis.frames.vtu import read_vtu  # noqa: E402
from ligwf.engine.guard import engine_env  # noqa: E402
from ligwf.study.manifest import DONE  # noqa: E402
from ligwf.engine.launch import run_case  # noqa: E402
from ligwf.engine.render import grid_vars, shipped_template_dir  # noqa: E402
from ligwf.study.layout import MESH_NAME  # noqa: E402
from ligwf.engine.resume import render_resume, restart_files, resume_phase  # noqa: E402
from ligwf.engine.site import EngineConfig  # noqa: E402
from ligwf.study.layout import RESUME_INPUT  # noqa: E402
from ligwf.scene.workflow import load_workflow  # noqa: E402
from ligwf.study.case import CaseFolder  # noqa: E402
from ligwf.study.layout import SCREEN_FILE  # noqa: E402
from ligwf.pipeline.prepare import render_workflow, write_study  # noqa: E402

WORKFLOW = ROOT / "workflows" / "we_vs_bo.yaml"
LOG_FILE = "log.liggghts"            # the -log name of EngineConfig.command
#: the skin ratio of every case before issue #15
OLD_SKIN_RATIO = 0.5
#: |z| below which a statistic is "the same within noise"
Z_NOISE = 3.0
#: largest relative pair-force difference after one step that counts as round-off
EXACT_TOLERANCE = 1e-8
#: contact columns the benchmark adds to ligwf's compute pair/gran/local
FORCE_COLUMNS = ("force", "force_normal")


class BenchFailed(SystemExit):
    """A run or a check could not be carried out: no verdict is printed."""


def selection(cg: int, settle: float, run: float, skin_ratio: float | None) -> list[str]:
    """``--set`` values of the one weber case at ``cg`` with ``skin_ratio`` (None: default)."""
    sets = [f"sweep.cg_levels=[{cg}]", "sweep.rules=[weber]", "sweep.replicas=1",
            "sweep.per_cg={}", f"scene.process.settle_time={settle}",
            f"scene.process.run_time={run}", "scene.analysis.contact_dumps=true"]
    if skin_ratio is not None:
        sets.append(f"scene.numerics.skin_ratio={skin_ratio}")
    return sets


def force_templates(folder: Path) -> Path:
    """A template folder whose ``_contacts.j2`` is ligwf's with :data:`FORCE_COLUMNS` added."""
    shipped = (shipped_template_dir() / "_contacts.j2").read_text()
    pattern = re.compile(r"^(compute contacts all pair/gran/local .*)$", re.M)
    if len(pattern.findall(shipped)) != 1:
        raise BenchFailed("ligwf's _contacts.j2 no longer has one 'compute contacts all "
                          "pair/gran/local' line: update force_templates()")
    text = pattern.sub(lambda m: m.group(1) + " " + " ".join(FORCE_COLUMNS), shipped)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "_contacts.j2").write_text(text)
    return folder


def prepare(sets: list[str], out: Path, templates: Path) -> CaseFolder:
    wf = load_workflow(WORKFLOW, sets)
    rendered = render_workflow(wf, [templates])
    if len(rendered) != 1:
        raise BenchFailed(f"{sets} gives {len(rendered)} cases, need exactly 1")
    return write_study(wf, rendered, out, out.parent / "meshes").cases[0]


def run_cases(cases: dict[str, CaseFolder], nprocs: int, engine: EngineConfig,
              templates: Path, side_by_side: bool) -> None:
    """Run every case with ligwf's runner; each must end ``done``."""
    stop = threading.Event()
    failures: dict[str, str] = {}

    def one(label: str, case: CaseFolder, eng: EngineConfig) -> None:
        man = run_case(case, nprocs, eng, None, stop, template_dirs=[templates]) or case.manifest()
        if man is None or man.status != DONE:
            failures[label] = "no manifest" if man is None else f"{man.status}: {man.reason}"

    if not side_by_side:
        for label, case in cases.items():
            print(f"running {label}: {case.path} ...", flush=True)
            one(label, case, engine)
    else:
        # two separate mpiruns would each bind their rank to core 0: let the OS place them
        eng = dataclasses.replace(engine, mpirun_args=engine.mpirun_args + ("--bind-to", "none"))
        print(f"running {', '.join(cases)} side by side (--bind-to none) ...", flush=True)
        threads = [threading.Thread(target=one, args=(label, case, eng))
                   for label, case in cases.items()]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    if failures:
        raise BenchFailed("; ".join(f"{k} ended {v}" for k, v in failures.items()))


_LOOP_RE = re.compile(r"^Loop time of (\S+) on (\d+) procs for (\d+) steps with (\d+) atoms")
_BLOCK_KEYS = {
    "pair_s": re.compile(r"^Pair\s+time \(%\) = (\S+)"),
    "neigh_s": re.compile(r"^Neigh\s+time \(%\) = (\S+)"),
    "neighs_per_atom": re.compile(r"^Ave neighs/atom = (\S+)"),
    "builds": re.compile(r"^Neighbor list builds = (\S+)"),
    "dangerous": re.compile(r"^Dangerous builds = (\S+)"),
}


def run_blocks(log_text: str) -> list[dict[str, float]]:
    """The statistics LIGGGHTS prints after each ``run``: loop seconds, steps, Pair/Neigh
    seconds, Ave neighs/atom, list builds, dangerous builds."""
    blocks: list[dict[str, float]] = []
    for line in log_text.splitlines():
        line = line.strip()
        if m := _LOOP_RE.match(line):
            blocks.append({"loop_s": float(m.group(1)), "steps": int(m.group(3))})
        elif blocks:
            for key, rx in _BLOCK_KEYS.items():
                if m := rx.match(line):
                    blocks[-1].setdefault(key, float(m.group(1)))
    return blocks


def cost(case: CaseFolder) -> dict[str, float]:
    """Production-run statistics (last log block) and the manifest's wall seconds."""
    blocks = run_blocks((case.path / LOG_FILE).read_text(errors="replace"))
    if not blocks or blocks[-1]["steps"] != case.scaled.numerics.run_steps:
        raise BenchFailed(f"{case.path / LOG_FILE}: the last run block is not the production "
                          f"run of {case.scaled.numerics.run_steps} steps")
    row = dict(blocks[-1])
    man = case.manifest()
    row["wall_s"] = man.wall_seconds
    for phase in ("fill", "settle", "production"):
        row[f"{phase}_s"] = man.phases.get(phase, {}).get("wall_seconds", math.nan)
    return row


def saved(old: float, new: float) -> str:
    return f"{100.0 * (old - new) / old:+.1f} %" if old > 0 else "n/a"


def print_cost(cases: dict[str, CaseFolder], costs: dict[str, dict[str, float]]) -> None:
    print("\nCost (production = the last 'Loop time' block of log.liggghts; phases and "
          "total from the manifest)")
    print(f"{'run':>4} {'skin/d':>7} {'fill/d':>7} {'prod s':>8} {'Pair s':>8} {'Neigh s':>8} "
          f"{'neighs/atom':>11} {'builds':>7} {'steps/build':>11} {'dangerous':>9} "
          f"{'fill s':>7} {'settle s':>8} {'total s':>8}")
    for label, case in cases.items():
        s, c = case.scaled, costs[label]
        print(f"{label:>4} {s.numerics.skin / s.d_min:>7.3f} {s.skin_fill / s.d_min:>7.3f} "
              f"{c['loop_s']:>8.2f} {c.get('pair_s', math.nan):>8.2f} "
              f"{c.get('neigh_s', math.nan):>8.2f} {c.get('neighs_per_atom', math.nan):>11.2f} "
              f"{c.get('builds', 0):>7.0f} {c['steps'] / max(c.get('builds', 0), 1):>11.1f} "
              f"{c.get('dangerous', math.nan):>9.0f} {c['fill_s']:>7.2f} {c['settle_s']:>8.2f} "
              f"{c['wall_s']:>8.2f}")
    old, new = costs["OLD"], costs["NEW"]
    print(f"time saved NEW vs OLD: production {saved(old['loop_s'], new['loop_s'])} "
          f"({old['loop_s']:.2f} -> {new['loop_s']:.2f} s), "
          f"Pair {saved(old['pair_s'], new['pair_s'])}, whole run "
          f"{saved(old['wall_s'], new['wall_s'])} ({old['wall_s']:.2f} -> {new['wall_s']:.2f} s)")


@dataclasses.dataclass(frozen=True)
class PairForces:
    """Each interacting pair once (as read_contacts keeps it), forces onto particle ``lo``."""

    lo: np.ndarray          # (M,) int64, lower id
    hi: np.ndarray          # (M,) int64
    delta: np.ndarray       # (M,) overlap, m (negative: gap of a bridge)
    force: np.ndarray       # (M, 3) pair force on ``lo``, N
    force_normal: np.ndarray   # (M, 3) its normal part, N
    periodic: np.ndarray    # (M,) bool, the pair's line spans half the slice: across the boundary

    def keys(self) -> np.ndarray:
        """One int64 per pair, comparable between dumps (ids < 2^31)."""
        return (self.lo << 32) | self.hi


def read_pair_forces(path: Path, slice_length: float) -> PairForces:
    """A contact dump with forces. Ids, overlap and the choice of one row per pair are
    ``read_contacts``'; the force vectors come from the same file through ``read_vtu``.
    LIGGGHTS lists the force on ``id1``; which particle of a pair is ``id1`` depends on the
    atom order, so both vectors are turned onto the lower id (equal and opposite). A pair
    whose centres lie more than half the periodic ``slice_length`` (m) apart is a pair across
    the boundary (its line spans the box)."""
    frame = read_contacts(path)
    if len(frame) == 0:
        z = np.zeros((0, 3))
        return PairForces(frame.id1, frame.id2, frame.delta, z, z.copy(), np.zeros(0, bool))
    vtu = read_vtu(path, frozenset(("Points", "id1", "id2") + FORCE_COLUMNS), "fast")
    data = vtu.cell_data
    missing = [c for c in FORCE_COLUMNS if c not in data]
    if missing:
        raise BenchFailed(f"{path}: no {', '.join(missing)} array (not rendered with the "
                          "benchmark's _contacts.j2?)")
    id1 = np.asarray(data["id1"]).astype(np.int64).reshape(-1)
    id2 = np.asarray(data["id2"]).astype(np.int64).reshape(-1)
    sign = np.where(id1 < id2, 1.0, -1.0)[:, None]
    lo, hi = np.minimum(id1, id2), np.maximum(id1, id2)
    first = first_of_each_pair(lo, hi)
    rows = np.arange(len(lo)) if first is None else first
    if not (np.array_equal(lo[rows], frame.id1) and np.array_equal(hi[rows], frame.id2)):
        raise BenchFailed(f"{path}: the pairs read with forces differ from read_contacts'")
    force = (np.asarray(data["force"], dtype=float).reshape(-1, 3) * sign)[rows]
    normal = (np.asarray(data["force_normal"], dtype=float).reshape(-1, 3) * sign)[rows]
    ends = np.asarray(vtu.points, dtype=float).reshape(-1, 2, 3)       # two centres per line
    span = np.linalg.norm(ends[:, 0] - ends[:, 1], axis=1)[rows]
    periodic = span > 0.5 * slice_length
    return PairForces(frame.id1, frame.id2, frame.delta, force, normal, periodic)


#: per-frame bond statistics: (key, label, format)
METRICS = (
    ("bridges", "bridges per particle", ".4f"),
    ("touching", "share of bridges in contact", ".4f"),
    ("fn_med", "|F_n| median, N", ".4e"),
    ("fn_p90", "|F_n| 90th percentile, N", ".4e"),
    ("delta_p10", "delta/d_min 10th percentile", ".3e"),
    ("delta_med", "delta/d_min median", ".3e"),
    ("delta_p90", "delta/d_min 90th percentile", ".3e"),
)


def bond_statistics(case: CaseFolder, skip_time: float) -> tuple[list[int], dict[str, np.ndarray]]:
    """Per production frame (after ``skip_time`` s of turning): the :data:`METRICS`."""
    s = case.scaled
    first = case.production_start_step + int(round(skip_time / s.numerics.dt))
    frames = [f for f in discover_frames(case.path) if f.step >= first and f.contacts is not None]
    if len(frames) < 2:
        raise BenchFailed(f"{case.path}: {len(frames)} production contact frames, need >= 2")
    rows: dict[str, list[float]] = {key: [] for key, _, _ in METRICS}
    for f in frames:
        pf = read_pair_forces(f.contacts, s.drum.length)
        if len(pf.lo) == 0:
            raise BenchFailed(f"{f.contacts}: no bridges in a production frame")
        fn = np.linalg.norm(pf.force_normal, axis=1)
        d = pf.delta / s.d_min
        rows["bridges"].append(2.0 * len(pf.lo) / len(read_particles(f.particles)))
        rows["touching"].append(float(np.mean(d > 0)))
        rows["fn_med"].append(float(np.median(fn)))
        rows["fn_p90"].append(float(np.percentile(fn, 90)))
        for key, q in (("delta_p10", 10), ("delta_med", 50), ("delta_p90", 90)):
            rows[key].append(float(np.percentile(d, q)))
    return [f.step for f in frames], {k: np.asarray(v) for k, v in rows.items()}


def z_score(old: np.ndarray, new: np.ndarray) -> float:
    """(mean new - mean old) / combined standard error of the frame means."""
    se = math.sqrt(old.var(ddof=1) / len(old) + new.var(ddof=1) / len(new))
    diff = float(new.mean() - old.mean())
    return 0.0 if diff == 0 else (diff / se if se > 0 else math.inf)


def print_bonds(stats: dict[str, tuple[list[int], dict[str, np.ndarray]]]) -> bool:
    (steps_old, old), (steps_new, new) = stats["OLD"], stats["NEW"]
    print(f"\nBond statistics over the production frames (OLD {len(steps_old)} frames, NEW "
          f"{len(steps_new)}; mean +- frame-to-frame std; z = difference / combined s.e.)")
    if steps_old != steps_new:
        print("  note: the two runs dumped at different steps")
    print(f"{'statistic':<28} {'OLD':>24} {'NEW':>24} {'z':>6}  verdict")
    same = True
    for key, label, fmt in METRICS:
        z = z_score(old[key], new[key])
        ok = abs(z) < Z_NOISE
        same &= ok
        cell = lambda a: f"{a.mean():{fmt}} +- {a.std(ddof=1):{fmt}}"  # noqa: E731
        print(f"{label:<28} {cell(old[key]):>24} {cell(new[key]):>24} {z:>6.2f}  "
              f"{'same within noise' if ok else 'DIFFERENT (|z| >= 3)'}")
    return same


#: steps of the exact check shown in its tables (those within --exact-steps)
SHOWN_STEPS = (0, 1, 2, 5, 10, 20, 50, 100, 200)


def exact_inputs(text: str, skin: float, steps: int, warm_up: int) -> dict[str, str]:
    """ligwf's production resume input ``text`` without restarts and particle dump, the
    contacts dumped every step, ``run <steps>`` instead of ``upto``; per variant (module
    docstring, 3.) ``skin`` from the switch after ``warm_up`` steps, or from the restart."""
    edits = (
        (r"^restart .*\n", ""),
        (r"^dump(_modify)? particles .*\n", ""),
        (r"^(dump contacts all local/gran/vtk) \d+ ", r"\1 1 "),
        (r"^run \d+ upto$", f"run {steps}"),
    )
    for pattern, repl in edits:
        text, n = re.subn(pattern, repl, text, flags=re.M)
        if n == 0:
            raise BenchFailed(f"resume input: no line matches {pattern!r}: update exact_inputs()")
    neighbor = re.compile(r"^neighbor \S+ bin$", re.M)
    first_run = re.compile(r"^run 0$", re.M)
    rotate = re.compile(r"^fix rotate .*\n", re.M)
    if not len(neighbor.findall(text)) == len(first_run.findall(text)) == len(
            rotate.findall(text)) == 1:
        raise BenchFailed("resume input: not one neighbor line, 'run 0' and 'fix rotate': "
                          "update exact_inputs()")
    # the drum turns during the warm-up; the dumps are defined after it, so their first
    # frame is written at the setup of the measured run, with lists of the new skin
    turning = rotate.search(text).group(0)
    switched = first_run.sub(f"run 0\n{turning}run {warm_up}\nneighbor {skin!r} bin",
                             rotate.sub("", text))
    return {"switched": switched, "restart": neighbor.sub(f"neighbor {skin!r} bin", text)}


def run_exact(case: CaseFolder, folder: Path, text: str, restart_path: str,
              engine: EngineConfig) -> dict[str, float]:
    """Run ``text`` on one rank in ``folder`` (mesh and restart copied from ``case``);
    the statistics of its last run block."""
    (folder / "post").mkdir(parents=True)
    (folder / Path(restart_path).parent).mkdir(parents=True, exist_ok=True)
    shutil.copy2(case.path / MESH_NAME, folder / MESH_NAME)
    shutil.copy2(case.path / restart_path, folder / restart_path)
    (folder / RESUME_INPUT).write_text(text)
    cmd = engine.command(RESUME_INPUT, 1, extra=grid_vars(case.scaled, 1))
    with open(folder / SCREEN_FILE, "wb") as screen:
        code = subprocess.call(cmd, cwd=folder, stdout=screen, stderr=subprocess.STDOUT,
                               stdin=subprocess.DEVNULL, env=engine_env())
    if code != 0:
        tail = "\n".join((folder / SCREEN_FILE).read_text(errors="replace").splitlines()[-15:])
        raise BenchFailed(f"exact run in {folder} exited {code}:\n{tail}")
    return run_blocks((folder / LOG_FILE).read_text(errors="replace"))[-1]


def compare_frames(old: PairForces, new: PairForces) -> dict[str, float]:
    """Pair sets and relative force differences |dF| / |F| of two dumps of one step."""
    common, i_old, i_new = np.intersect1d(old.keys(), new.keys(), return_indices=True)
    out = {"pairs": len(old.lo), "only_old": len(old.lo) - len(common),
           "only_new": len(new.lo) - len(common)}
    for name in FORCE_COLUMNS:
        a, b = getattr(old, name)[i_old], getattr(new, name)[i_new]
        size = np.linalg.norm(a, axis=1)
        rel = np.where(size > 0, np.linalg.norm(b - a, axis=1) / np.where(size > 0, size, 1), 0)
        out[name] = float(rel.max(initial=0.0))
        out[name + "_median"] = float(np.median(rel)) if len(rel) else 0.0
        if name == "force":
            off = rel > EXACT_TOLERANCE
            out["off"] = int(off.sum())
            out["off_periodic"] = int((off & old.periodic[i_old]).sum())
    return out


def exact_table(folders: dict[str, Path], first_step: int, steps: int,
                slice_length: float) -> dict[int, dict]:
    """Compare the OLD and NEW contact dumps of the shown steps; print and return them."""
    print(f"{'step':>5} {'pairs':>6} {'only OLD':>8} {'only NEW':>8} {'max |dF|/|F|':>13} "
          f"{'median':>9} {'max |dFn|/|Fn|':>15} {'> 1e-8 (periodic)':>18}")
    rows = {}
    for k in [k for k in SHOWN_STEPS if k < steps] + [steps]:
        frames = [read_pair_forces(folders[label] / "post" / f"contacts_{first_step + k}.vtu",
                                   slice_length) for label in ("OLD", "NEW")]
        c = rows[k] = compare_frames(*frames)
        print(f"{k:>5} {c['pairs']:>6} {c['only_old']:>8} {c['only_new']:>8} {c['force']:>13.3e} "
              f"{c['force_median']:>9.2e} {c['force_normal']:>15.3e} "
              f"{c['off']:>10} ({c['off_periodic']})")
    return rows


def exact_check(old_case: CaseFolder, new_skin: float, steps: int, warm_up: int,
                engine: EngineConfig, templates: Path, work: Path) -> bool:
    s = old_case.scaled
    production = [r for r in restart_files(old_case.path)
                  if resume_phase(s, r.step)[0] == "production"]
    if not production:
        raise BenchFailed(f"{old_case.path}: no periodic restart written while turning "
                          "(production shorter than the restart interval?): "
                          "use a longer --run-time")
    restart = production[0]
    (text,) = render_resume(s, restart, [templates]).values()
    skins = {"OLD": s.numerics.skin, "NEW": new_skin}
    inputs = {label: exact_inputs(text, skin, steps, warm_up)
              for label, skin in skins.items()}
    for variant in ("switched", "restart"):
        differ = [(a, b) for a, b in zip(inputs["OLD"][variant].splitlines(),
                                         inputs["NEW"][variant].splitlines()) if a != b]
        if len(differ) > 1:
            raise BenchFailed(f"exact inputs differ in more than the neighbor line: {differ}")
    print(f"\nExact force check from {restart.path} of OLD (step {restart.step}, "
          f"{(restart.step - old_case.production_start_step) * s.numerics.dt:.3f} s into production), "
          f"1 rank, ligwf's resume input, skin OLD {skins['OLD']:.4g} m vs NEW "
          f"{skins['NEW']:.4g} m, contacts dumped every step", flush=True)
    verdict = True
    for variant, first_step, title in (
            ("switched", restart.step + warm_up,
             f"(a) both {warm_up} steps with the OLD skin after the restart, then OLD vs NEW "
             f"skin (step 0: same state, lists rebuilt with each skin)"),
            ("restart", restart.step,
             "(b) OLD vs NEW skin straight from read_restart (step 0: the restart state)")):
        folders = {label: work / "exact" / variant / label for label in skins}
        blocks = {label: run_exact(old_case, folders[label], inputs[label][variant],
                                   restart.path, engine) for label in skins}
        builds = {label: blocks[label].get("builds", 0) for label in skins}
        print(f"{title}; list builds in the {steps} steps: OLD {builds['OLD']:.0f}, "
              f"NEW {builds['NEW']:.0f}")
        rows = exact_table(folders, first_step, steps, s.drum.length)
        if variant == "switched":
            verdict = all(rows[k]["only_old"] == 0 and rows[k]["only_new"] == 0
                          and rows[k]["force"] <= EXACT_TOLERANCE
                          and rows[k]["force_normal"] <= EXACT_TOLERANCE for k in (0, 1))
            print(f"(a) after 0 and 1 step: {'agrees' if verdict else 'DISAGREES'} (identical "
                  f"pair sets, max relative difference <= {EXACT_TOLERANCE:g})")
        else:
            r0 = rows[0]
            print(f"(b) at the restart state {r0['off']} pair(s) differ, {r0['off_periodic']} of "
                  "them across the periodic boundary (the first list after read_restart; "
                  "none at step 0 of (a))")
    return verdict


def load_line(when: str) -> None:
    one, five, _ = os.getloadavg()
    print(f"load average {when}: {one:.2f} (1 min), {five:.2f} (5 min)", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cg", type=int, choices=(1, 2, 3), default=2, help="CG level (default 2)")
    ap.add_argument("--settle-time", type=float, default=0.3, help="s at rest (default 0.3)")
    ap.add_argument("--run-time", type=float, default=1.0, help="s turning (default 1.0)")
    ap.add_argument("--np", type=int, default=1, help="MPI ranks per run (default 1)")
    order = ap.add_mutually_exclusive_group()
    order.add_argument("--serial", dest="side_by_side", action="store_false",
                       help="OLD, then NEW (default)")
    order.add_argument("--side-by-side", dest="side_by_side", action="store_true",
                       help="both at once, each mpirun --bind-to none")
    ap.add_argument("--new-skin-ratio", type=float, default=None,
                    help="NEW skin / d_min (default: unset, the skin from the physics)")
    ap.add_argument("--skip-time", type=float, default=0.0,
                    help="s of turning left out of the bond statistics (default 0)")
    ap.add_argument("--exact-steps", type=int, default=100,
                    help="steps of the exact force check (default 100)")
    ap.add_argument("--warm-up", type=int, default=10,
                    help="steps with the OLD skin after the restart before the exact check "
                    "switches skins (default 10)")
    ap.add_argument("--keep", action="store_true", help="keep the run folders")
    ap.set_defaults(side_by_side=False)
    args = ap.parse_args()
    if args.np < 1 or args.exact_steps < 1 or args.warm_up < 1:
        ap.error("--np, --exact-steps and --warm-up must be >= 1")

    work = Path(tempfile.mkdtemp(prefix="bench_skin_"))
    templates = force_templates(work / "templates")
    ratios = {"OLD": OLD_SKIN_RATIO, "NEW": args.new_skin_ratio}
    cases = {label: prepare(selection(args.cg, args.settle_time, args.run_time, r),
                            work / label.lower(), templates) for label, r in ratios.items()}
    s = cases["OLD"].scaled
    print(f"case: {WORKFLOW.name} CG{args.cg} weber r0, {s.particles.count} particles, dt "
          f"{s.numerics.dt:.4g} s, settle {args.settle_time:g} s + production {args.run_time:g} s "
          f"({s.numerics.run_steps} steps), -np {args.np}, "
          f"{'side by side' if args.side_by_side else 'serial'}; runs in {work}")
    for label, case in cases.items():
        c = case.scaled
        how = ("default (from the physics)" if ratios[label] is None
               else f"skin_ratio={ratios[label]}")
        print(f"  {label}: {how}: skin {c.numerics.skin:.4g} m = {c.numerics.skin / c.d_min:.3f} d_min, "
              f"fill {c.skin_fill:.4g} m = {c.skin_fill / c.d_min:.3f} d_min")
    engine = EngineConfig.from_site()
    load_line("at start")
    run_cases(cases, args.np, engine, templates, args.side_by_side)
    load_line("after the runs")

    costs = {label: cost(case) for label, case in cases.items()}
    print_cost(cases, costs)
    stats = {label: bond_statistics(case, args.skip_time) for label, case in cases.items()}
    same = print_bonds(stats)
    exact = exact_check(cases["OLD"], cases["NEW"].scaled.numerics.skin, args.exact_steps, args.warm_up,
                        engine, templates, work)
    safe = all(c.get("dangerous", 1) == 0 for c in costs.values())
    ok = same and exact and safe
    print(f"\nverdict: bonds {'same within noise' if same else 'DIFFER'}; exact forces "
          f"{'agree' if exact else 'DISAGREE'}; dangerous builds {'none' if safe else 'SOME'}; "
          f"production time saved {saved(costs['OLD']['loop_s'], costs['NEW']['loop_s'])}")
    if args.keep:
        print(f"run folders kept in {work}")
    else:
        shutil.rmtree(work, ignore_errors=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
