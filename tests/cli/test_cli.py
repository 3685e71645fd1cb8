"""CLI: render writes case folders, check writes nothing, bad input writes nothing."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from ligwf.cli.main import main

from helpers import DRUM


def test_render_writes_one_folder_per_case(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "study"
    assert main(["render", str(DRUM), "--out", str(out), "--set", "sweep.cg_levels=[1,2]"]) == 0
    table = capsys.readouterr().out
    for col in ("CG", "rule", "particles", "dt", "steps"):
        assert col in table
    study = json.loads((out / "study.json").read_text())
    ids = [c["case_id"] for c in study["cases"]]
    assert ids == ["cg1-none-r0", "cg2-weber-r0", "cg2-bond-r0"]
    for cid in ids:
        case = out / cid
        assert (case / "in.liggghts").is_file() and (case / "drum.stl").is_file()
        assert (case / "post").is_dir() and (case / "restart").is_dir()
        rec = json.loads((case / "scene.json").read_text())
        assert rec["case_id"] == cid and len(rec["scene_hash"]) == 64
        assert rec["scaled"]["particle_count"] > 0
    assert len(list((tmp_path / "cache").glob("drum_*.stl"))) == 1
    # rendering is deterministic: same hash again
    out2 = tmp_path / "again"
    main(["render", str(DRUM), "--out", str(out2), "--set", "sweep.cg_levels=[1,2]"])
    h1 = json.loads((out / "study.json").read_text())["cases"]
    h2 = json.loads((out2 / "study.json").read_text())["cases"]
    assert [c["scene_hash"] for c in h1] == [c["scene_hash"] for c in h2]


def test_check_writes_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["check", str(DRUM)]) == 0
    assert "5 case(s), valid" in capsys.readouterr().out
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("override,field", [
    ("scene.process.fill_fraction=0.9", "scene.process.fill_fraction"),
    ("scene.drum.lifters.height=0.03", "lifters.height"),
    ("sweep.rules=[weber,bnd]", "bnd"),
    ("scene.name=a$b", "scene.name"),
])
def test_bad_input_is_refused_before_anything_is_written(tmp_path, capsys, override, field):
    out = tmp_path / "study"
    assert main(["render", str(DRUM), "--out", str(out), "--set", override]) == 2
    err = capsys.readouterr().err
    assert "ConfigError" in err and field in err
    assert not out.exists()


def test_check_names_the_granule_definition_and_the_verdict_budget(tmp_path, monkeypatch,
                                                                  capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["check", str(DRUM), "--set", "analysis.granules=held",
                 "--set", "analysis.hold_time=0.3", "--set", "accept.angle_deg=2",
                 "--set", "accept.gsd_error=null"]) == 0
    out = capsys.readouterr().out
    assert "analysis: granules (held, bridges through 0.3 s), GSD and kinetics for every " \
        "case" in out
    budget = next(ln for ln in out.splitlines() if ln.startswith("verdict budget"))
    assert "angle of repose +-2 deg" in budget and "noise floor" not in budget
    assert "not in the budget" in budget and "<= 0.1" in budget


def test_console_entry_point():
    out = subprocess.run([sys.executable, "-m", "ligwf.cli.main", "--help"], capture_output=True, text=True)
    assert out.returncode == 0
    assert "render" in out.stdout and "check" in out.stdout


def test_check_prints_the_rank_plan(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("SLURM_JOB_ID", raising=False)
    assert main(["check", str(DRUM), "--cores", "2", "--set", "sweep.cg_levels=[3,1]",
                 "--set", "scene.drum.length=0.018"]) == 0
    out = capsys.readouterr().out
    assert "rank plan for 2 core(s) (--cores)" in out
    # the plan table lists each case again after the case table: ranks, what limited them
    plan_rows = [[c.strip() for c in line.split("│")[1:-1]] for line in out.splitlines()
                 if line.startswith("│ cg")][3:6]   # then the regime table
    assert [(r[0], r[2], r[3]) for r in plan_rows] == [
        ("cg3-weber-r0", "1", "slab, particles"), ("cg3-bond-r0", "1", "slab, particles"),
        ("cg1-none-r0", "2", "cores")]
    assert "phase 1: 1 case(s) one after the other on 2 rank(s) (mpirun -np 2)" in out
    assert ("phase 2: 2 case(s) side by side, 2 at a time on 1 rank(s) each (one mpirun -np 2 "
            "ensemble), longest first") in out
    assert list(tmp_path.iterdir()) == []


def test_check_plans_for_the_cores_of_a_slurm_allocation(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SLURM_JOB_ID", "42")
    monkeypatch.setenv("SLURM_NTASKS", "1")
    assert main(["check", str(DRUM)]) == 0
    out = capsys.readouterr().out
    assert "rank plan for 1 core(s) (SLURM_NTASKS)" in out
    assert "phase 1: 5 case(s) one after the other on 1 rank(s)" in out


@pytest.mark.parametrize("argv, planned, nprocs, ensemble", [
    ([], True, None, 0),
    (["--np", "2"], False, 2, 0),
    (["--ensemble", "2"], False, 1, 0 + 2),
    (["--np", "2", "--ensemble", "4"], False, 2, 4),
])
def test_run_plans_unless_np_or_ensemble_is_given(tmp_path, argv, planned, nprocs, ensemble):
    from ligwf.cli.main import build_parser
    from ligwf.local import run_settings

    for command in ("run", "study"):
        args = build_parser().parse_args([command, str(DRUM), "--out", str(tmp_path / "s"),
                                          *argv, "--cores", "2"])
        settings = run_settings(args.np, args.ensemble, args.cores, args.retry_unstable,
                                args.templates)
        assert (settings.planned, settings.nprocs, settings.ensemble, settings.cores) == (
            planned, nprocs, ensemble, 2)


def test_cores_must_be_a_positive_whole_number(capsys):
    assert main(["check", str(DRUM), "--cores", "0"]) == 2
    assert "--cores" in capsys.readouterr().err


def test_run_names_the_cases_another_live_runner_holds(tmp_path, monkeypatch):
    """A second ``ligwf run`` on a study leaves a case another live ligwf process is
    running to it and says so (not just "nothing to run")."""
    import socket

    from ligwf.cli.run import elsewhere
    from ligwf.study.manifest import Manifest
    from ligwf.study.processes import start_time
    from ligwf.study.study import Study

    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "study"
    assert main(["render", str(DRUM), "--out", str(out), "--set", "sweep.cg_levels=[3]",
                 "--set", "sweep.rules=[weber]"]) == 0
    case = Study.open(out).cases[0]
    other = subprocess.Popen(["sleep", "60"])            # stands for the other runner
    try:
        m = Manifest(case_id=case.case_id, index=case.index, scene_hash=case.scene_hash,
                     ligwf_version="", liggghts_version="", status="running",
                     host=socket.gethostname(), pid=other.pid, pid_start=start_time(other.pid))
        case.write_manifest(m)
        assert elsewhere(Study.open(out).cases, False) == [
            f"{case.case_id}: running in process {other.pid} on {socket.gethostname()}: "
            "left to that runner"]
    finally:
        other.kill()
        other.wait()
    assert elsewhere(Study.open(out).cases, False) == []     # its runner is gone: resumable
