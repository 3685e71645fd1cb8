"""Nodes per case, wall time against --time, and the Slurm plan table of ``slurm submit``
(``ligwf.slurm.walltime``; no scheduler, no engine)."""

from __future__ import annotations

import re

import pytest

from helpers import ROOT
from ligwf.cli.main import main
from ligwf.engine.plan import CaseLoad, fixed_ranks, plan_ranks
from ligwf.errors import ConfigError
from ligwf.slurm.walltime import (hours_minutes, nodes_for, over_time_warning, plan_rows,
                                slab_note, slurm_time_seconds)
from ligwf.scheduler import JobRound
from ligwf.slurm.jobs import plan_jobs
from ligwf.slurm.script import ScriptContext, array_script
from ligwf.slurm.site import SlurmSite, load_slurm_site
from ligwf.pipeline.prepare import prepare_workflow, prepared_loads

PAPER = ROOT / "workflows" / "paper_scale.yaml"
#: paper_scale.yaml reduced to its CG1 case (360,000 particles of 1 mm, 60 mm periodic axis)
CG1_ONLY = ["--set", "sweep.cg_levels=[1]", "--set", "sweep.rules=[weber]",
            "--set", "sweep.replicas=1", "--set", "sweep.per_cg={}"]


# --------------------------------------------------------------------- arithmetic

@pytest.mark.parametrize("ranks, per_node, nodes", [
    (1, 64, 1), (15, 64, 1), (64, 64, 1), (65, 64, 2), (128, 64, 2), (129, 64, 3),
    (15, 8, 2), (16, 8, 2), (17, 8, 3), (7, 1, 7), (3, None, None)])
def test_nodes_are_ranks_over_cores_per_node_rounded_up(ranks, per_node, nodes):
    assert nodes_for(ranks, per_node) == nodes


@pytest.mark.parametrize("ranks, per_node, needle", [
    (0, 64, r"ranks = 0: .*\[1, inf\)"), (4, 0, r"cores per node = 0: .*\[1, inf\)"),
    (4, -1, r"cores per node = -1"), (4, True, r"cores per node = True"),
    (4, 2.5, r"cores per node = 2.5")])
def test_nodes_refuse_what_is_not_a_whole_positive_number(ranks, per_node, needle):
    with pytest.raises(ConfigError, match=needle):
        nodes_for(ranks, per_node)


@pytest.mark.parametrize("text, seconds", [
    ("30", 1800), ("30:15", 1815), ("02:00:00", 7200), ("2-0", 172800),
    ("1-12", 129600), ("1-02:30", 95400), ("2-00:00:00", 172800), ("1-00:00:01", 86401),
    ("0", None), (None, None)])
def test_slurm_time_in_seconds(text, seconds):
    assert slurm_time_seconds(text) == seconds


def test_every_time_the_site_accepts_can_be_read():
    for text in ("30", "30:00", "01:00:00", "2-0", "2-12:00", "1-02:00:00"):
        SlurmSite(time=text)                # accepted by the site ...
        assert slurm_time_seconds(text) > 0  # ... and read here
    with pytest.raises(ConfigError, match="not a Slurm time"):
        slurm_time_seconds("soon")


@pytest.mark.parametrize("seconds, text", [(0, "0:00"), (1, "0:01"), (60, "0:01"),
                                           (61, "0:02"), (24480, "6:48"), (360000, "100:00")])
def test_hours_minutes_rounds_up(seconds, text):
    assert hours_minutes(seconds) == text


# --------------------------------------------------------------------- rows

def _load(name: str, particles: int = 360_000, d_max: float = 1e-3) -> CaseLoad:
    return CaseLoad(name, particles, 700_000, 0.06, d_max)


def test_replicas_with_one_load_share_a_row_other_cases_do_not():
    loads = [_load("cg1-none-r0"), _load("cg2-weber-r0", 45_000, 2e-3),
             _load("cg2-weber-r1", 45_000, 2e-3), _load("cg2-bond-r0", 45_000, 2e-3)]
    plans = [plan_ranks(l, None) for l in loads]
    rows = plan_rows(loads, plans, [(1, "none"), (2, "weber"), (2, "weber"), (2, "bond")], 8)
    assert [r.label for r in rows] == ["cg1-none-r0", "cg2-weber-r0 +1 more", "cg2-bond-r0"]
    assert [r.cases for r in rows][1] == ("cg2-weber-r0", "cg2-weber-r1")
    assert [(r.ranks, r.bound, r.nodes) for r in rows] == [(15, "slab", 2), (7, "slab", 1),
                                                           (7, "slab", 1)]
    assert rows[0].estimated_seconds == plans[0].estimated_seconds
    with pytest.raises(ConfigError, match="must be as many"):
        plan_rows(loads, plans[:2], [0] * 4, 8)


def test_slab_bound_rows_explain_the_limit_in_numbers():
    load = _load("cg1-none-r0")
    (row,) = plan_rows([load], [plan_ranks(load, None)], [0], None)
    assert row.slab_bound and row.nodes is None
    note = slab_note(row)
    assert "15 ranks is the axial slab limit, 60 mm / (4 x 1 mm largest diameter)" in note
    assert "particles alone would allow 120" in note
    small = _load("small", 5_000, 3e-3)
    (row,) = plan_rows([small], [plan_ranks(small, None)], [0], None)
    assert not row.slab_bound                 # 1 rank: particles limit it too


def test_over_time_compares_one_case_with_its_task_limit():
    load = _load("cg1-none-r0")
    (row,) = plan_rows([load], fixed_ranks([load], 15, "--ntasks"), [0], 64)
    assert row.exceeds(slurm_time_seconds("02:00:00"))
    assert not row.exceeds(slurm_time_seconds("7-00:00:00"))
    assert not row.exceeds(None)
    text = over_time_warning(row, "02:00:00")
    assert text.startswith(f"cg1-none-r0: estimated {hours_minutes(row.estimated_seconds)} "
                           "(h:mm) on 15 rank(s) exceeds --time 02:00:00")


# --------------------------------------------------------------------- scripts

def test_planned_arrays_ask_for_nodes_when_cores_per_node_are_known(tmp_path):
    site = SlurmSite(ligwf="/venv/bin/ligwf", cores_per_node=8)
    jobs = plan_jobs(tmp_path, "s", site, JobRound((0, 1, 2), ranks={0: 15, 1: 7, 2: 1}))
    assert [(j.site.ntasks, j.nodes) for j in jobs] == [(15, 2), (7, 1), (1, 1)]
    assert "#SBATCH --ntasks=15\n#SBATCH --nodes=2\n" in jobs[0].script_text
    # unknown cores per node: tasks only, as before
    plain = plan_jobs(tmp_path, "s", SlurmSite(ligwf="/venv/bin/ligwf"),
                      JobRound((0,), ranks={0: 15}))
    assert plain[0].nodes is None and "--nodes" not in plain[0].script_text
    # --ntasks / site ntasks: every case on that many ranks, no --nodes (as before)
    fixed = plan_jobs(tmp_path, "s", SlurmSite(ligwf="x", ntasks=32, cores_per_node=8),
                      JobRound((0, 1)))
    assert fixed[0].nodes is None and "--nodes" not in fixed[0].script_text


def test_array_script_refuses_more_nodes_than_tasks():
    ctx = ScriptContext(ROOT, "j", "0")
    with pytest.raises(ConfigError, match=r"nodes = 5: allowed range \[1, ntasks = 4\]"):
        array_script(ctx, SlurmSite(ntasks=4), [0], nodes=5)


@pytest.mark.parametrize("value, needle", [("0", "allowed range [1, inf)"),
                                           ("-3", "allowed range [1, inf)"),
                                           ("x", "expected a whole number (allowed range")])
def test_site_cores_per_node_is_checked(tmp_path, monkeypatch, value, needle):
    monkeypatch.setenv("LIGWF_SITE", str(tmp_path / "none.yaml"))
    assert load_slurm_site({"LIGWF_SLURM_CORES_PER_NODE": "64"}).cores_per_node == 64
    with pytest.raises(ConfigError, match=r"slurm cores_per_node = .*" + re.escape(needle)):
        load_slurm_site({"LIGWF_SLURM_CORES_PER_NODE": value})


# --------------------------------------------------------------------- the CLI

def _submit(tmp_path, monkeypatch, capsys, *extra, site_file=""):
    (tmp_path / "site.yaml").write_text(site_file)
    monkeypatch.setenv("LIGWF_SITE", str(tmp_path / "site.yaml"))
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    for name in ("NTASKS", "CORES_PER_NODE", "TIME"):
        monkeypatch.delenv("LIGWF_SLURM_" + name, raising=False)
    out = tmp_path / "study"
    code = main(["slurm", "submit", str(PAPER), "--out", str(out), *CG1_ONLY, *extra])
    assert not out.exists() and not (tmp_path / "meshes").exists()
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _plan_row(text: str) -> list[str]:
    """The plan table's row of the CG1 case (the case table comes first)."""
    rows = [[c.strip() for c in line.split("│")[1:-1]] for line in text.splitlines()
            if line.startswith("│ cg1-none-r0")]
    assert len(rows) == 2, text
    return rows[1]


def test_dry_run_of_paper_scale_cg1_shows_ranks_nodes_and_estimate(tmp_path, monkeypatch,
                                                                   capsys):
    # issue #24: past the 15 axial slabs, a 2-D grid on >= 64 ranks over >= 2 nodes, with the
    # estimate and what it rests on
    code, out, err = _submit(tmp_path, monkeypatch, capsys, "--dry-run",
                             "--cores-per-node", "64", "--time", "00:10:00")
    assert code == 0, err
    (load,) = prepared_loads(prepare_workflow(PAPER, [a for a in CG1_ONLY if a != "--set"],
                                              [], False))
    plan = plan_ranks(load, None)
    estimate = hours_minutes(plan.estimated_seconds)
    nodes = -(-plan.ranks // 64)
    assert plan.ranks >= 64 and nodes >= 2 and plan.grid[1] > 1
    row = _plan_row(out)
    assert row == ["cg1-none-r0", "2.54e+11", str(plan.ranks), "grid", str(nodes), estimate,
                   "00:10:00 (too short)", "360,000", f"{load.steps:,}"]
    assert re.fullmatch(r"\d+:\d\d", estimate)
    assert f"array-1.sh: 1 case(s), --ntasks={plan.ranks}, --nodes={nodes}" in out
    assert "nodes = ceil(ranks / 64 cores per node), asked for with --nodes" in out
    text = " ".join(out.split())            # the notes wrap at the console width
    axial, across = plan.grid
    assert (f"cg1-none-r0: {plan.ranks} ranks = {axial} slab(s) along the axis") in text
    assert f"x {across} columns across" in text
    assert f"efficiency {plan.efficiency:.2f}" in text and "no load balancing" in text
    assert "fit to 0.88 measured on 2 axial ranks" in text
    assert "scaling_model.md" in text and "bench_scaling_slurm.py" in text
    assert f"#SBATCH --ntasks={plan.ranks}\n#SBATCH --nodes={nodes}\n" in out
    assert (f"ligwf: warning: cg1-none-r0: estimated {estimate} (h:mm) on {plan.ranks} rank(s) "
            "exceeds --time 00:10:00") in err
    assert "Traceback" not in err


def test_dry_run_without_cores_per_node_says_nodes_are_unknown(tmp_path, monkeypatch, capsys):
    code, out, err = _submit(tmp_path, monkeypatch, capsys, "--dry-run")
    assert code == 0, err
    assert _plan_row(out)[4] == "?" and _plan_row(out)[6] == "-"
    assert "nodes ?: cores per node unknown" in out
    assert "no --time (nor site time)" in out
    assert "--nodes" not in "".join(l for l in out.splitlines(True) if l.startswith("#SBATCH"))
    assert "exceeds --time" not in err


def test_site_cores_per_node_and_time_are_used(tmp_path, monkeypatch, capsys):
    code, out, err = _submit(tmp_path, monkeypatch, capsys, "--dry-run", site_file=(
        "slurm:\n  cores_per_node: 8\n  time: 7-00:00:00\n"))
    assert code == 0, err
    ranks = int(_plan_row(out)[2])
    assert _plan_row(out)[4] == str(-(-ranks // 8)) and _plan_row(out)[6] == "7-00:00:00"
    assert f"#SBATCH --ntasks={ranks}\n#SBATCH --nodes={-(-ranks // 8)}\n" in out
    assert "exceeds --time" not in err


def test_ntasks_keeps_its_script_and_the_table_still_counts_nodes(tmp_path, monkeypatch,
                                                                  capsys):
    code, out, err = _submit(tmp_path, monkeypatch, capsys, "--dry-run", "--ntasks", "32",
                             "--cores-per-node", "16")
    assert code == 0, err
    assert _plan_row(out)[2:5] == ["32", "--ntasks", "2"]
    assert "#SBATCH --ntasks=32\n#SBATCH --output=" in out
    assert "not asked for: on --ntasks / site ntasks" in out


@pytest.mark.parametrize("value", ["0", "-1", "x", "2.5"])
@pytest.mark.parametrize("dry_run", [True, False])
def test_bad_cores_per_node_is_refused_before_anything_is_written(tmp_path, monkeypatch,
                                                                  capsys, value, dry_run):
    extra = ["--cores-per-node", value] + (["--dry-run"] if dry_run else [])
    code, out, err = _submit(tmp_path, monkeypatch, capsys, *extra)
    assert code == 2 and out == ""
    assert ("argument --cores-per-node: must be a whole number of cores, allowed range "
            f"[1, inf), got '{value}'") in " ".join(err.split())
    assert "Traceback" not in err
