"""A study's folder is its own (issue 46 item 2).

``render``, ``run``, ``study --until-decided`` and ``slurm submit`` into a folder holding
another study (another name, other scene values, other seeds) are refused in one line
naming both studies and what differs, before anything is written; ``--replace`` writes it
and keeps what it does not change. Every path written is checked inside ``--out`` first:
a symbolic link for the study record, a case folder or ``post/`` is refused in one line
and nothing is written, here or at the link's target.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from helpers import ROOT
from ligwf.cli.main import main
from ligwf.study import layout

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"
OTHER = ("--set", "name=other", "--set", "scene.liquid.surface_tension=0.05")


def _tree(folder: Path) -> dict[str, tuple[int, bytes | None]]:
    """Every path below ``folder`` with its modification time and content (files)."""
    return {str(p.relative_to(folder)): (p.lstat().st_mtime_ns,
                                         p.read_bytes() if p.is_file() and not p.is_symlink()
                                         else None)
            for p in sorted(folder.rglob("*"))}


def _error(err: str) -> str:
    """The one error line of stderr (the workflow's warnings come before it)."""
    (line,) = [ln for ln in err.strip().splitlines() if not ln.startswith("ligwf: warning:")]
    assert line.startswith("ligwf: ConfigError: "), line
    return line


@pytest.fixture
def study(tmp_path, monkeypatch):
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    out = tmp_path / "study"
    assert main(["render", str(TINY), "--out", str(out)]) == 0
    return out


@pytest.mark.parametrize("argv,differs", [
    (["render", str(TINY), *OTHER], ("name 'runner-tiny' -> 'other'",
                                     "scene.liquid.surface_tension 0.024 -> 0.05")),
    (["run", str(TINY), "--set", "scene.numerics.seed=20011"],
     ("scene.numerics.seed = 20011 added",)),
    (["study", str(TINY), "--until-decided", *OTHER], ("name 'runner-tiny' -> 'other'",)),
    (["slurm", "submit", str(TINY), "--dry-run", "--set", "sweep.rules=[weber]"],
     ("sweep.rules[1] removed",)),
    (["render", str(TINY), "--set", "scene.process.rotation.rpm=20"],
     ("scene.process.rotation.rpm 30 -> 20",)),
])
def test_another_study_is_refused_in_one_line_before_anything_is_written(study, capsys,
                                                                         argv, differs):
    before = _tree(study)
    capsys.readouterr()
    assert main([*argv, "--out", str(study)]) == 2
    line = _error(capsys.readouterr().err)
    assert "holds another study: 'runner-tiny' (2 case(s))" in line, line
    assert "--replace" in line
    for text in differs:
        assert text in line, line
    assert _tree(study) == before, "something was written"


def test_the_same_study_and_its_analysis_settings_are_its_own(study):
    assert main(["render", str(TINY), "--out", str(study)]) == 0
    assert main(["render", str(TINY), "--out", str(study), "--set",
                 "analysis.bootstrap=30"]) == 0
    assert json.loads((study / layout.STUDY_FILE).read_text())["analysis"]["bootstrap"] == 30


def test_replace_writes_the_other_study_and_keeps_the_cases_it_does_not_change(study):
    """Another sweep (one rule instead of two): the weber case is the
    same scene, so its record stays byte for byte (same scene hash: its run is skipped
    as done) and its outputs stay; the study record is the new one."""
    case = study / "cg3-weber-r0"
    kept = case / layout.POST_DIR / "particles_100.vtu"
    kept.write_text("a frame of the finished run")
    scene = (case / layout.SCENE_FILE).read_bytes()
    assert main(["render", str(TINY), "--out", str(study), "--replace", "--set",
                 "sweep.rules=[weber]"]) == 0
    record = json.loads((study / layout.STUDY_FILE).read_text())
    assert [c["case_id"] for c in record["cases"]] == ["cg3-weber-r0"]
    assert record["workflow"]["sweep"]["rules"] == ["weber"]
    assert (case / layout.SCENE_FILE).read_bytes() == scene
    assert kept.read_text() == "a frame of the finished run"


def test_a_symlinked_study_record_is_refused_before_any_case_is_written(tmp_path, capsys,
                                                                          monkeypatch):
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    out, elsewhere = tmp_path / "study", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / layout.STUDY_FILE).symlink_to(elsewhere / "study.json")
    assert main(["render", str(TINY), "--out", str(out)]) == 2
    line = _error(capsys.readouterr().err)
    assert f"{out / layout.STUDY_FILE} is a symbolic link" in line, line
    assert sorted(p.name for p in out.iterdir()) == [layout.STUDY_FILE]
    assert list(elsewhere.iterdir()) == []


@pytest.mark.parametrize("link", ["cg3-bond-r0", f"cg3-bond-r0/{layout.POST_DIR}"])
def test_a_symlinked_case_or_output_folder_is_refused_by_render_and_run_case(
        study, tmp_path, capsys, link):
    target = tmp_path / "elsewhere"
    (study / link).rename(target)
    (study / link).symlink_to(target)
    outside = _tree(target)
    before = _tree(study)
    for argv in (["render", str(TINY), "--out", str(study)],
                 ["run", str(TINY), "--out", str(study)],
                 ["run-case", str(study), "--index", "1"]):
        capsys.readouterr()
        assert main(argv) == 2, argv
        line = _error(capsys.readouterr().err)
        assert f"{study / link} is a symbolic link" in line, line
        assert "Traceback" not in line and "rmtree" not in line
    assert _tree(study) == before and _tree(target) == outside


def test_a_case_folder_leading_outside_through_a_parent_link_is_refused(study, tmp_path,
                                                                        capsys):
    """A case folder that is no link itself but lies below one (``post`` -> a folder
    outside, via a relative link in the way) still resolves outside: refused."""
    case = study / "cg3-weber-r0"
    target = tmp_path / "outside"
    target.mkdir()
    os.rename(case / layout.RESTART_DIR, target / layout.RESTART_DIR)
    (case / layout.RESTART_DIR).symlink_to(target / layout.RESTART_DIR)
    assert main(["render", str(TINY), "--out", str(study)]) == 2
    assert "is a symbolic link" in capsys.readouterr().err


@pytest.mark.parametrize("folder,argv", [
    (layout.ANALYSIS_DIR, ["analyse"]), (layout.REPORT_DIR, ["report", "--no-snapshots"])])
def test_a_symlinked_output_folder_of_the_study_is_refused(study, tmp_path, capsys, folder,
                                                           argv):
    target = tmp_path / "outside"
    target.mkdir()
    (study / folder).symlink_to(target)
    capsys.readouterr()
    assert main([argv[0], str(study), *argv[1:]]) == 2
    line = _error(capsys.readouterr().err)
    assert f"{study / folder} is a symbolic link" in line, line
    assert list(target.iterdir()) == []
