"""Files with the user's permissions, and ``--out`` that never replaces what is not a
regular file (issue 32): atomic writes give ``0666`` less the umask (mkstemp's ``0600``
made every study, scene and report file unreadable to anyone else)."""

from __future__ import annotations

import os
import stat
from contextlib import contextmanager
from pathlib import Path

import pytest

from apistudy import api_study
from helpers import ROOT
from ligwf.cli.main import main
from ligwf.fsio import NotReplaceable, atomic_write_text, replaceable

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


@contextmanager
def umask(mask: int):
    old = os.umask(mask)
    try:
        yield
    finally:
        os.umask(old)


def modes(folder: Path) -> dict[str, int]:
    """Permission bits of every regular file below ``folder``."""
    return {str(p.relative_to(folder)): stat.S_IMODE(p.stat().st_mode)
            for p in folder.rglob("*") if p.is_file() and not p.is_symlink()}


@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o027, 0o640), (0o002, 0o664)])
def test_an_atomic_write_takes_the_umask(tmp_path, mask, mode):
    with umask(mask):
        atomic_write_text(tmp_path / "a.json", "{}")
        atomic_write_text(tmp_path / "a.json", "{}\n")      # replaced: same rule
    assert stat.S_IMODE((tmp_path / "a.json").stat().st_mode) == mode


def test_every_file_of_a_render_is_readable_as_the_umask_allows(tmp_path):
    out, cache = tmp_path / "study", tmp_path / "cache"
    with umask(0o027):
        assert main(["render", str(TINY), "--out", str(out), "--mesh-cache", str(cache)]) == 0
    found = modes(out) | {f"cache/{k}": v for k, v in modes(cache).items()}
    assert {"study.json", "cg3-bond-r0/scene.json", "cg3-bond-r0/in.liggghts",
            "cg3-bond-r0/drum.stl"} <= set(found)
    assert {k: v for k, v in found.items() if v != 0o640} == {}


@pytest.mark.engine
@pytest.mark.mpi
def test_every_file_of_a_reported_study_is_readable_by_others(engine, tmp_path_factory):
    """The run manifests, thermo tables, analysis tables and every report file of a real
    ``ligwf study`` (made under the session's umask): none more private than the umask."""
    study = api_study(engine, tmp_path_factory)
    mask = os.umask(0)
    os.umask(mask)
    found = modes(study)
    kinds = {"manifest.json", "thermo.csv", "analysis.json", "index.html", "conditions.csv"}
    assert kinds <= {Path(k).name for k in found}, kinds - {Path(k).name for k in found}
    private = {k: oct(v) for k, v in found.items() if v & 0o444 != 0o444 & ~mask}
    assert private == {}


def test_what_is_not_a_regular_file_is_never_replaced(tmp_path):
    fifo, link, folder = tmp_path / "fifo", tmp_path / "link", tmp_path / "dir"
    os.mkfifo(fifo)
    (tmp_path / "target").write_text("kept")
    link.symlink_to(tmp_path / "target")
    folder.mkdir()
    for path, what in ((fifo, "a FIFO"), (link, "a symbolic link"), (folder, "a folder")):
        with pytest.raises(NotReplaceable, match=what):
            atomic_write_text(path, "x")
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and link.is_symlink()
    assert (tmp_path / "target").read_text() == "kept"
    assert replaceable(Path("/dev/null")) == "a device node"


def test_an_error_names_the_file_not_its_temporary_copy(tmp_path):
    with pytest.raises(OSError) as info:
        atomic_write_text(Path("/proc/ligwf-test.json"), "x")
    assert info.value.filename == "/proc/ligwf-test.json"


@pytest.mark.parametrize("target", ["fifo", "link", "", "dir"])
def test_schema_out_refuses_what_it_must_not_replace(tmp_path, capsys, target):
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "link").symlink_to(tmp_path / "missing")
    (tmp_path / "dir").mkdir()
    path = target if target == "" else str(tmp_path / target)
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main(["schema", "--out", path]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ligwf: usage error") and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    assert stat.S_ISFIFO(os.lstat(tmp_path / "fifo").st_mode)
    assert (tmp_path / "link").is_symlink()


def test_schema_out_where_no_file_can_be_made_is_one_line_naming_the_option(tmp_path, capsys):
    """/proc takes no new file: one line naming --out and the path, not a bare
    FileNotFoundError (issue 32 item 5)."""
    assert main(["schema", "--out", "/proc/ligwf-x.json"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ligwf: ConfigError: --out /proc/ligwf-x.json: cannot write a file "
                          "there (No such file or directory)"), err
    assert len(err.strip().splitlines()) == 1
