"""docs/cli.md is the command-line reference generated from ligwf's own argument parser
(`ligwf schema --cli docs/cli.md`), as docs/workflow_reference.md is generated from the
models: the committed file is the generated text, every command and option of the parser is
in it, and the generator follows a parser it has never seen."""

from __future__ import annotations

import argparse
import subprocess
import sys

from helpers import ROOT
from ligwf.cli.main import build_parser, main
from ligwf.cli.reference import cli_markdown

CLI_FILE = ROOT / "docs" / "cli.md"
REGENERATE = "ligwf schema --cli docs/cli.md"


def _commands(parser: argparse.ArgumentParser, prog: str):
    """(prog, parser) of the parser and every sub-command below it, walked by argparse."""
    yield prog, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                yield from _commands(child, f"{prog} {name}")


def test_committed_cli_reference_is_the_generated_one(tmp_path):
    """In a fresh interpreter, as a user runs it: the parser's choices come from registries
    (``--liquid``) that a test may extend in this process (tests/liquids' toy model)."""
    out = tmp_path / "cli.md"
    done = subprocess.run([sys.executable, "-m", "ligwf.cli.main", "schema", "--cli", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert CLI_FILE.read_text() == out.read_text(), f"regenerate: {REGENERATE}"


def test_every_command_and_option_is_in_the_reference():
    text = cli_markdown(build_parser())
    commands = list(_commands(build_parser(), "ligwf"))
    assert len(commands) > 15
    for prog, parser in commands[1:]:
        assert f"## `{prog}`" in text, prog
        section = text.split(f"## `{prog}`\n", 1)[1].split("\n## ", 1)[0]
        for action in parser._actions:
            if isinstance(action, (argparse._HelpAction, argparse._SubParsersAction)):
                continue
            name = action.option_strings[-1] if action.option_strings else action.dest
            assert f"- `{name}" in section, f"{prog}: {name}"
            if action.help:
                shown = " ".join(action.help.split()).replace("%%", "%")
                assert shown[:40] in section, f"{prog}: {name} help"


def test_the_generator_follows_a_parser_it_has_never_seen(tmp_path):
    toy = argparse.ArgumentParser(prog="toy")
    sub = toy.add_subparsers(dest="command")
    p = sub.add_parser("go", help="go somewhere")
    p.add_argument("where", help="a place")
    p.add_argument("--speed", type=float, default=1.5, help="m/s, at most %(default)s twice")
    p.add_argument("--mode", choices=["walk", "run"], required=True, help="how")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--left", action="store_true", help="turn left")
    g.add_argument("--right", action="store_true", help="turn right")
    p.add_argument("--secret", help=argparse.SUPPRESS)
    text = cli_markdown(toy)
    assert "Commands: [`go`](#toy-go)." in text
    assert "## `toy go`\n\ngo somewhere\n" in text
    assert "toy go where [--speed SPEED] --mode {walk,run} [--left | --right]\n" in text
    assert "- `--speed SPEED`: m/s, at most 1.5 twice\n" in text
    assert "- `--mode {walk,run}`: how (required)\n" in text
    assert "secret" not in text
    p.add_argument("--new", default=3, help="a new option")
    assert "- `--new NEW`: a new option (default: 3)" in cli_markdown(toy)


def test_ligwf_schema_writes_the_reference(tmp_path):
    out = tmp_path / "cli.md"
    assert main(["schema", "--cli", str(out)]) == 0
    assert out.read_text() == cli_markdown(build_parser())
