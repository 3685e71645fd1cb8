"""``ligwf schema``: the workflow's JSON Schema, its reference and the data dictionary.

Without options it prints the JSON Schema of a workflow file (for a YAML editor:
``# yaml-language-server: $schema=docs/workflow.schema.json``); ``--out`` writes it,
``--reference`` writes the markdown workflow reference, ``--dictionary`` the data
dictionary of every table ligwf writes and ``--cli`` the command-line reference. The text
comes from :mod:`ligwf.scene.reference`, :mod:`ligwf.report.dictionary` and
:mod:`ligwf.cli.reference` (on the parser ``ligwf`` runs with); the committed copies in
``docs/`` are regenerated with::

    ligwf schema --out docs/workflow.schema.json --reference docs/workflow_reference.md \\
        --dictionary docs/data_dictionary.md --cli docs/cli.md
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from ligwf.cli.common import console
from ligwf.cli.reference import cli_markdown
from ligwf.errors import ConfigError
from ligwf.fsio import atomic_write_text, replaceable
from ligwf.report.dictionary import dictionary_markdown
from ligwf.scene.reference import reference_markdown, schema_text


def file_to_write(text: str) -> Path:
    """argparse type: a file ligwf may (re)write: not a folder, in an existing writable
    folder, not a symbolic link, FIFO or device node (refused before anything is written)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is an empty path; name the file")
    path = Path(text)
    why = replaceable(path)
    if why is not None:
        raise argparse.ArgumentTypeError(f"{text} is {why}: ligwf writes only regular files "
                                         "and does not replace it")
    parent = path.parent
    if not parent.is_dir():
        raise argparse.ArgumentTypeError(f"{text}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"{text}: folder {parent} is not writable")
    return path


def cmd_schema(args: argparse.Namespace) -> int:
    outputs = [("--out", args.out, schema_text), ("--reference", args.reference,
                                                  reference_markdown),
               ("--dictionary", args.dictionary, dictionary_markdown),
               ("--cli", args.cli, lambda: cli_markdown(args.root_parser))]
    texts = [(option, path, make()) for option, path, make in outputs if path is not None]
    if not texts:
        print(schema_text(), end="")
        return 0
    for option, path, text in texts:     # every text built before the first file is written
        try:
            atomic_write_text(path, text)
        except OSError as exc:       # e.g. /proc/x.json: a folder that holds no new files
            raise ConfigError(f"{option} {path}: cannot write a file there "
                              f"({exc.strerror or exc})") from None
        console.print(f"wrote {path}", highlight=False)
    return 0


def register(subparsers) -> None:
    """Add ``schema``."""
    p = subparsers.add_parser(
        "schema", help="print the workflow's JSON Schema (for YAML editors); write it, the "
        "workflow reference, the data dictionary of every table and the command-line reference")
    p.add_argument("--out", type=file_to_write, default=None, metavar="FILE",
                   help="write the JSON Schema here (e.g. docs/workflow.schema.json)")
    p.add_argument("--reference", type=file_to_write, default=None, metavar="FILE",
                   help="write the markdown workflow reference here (docs/workflow_reference.md)")
    p.add_argument("--dictionary", type=file_to_write, default=None, metavar="FILE",
                   help="write the data dictionary of every table here (docs/data_dictionary.md)")
    p.add_argument("--cli", type=file_to_write, default=None, metavar="FILE",
                   help="write the command-line reference of every command here (docs/cli.md)")
    p.set_defaults(func=cmd_schema)
