"""Paths ligwf writes: checked as text, as case ids and against the study folder before
anything is written.

A path a user gives (``--out``) or a record holds (a case id in ``study.json``) ends up in
file system calls, in Slurm batch scripts and in engine inputs. Three rules hold for every
one of them, each refused in one line naming the path and why (:class:`ConfigError`):

* **one line of text**: no control character (a newline in ``--out`` would become a shell
  line of a batch script), at most :data:`MAX_PATH_CHARS` characters (``PATH_MAX``) and
  :data:`MAX_NAME_BYTES` bytes per name (``NAME_MAX``);
* **a case id is a folder name**: letters, digits and ``_ . + -``, not starting with a dot,
  so ``../victim`` or ``a/b`` in a study record never leaves the study folder;
* **inside the study folder**: every path ligwf is about to write resolves (symbolic links
  followed) to a place inside ``--out``, and the study record, the case folders and their
  output folders are not symbolic links (:func:`check_inside`), checked before the first
  write so a refusal leaves nothing behind.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Iterable

from ligwf.errors import ConfigError

#: longest path the kernel takes (Linux ``PATH_MAX``, the terminating NUL included)
MAX_PATH_CHARS = 4096
#: longest single name in a path (``NAME_MAX`` on ext4, xfs, btrfs, tmpfs: bytes)
MAX_NAME_BYTES = 255
#: characters that are no text: C0 controls (newline, tab, escape ...), DEL, C1 controls,
#: the Unicode line and paragraph separators
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029]")
#: a case folder's name: what :func:`ligwf.scene.workflow.expand` builds case ids from
CASE_ID = re.compile(r"^[A-Za-z0-9_+-][A-Za-z0-9_.+-]*$")
#: longest case id (the study path comes on top of it; matches the workflow's limit)
MAX_CASE_ID = 200


def control_character(text: str) -> str | None:
    """The first control character of ``text`` in words (``a line break (\\n) at character
    12``), None when it has none."""
    m = _CONTROL.search(text)
    if m is None:
        return None
    ch = m.group()
    names = {"\n": "a line break (\\n)", "\r": "a carriage return (\\r)", "\t": "a tab (\\t)",
             "\x00": "a NUL byte"}
    what = names.get(ch, f"the control character U+{ord(ch):04X}")
    return f"{what} at character {m.start() + 1}"


def path_text_problem(text: str) -> str | None:
    """Why ``text`` cannot be a path ligwf writes to or puts into a script (None: it can)."""
    if (ch := control_character(text)) is not None:
        return f"holds {ch}; a path is one line of text"
    if len(text) >= MAX_PATH_CHARS:
        return (f"{len(text):,} characters, allowed at most {MAX_PATH_CHARS - 1:,} (the "
                "system's PATH_MAX)")
    for name in text.split("/"):
        size = len(name.encode("utf-8", "surrogateescape"))
        if size > MAX_NAME_BYTES:
            return (f"holds a name of {size} bytes ({name[:24]}...), allowed at most "
                    f"{MAX_NAME_BYTES} (the file system's NAME_MAX)")
    return None


def shown(text: str, limit: int = 80) -> str:
    """``text`` as a message shows it: escaped (repr) and cut to ``limit`` characters."""
    r = repr(str(text))
    return r if len(r) <= limit else r[:limit - 4] + "...'"


def case_id_problem(case_id: object) -> str | None:
    """Why ``case_id`` cannot be a case folder's name (None: it can)."""
    if not isinstance(case_id, str) or not case_id:
        return "not a name"
    if "/" in case_id or "\\" in case_id:
        return "holds a path separator; a case id is one folder name"
    if case_id in (".", "..") or case_id.startswith("."):
        return "starts with a dot (a hidden or parent folder); a case id is a plain name"
    if len(case_id) > MAX_CASE_ID:
        return f"{len(case_id)} characters, allowed at most {MAX_CASE_ID}"
    if not CASE_ID.match(case_id):
        return "allowed characters are letters, digits and _ . + -"
    return None


def check_case_id(case_id: object, where: str) -> None:
    """ConfigError naming ``where`` (the record) and the case id unless it is a plain
    folder name (:func:`case_id_problem`)."""
    why = case_id_problem(case_id)
    if why is not None:
        raise ConfigError(f"{where}: case id {shown(str(case_id))}: {why}")


def resolved(path: Path) -> Path:
    """``path`` with every symbolic link followed (as far as it exists); ConfigError (one
    line) on a symbolic link loop or a path the system refuses."""
    try:
        return Path(path).resolve()
    except RuntimeError:                   # Python < 3.13 on a loop
        raise ConfigError(f"{path}: a symbolic link loop (a link that points back into "
                          "itself); name a real folder") from None
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be resolved ({exc.strerror or exc})") from None


def check_inside(root: Path, paths: Iterable[Path]) -> None:
    """ConfigError unless every one of ``paths`` (below ``root``) is no symbolic link and
    resolves inside ``root`` (itself resolved): a symlinked study record, case folder or
    output folder would write outside the study (or into another). Called before writing."""
    base = resolved(root)
    for path in paths:
        path = Path(path)
        if path.is_symlink():
            raise ConfigError(f"{path} is a symbolic link (to {os.readlink(path)}): ligwf "
                              f"writes a study's files only inside its folder {root}; remove "
                              "the link or name another --out")
        where = resolved(path)
        if where != base and base not in where.parents:
            raise ConfigError(f"{path} resolves to {where}, outside the study folder {base} "
                              "(a symbolic link on the way?): ligwf writes only inside it")
