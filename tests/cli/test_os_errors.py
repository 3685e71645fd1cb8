"""A user-reachable OSError prints one line in words (no ``[Errno N]``), naming the file."""

from __future__ import annotations

import errno

from ligwf.cli.main import os_error_text
from ligwf.fsio import FolderNotWritable


def test_os_error_in_words():
    exc = FileNotFoundError(errno.ENOENT, "No such file or directory", "/x/y.yaml")
    assert os_error_text(exc) == "No such file or directory: /x/y.yaml"
    two = OSError(errno.EXDEV, "Invalid cross-device link", "/a", None, "/b")
    assert os_error_text(two) == "Invalid cross-device link: /a -> /b"
    assert "[Errno" not in os_error_text(OSError(errno.EIO, "Input/output error"))
    assert os_error_text(OSError("bare")) == "bare"
    assert os_error_text(FolderNotWritable("cannot write in /r: Read-only file system")) == (
        "cannot write in /r: Read-only file system")


def test_a_missing_workflow_file_is_one_line_without_errno(tmp_path, capsys):
    from ligwf.cli.main import main
    code = main(["check", str(tmp_path / "nowhere.yaml")])
    err = capsys.readouterr().err
    assert code == 2 and "[Errno" not in err and len(err.strip().splitlines()) == 1


def test_a_full_disk_during_analysis_names_the_study_folder(tmp_path, monkeypatch, capsys):
    """Issue 46 item 6: ``ligwf analyse`` on a study whose file system fills up names the
    study's folder, not the current one (a write error carries no file name: the stage
    that writes says where). A real tmpfs holds the study; the current folder is elsewhere."""
    import os
    import shutil
    import subprocess

    from helpers import ROOT
    from ligwf.cli.main import main

    disk = tmp_path / "disk"
    disk.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(disk)], check=True)
    try:
        study = disk / "study"
        shutil.copytree(ROOT / "tests" / "data" / "cg3_slice", study)
        fd = os.open(disk / "ballast", os.O_WRONLY | os.O_CREAT)   # fill it to the last block
        try:
            while True:
                os.write(fd, b"\0" * 4096)
        except OSError:
            pass
        finally:
            os.close(fd)
        monkeypatch.chdir(tmp_path)
        capsys.readouterr()
        assert main(["analyse", str(study), "--no-vtu"]) == 2
        err = capsys.readouterr().err
        (line,) = err.strip().splitlines()
        assert "ligwf: FolderNotWritable: cannot write in " + str(study) in line, line
        assert "No space left on device" in line and "Traceback" not in err
        assert not list((study / "analysis").glob(".staging-*")) if (
            study / "analysis").is_dir() else True
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=False)
