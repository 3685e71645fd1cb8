"""The command-line reference (``docs/cli.md``), generated from the argument parser itself.

Every command and sub-command the parser knows, with its usage line, its description and
each option's flags, value name, choices, default and help text, so the reference cannot
drift from what ``ligwf --help`` says (``tests/cli/test_cli_reference.py`` compares the
committed file with this text; ``ligwf schema --cli docs/cli.md`` rewrites it). Pure: a
parser in, markdown out; the usage lines are built here, not by argparse's formatter, whose
line breaks follow the terminal width.
"""

from __future__ import annotations

import argparse
import inspect

HEADER = ("# Command-line reference\n\n"
          "Generated from ligwf's argument parser: `ligwf schema --cli docs/cli.md` rewrites "
          "this file and `tests/cli/test_cli_reference.py` fails when it differs from the "
          "parser. What the commands are for and a first study: the [README](../README.md).\n")


def _sub_action(parser: argparse.ArgumentParser) -> argparse._SubParsersAction | None:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action
    return None


def _shown(action: argparse.Action) -> bool:
    return action.help is not argparse.SUPPRESS and not isinstance(
        action, (argparse._HelpAction, argparse._SubParsersAction))


def _value_name(action: argparse.Action) -> str:
    if action.choices is not None and not isinstance(action.choices, dict):
        return "{" + ",".join(str(c) for c in action.choices) + "}"
    if action.metavar is not None:
        return action.metavar if isinstance(action.metavar, str) else " ".join(action.metavar)
    return action.dest if not action.option_strings else action.dest.upper()


def _takes_value(action: argparse.Action) -> bool:
    return action.nargs != 0


def _synopsis(action: argparse.Action) -> str:
    """``--np K``, ``workflow``, ``--set KEY=VALUE`` (repeatable ones are said in help)."""
    name = _value_name(action)
    if not action.option_strings:
        return name + (" ..." if action.nargs in ("*", "+") else "")
    flags = ", ".join(action.option_strings)
    if not _takes_value(action):
        return flags
    if action.nargs == "?":
        return f"{flags} [{name}]"
    if action.nargs in ("*", "+"):
        return f"{flags} {name} ..."
    return f"{flags} {name}"


def _usage(prog: str, parser: argparse.ArgumentParser) -> str:
    parts = [prog]
    groups = {id(a): g for g in parser._mutually_exclusive_groups for a in g._group_actions}
    done: set[int] = set()
    for action in parser._actions:
        if not _shown(action) or id(action) in done:
            continue
        group = groups.get(id(action))
        members = [a for a in group._group_actions if _shown(a)] if group else [action]
        done.update(id(a) for a in members)
        text = " | ".join(_synopsis(a).split(", ")[-1] if a.option_strings
                          and not _takes_value(a) else _short(a) for a in members)
        required = group.required if group else (action.required or not action.option_strings)
        parts.append(text if required and len(members) == 1 else
                     f"({text})" if required else f"[{text}]")
    sub = _sub_action(parser)
    if sub is not None:
        parts.append("{" + ",".join(sub.choices) + "} ...")
    return " ".join(parts)


def _short(action: argparse.Action) -> str:
    """One flag (the long one) and the value name: the usage line's form."""
    if not action.option_strings:
        return _synopsis(action)
    flag = action.option_strings[-1]
    return flag if not _takes_value(action) else f"{flag} {_value_name(action)}"


def _help(action: argparse.Action, prog: str) -> str:
    text = " ".join((action.help or "").split())
    raw = text
    if "%" in text:                      # argparse's %(default)s and friends
        params = {k: v for k, v in vars(action).items() if v is not argparse.SUPPRESS}
        params["prog"] = prog
        text = text % params
    default = action.default
    if (action.option_strings and _takes_value(action) and default not in (None, [], ())
            and default is not argparse.SUPPRESS and "default" not in raw):
        text += f" (default: {default})"
    if action.required and action.option_strings:
        text += " (required)"
    return text


def _description(parser: argparse.ArgumentParser, help_text: str | None) -> str:
    text = parser.description or help_text or ""
    return inspect.cleandoc(text) if text else ""


def _options(parser: argparse.ArgumentParser, prog: str) -> str:
    """One bullet per argument: its synopsis, then its help text."""
    return "\n".join(f"- `{_synopsis(a)}`: {_help(a, prog)}".rstrip(": ")
                     for a in parser._actions if _shown(a))


def _command(prog: str, parser: argparse.ArgumentParser, help_text: str | None,
             out: list[str]) -> None:
    """Markdown blocks of one command (heading, what it does, usage, options), then those
    of its sub-commands."""
    out.append(f"## `{prog}`")
    if help_text and parser.description and help_text not in parser.description:
        out.append(" ".join(help_text.split()) + ".")
    description = _description(parser, help_text)
    if description:
        out.append(description)
    out.append(f"```\n{_usage(prog, parser)}\n```")
    options = _options(parser, prog)
    if options:
        out.append(options)
    sub = _sub_action(parser)
    if sub is not None:
        helps = {a.dest: a.help for a in sub._choices_actions}
        for name, child in sub.choices.items():
            _command(f"{prog} {name}", child, helps.get(name), out)


def cli_markdown(parser: argparse.ArgumentParser) -> str:
    """The markdown reference of ``parser`` and all its sub-commands, in registration order."""
    out = [HEADER.rstrip("\n")]
    sub = _sub_action(parser)
    if sub is None:
        _command(parser.prog, parser, None, out)
        return "\n\n".join(out) + "\n"
    out.append("Commands: " + ", ".join(f"[`{name}`](#{_anchor(parser.prog, name)})"
                                        for name in sub.choices) + ".")
    out.append(f"```\n{_usage(parser.prog, parser)}\n```")
    options = _options(parser, parser.prog)
    if options:
        out.append(options)
    helps = {a.dest: a.help for a in sub._choices_actions}
    for name, child in sub.choices.items():
        _command(f"{parser.prog} {name}", child, helps.get(name), out)
    return "\n\n".join(out) + "\n"


def _anchor(prog: str, name: str) -> str:
    """GitHub's anchor of the heading ``prog name`` in backticks."""
    return f"{prog} {name}".lower().replace(" ", "-")
