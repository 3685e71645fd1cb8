"""A wet case on 4 ranks, more than this machine's cores (issue #24): the real engine under
``mpirun --oversubscribe`` on the planner's 2-D grid (2 slabs along the axis x 2 columns
across) keeps the exact particle count, and every rank holds part of the bed.

The statistical check (1/2/4/8 ranks against the CG1 seed floor) is
``scripts/ranks_correctness.py`` (docs/results/performance/ranks.md); this test is its
small, always-run part: ~750 CG1 particles, 0.02 s settling, 0.1 s turning.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest

from helpers import ROOT
from ligwf.analysis.frames.dumps import discover_frames, read_particles
from ligwf.engine.ghosts import last_run_spread
from ligwf.engine.render import processor_grid
from ligwf.study.case import CaseFolder
from ligwf.study.manifest import read_manifest

pytestmark = [pytest.mark.engine, pytest.mark.mpi]

WORKFLOW = ROOT / "tests" / "workflows" / "runner_tiny.yaml"
#: CG1 of the runner's tiny drum at a tenth of it filled: ~750 particles of 1.5 mm in
#: 18 mm (3 slabs at most), so 4 ranks are 2 slabs x 2 columns across
CG1_SMALL = ("sweep.cg_levels=[1]", "sweep.rules=[weber]", "scene.process.fill_fraction=0.1")


def test_four_ranks_keep_every_particle_on_a_two_by_two_grid(tmp_path):
    out = tmp_path / "study"
    env = dict(os.environ)
    env["LIGWF_MPIRUN_ARGS"] = (env.get("LIGWF_MPIRUN_ARGS", "") + " --oversubscribe").strip()
    sets = [a for s in CG1_SMALL for a in ("--set", s)]
    r = subprocess.run([sys.executable, "-m", "ligwf.cli.main", "run", str(WORKFLOW), "--out",
                        str(out), *sets, "--np", "4"], capture_output=True, text=True,
                       timeout=900, env=env)
    assert r.returncode == 0, r.stdout + r.stderr
    (case_dir,) = [p for p in out.iterdir() if (p / "scene.json").exists()]
    case = CaseFolder.open(case_dir)
    m = read_manifest(case_dir)
    n = case.scaled.particles.count
    assert m.status == "done", m.reason
    assert m.nprocs == 4
    assert m.atoms_after_settle == m.atoms_end == n > 500
    # the grid the engine ran is the planner's: axis y, so "across by axial by 1"
    across, axial = processor_grid(case.scaled, 4)
    assert (across, axial) == (2, 2)
    log = (case_dir / "log.liggghts").read_text(errors="replace")
    assert re.findall(r"(\d+) by (\d+) by (\d+) MPI processor grid", log)[-1] == ("2", "2", "1")
    spread = last_run_spread(log)
    assert (spread.procs, spread.atoms) == (4, n)
    assert spread.local_avg * 4 == pytest.approx(n)
    assert spread.local_min > 0 and spread.ghost_min > 0     # the cuts run through the bed
    last = discover_frames(case_dir)[-1]
    ids = read_particles(last.particles).ids
    assert len(ids) == n and len(set(ids.tolist())) == n
