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
