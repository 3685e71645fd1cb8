"""benchmarks/bench_scaling_slurm.py, the strong-scaling command for a real cluster: what it
submits (dry run: the real ``ligwf slurm submit --dry-run``, nothing written or queued), the
model table it prints, and its collection of a finished rank count from a real log."""

from __future__ import annotations

import importlib.util
import shutil
import sys

from helpers import ROOT
from ligwf.engine.plan import case_load, plan_ranks
from ligwf.scene.workflow import load_workflow

SPEC = importlib.util.spec_from_file_location("bench_scaling_slurm",
                                              ROOT / "benchmarks" / "bench_scaling_slurm.py")
bench = importlib.util.module_from_spec(SPEC)
sys.modules[SPEC.name] = bench              # its dataclasses look their module up there
SPEC.loader.exec_module(bench)


def test_one_submission_per_rank_count_on_that_many_ranks(tmp_path):
    cmds = bench.submit_commands(tmp_path, [64, 16, 64], bench.WORKFLOW, 1, 0.2, 0.1,
                                 ["--partition", "big"], dry_run=True)
    assert len(cmds) == 2
    for cmd, ranks in zip(cmds, (16, 64)):
        assert cmd[3:5] == ["slurm", "submit"]
        assert cmd[cmd.index("--ntasks") + 1] == str(ranks)
        assert cmd[cmd.index("--out") + 1] == str(tmp_path / f"np{ranks}")
        assert "--no-analysis" in cmd and cmd[-3:] == ["--partition", "big", "--dry-run"]
        assert "sweep.cg_levels=[1]" in cmd and "scene.process.run_time=0.2" in cmd


def test_dry_run_prints_the_jobs_and_writes_nothing(tmp_path, capfd, monkeypatch):
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    code = bench.main(["submit", "--out", str(tmp_path / "scaling"), "--ranks", "16",
                       "--dry-run", "--cores-per-node", "64"])
    out = capfd.readouterr().out
    assert code == 0, out
    assert "--ntasks=16" in out and "would run: sbatch" in out
    assert not (tmp_path / "scaling").exists()


def test_the_model_table_is_the_planners():
    text = bench.model_table(bench.WORKFLOW, 1, [15, 119])
    wf = load_workflow(bench.WORKFLOW, ["sweep.cg_levels=[1]", "sweep.rules=[weber]",
                                        "sweep.replicas=1", "sweep.per_cg={}"])
    plan = plan_ranks(case_load("c", wf.cases[0].scaled()), None)
    row = next(l for l in text.splitlines() if l.split()[:1] == [str(plan.ranks)])
    assert f"{plan.grid[0]} x {plan.grid[1]}" in row and f"{plan.efficiency:.2f}" in row
    assert next(l for l in text.splitlines() if l.split()[:1] == ["15"]).split()[1:4] == \
        ["15", "x", "1"]


def test_collect_reads_a_finished_rank_count(tmp_path):
    # a real finished case: the demo's CG1 (tests/data/ranks/README.md); its log's last
    # block is the production run of the case's own step count
    demo = ROOT / "tests" / "data" / "ranks" / "demo_cg1_r0"
    case = tmp_path / "np1" / "cg1-none-r0"
    case.mkdir(parents=True)
    for name in ("scene.json", "log.liggghts"):
        shutil.copy2(demo / name, case / name)
    (tmp_path / "np2").mkdir()                    # a rank count without a finished case
    rows = bench.collect(tmp_path)
    assert [r.ranks for r in rows] == [1] and rows[0].grid == (1, 1, 1)
    assert rows[0].spread.atoms == 2255 and rows[0].modelled == 1.0
    text = bench.table(rows)
    assert "1.00" in text.splitlines()[1] and "against 1 rank(s)" in text
