"""Reading YAML that a user wrote: workflows, stability suites, site files, ``--set`` values.

``yaml.safe_load`` alone lets through what a hostile or careless file holds: a duplicate key
silently wins (the last one), bytes that are not UTF-8 end in a UnicodeDecodeError, an alias
chain ("billion laughs") expands into gigabytes later, deep nesting overflows the recursive
composer, and ``1e-3`` (no dot) is a string in YAML 1.1. This loader refuses the first four
with a one-line :class:`~ligwf.errors.ConfigError` naming the file and where, and reads
``1e-3`` as the number everybody means.

Scalars are resolved as in YAML 1.2's core schema, not 1.1's surprises: ``yes`` / ``no`` /
``on`` / ``off`` are words (only ``true`` / ``false`` are booleans), ``1:30`` is text (not
the base-60 number 90), ``012`` and ``0x1f`` are text (not octal 10 / hex 31), and a date
such as ``2024-01-01`` stays text (a date object cannot be stored in the JSON study
record). A number field given such text refuses it with the field and the reason
(:mod:`ligwf.scene.model`). Merge keys (``<<: *base``) work; a key repeated next to a merge
overrides the merged value, as YAML says.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

from ligwf.errors import ConfigError

#: a user's YAML file is small: refuse anything larger before parsing it
MAX_BYTES = 1_000_000
#: nodes after expanding every alias; a real workflow has a few hundred
MAX_NODES = 100_000

# YAML 1.1 floats need a dot; accept 1e-3, 5E+6 as well (as YAML 1.2 does)
_FLOAT = re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                    |\.[0-9_]+(?:[eE][-+][0-9]+)?
                    |[-+]?\.(?:inf|Inf|INF)
                    |\.(?:nan|NaN|NAN))$""", re.X)


#: YAML 1.2 core integers in decimal; 012 (1.1: octal), 0x1f, 1:30 (1.1: base 60) stay text
_INT = re.compile(r"^[-+]?(?:0|[1-9][0-9_]*)$")
_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
#: resolvers replaced (int, float, bool) or dropped (timestamp: a date is text; value: a
#: lone '=' is text)
_REPLACED = {"tag:yaml.org,2002:float", "tag:yaml.org,2002:int", "tag:yaml.org,2002:bool",
             "tag:yaml.org,2002:timestamp", "tag:yaml.org,2002:value"}


class _StrictLoader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 scalars that refuses duplicate keys and reads 1e-3 as a
    float."""

    def construct_mapping(self, node, deep=False):
        seen: dict[Any, Any] = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue    # '<<: *base': merged keys may be overridden (flatten_mapping)
            key = self.construct_object(key_node, deep=deep)
            try:
                hash(key)
            except TypeError:
                raise yaml.constructor.ConstructorError(
                    None, None, f"unhashable key {key!r}", key_node.start_mark) from None
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r} (first at line "
                    f"{seen[key].line + 1}; the last one would silently win)",
                    key_node.start_mark)
            seen[key] = key_node.start_mark
        return super().construct_mapping(node, deep=deep)


_StrictLoader.yaml_implicit_resolvers = {
    k: [(tag, rx) for tag, rx in v if tag not in _REPLACED]
    for k, v in yaml.SafeLoader.yaml_implicit_resolvers.items()}
_StrictLoader.add_implicit_resolver("tag:yaml.org,2002:bool", _BOOL, list("tTfF"))
_StrictLoader.add_implicit_resolver("tag:yaml.org,2002:int", _INT, list("-+0123456789"))
_StrictLoader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT,
                                    list("-+0123456789."))


#: stands for a node whose size is being counted (met again below itself: an alias cycle)
_COUNTING = -1


def _expanded_size(node, memo: dict[int, int]) -> int:
    """Nodes of the document with every alias expanded (aliases share node objects);
    ConfigError on an alias that refers to a node holding it (``d: &d [*d]``: a value
    containing itself, which no workflow field can hold and JSON cannot write)."""
    key = id(node)
    if memo.get(key) == _COUNTING:
        mark = node.start_mark
        raise ConfigError(f"an alias refers to the value that holds it (a value containing "
                          f"itself, from line {mark.line + 1}, column {mark.column + 1}); "
                          "write the value out")
    if key not in memo:
        memo[key] = _COUNTING
        if not isinstance(node, (yaml.SequenceNode, yaml.MappingNode)):
            memo[key] = 1
        elif isinstance(node, yaml.SequenceNode):
            memo[key] = 1 + sum(_expanded_size(n, memo) for n in node.value)
        elif isinstance(node, yaml.MappingNode):
            memo[key] = 1 + sum(_expanded_size(k, memo) + _expanded_size(v, memo)
                                for k, v in node.value)
        if memo[key] > MAX_NODES:
            raise ConfigError(f"more than {MAX_NODES:,} values once its aliases are expanded "
                              "(an alias chain?)")
    return memo[key]


def _one_line(exc: yaml.YAMLError) -> str:
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
    parts = [getattr(exc, "context", None), getattr(exc, "problem", None)]
    what = ": ".join(p for p in parts if p) or str(exc).splitlines()[0]
    return f"not valid YAML{where}: {what}"


#: characters YAML folds into a line break or a space without a word (C1 controls such as
#: NEL U+0085, line and paragraph separators): ``--set name=a<NEL>b`` became "a b"
_SILENT_BREAKS = re.compile("[\u0080-\u009f\u2028\u2029]")


def parse_yaml(text: str, source: str) -> Any:
    """Parse YAML text (``source`` names it in errors); ConfigError on anything refused."""
    if "\0" in text:
        raise ConfigError(f"{source}: holds a NUL character")
    if m := _SILENT_BREAKS.search(text):
        line = text.count("\n", 0, m.start()) + 1
        column = m.start() - (text.rfind("\n", 0, m.start()) + 1) + 1
        raise ConfigError(f"{source}: holds U+{ord(m.group()):04X}, a control or line-separator "
                          f"character, at "
                          f"line {line}, column {column} (YAML would read it as a line break "
                          "or a space); remove it, or write it as an escape in double quotes")
    try:
        loader = _StrictLoader(text)     # its reader refuses other control characters
    except yaml.YAMLError as exc:
        raise ConfigError(f"{source}: {_one_line(exc)}") from None
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _expanded_size(node, {})
        return loader.construct_document(node)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"{source}: {_one_line(exc)}") from None
    except RecursionError:
        raise ConfigError(f"{source}: nested too deeply to read (thousands of levels of "
                          "[ or {)") from None
    finally:
        loader.dispose()


#: line breaks a one-line value (``--set KEY=VALUE``) may not hold: YAML folds them into a
#: space (``name=a<LF>shell x`` became "a shell x"); its reader refuses other controls
_LINE_BREAKS = re.compile("[\n\r]")


def line_break_problem(text: str) -> str | None:
    """Where a value given on one line (a ``--set``) holds a line break, in words (None:
    it holds none)."""
    if m := _LINE_BREAKS.search(text):
        what = "a line break (\\n)" if m.group() == "\n" else "a carriage return (\\r)"
        return (f"holds {what} at character {m.start() + 1}; a value given on the command "
                "line is one line (YAML would fold it into a space)")
    return None


def read_yaml_file(path: str | Path, what: str) -> Any:
    """Parse a user's YAML file; ``what`` names it in errors ("workflow file", ...)."""
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{what} {path} is a directory, not a YAML file")
    if not path.is_file():
        try:
            path.stat()
        except OSError as exc:          # a symlink loop, no permission on a folder, ...
            if not isinstance(exc, FileNotFoundError):
                raise ConfigError(f"{what} {path}: cannot be opened "
                                  f"({exc.strerror})") from None
        raise ConfigError(f"{what} {path} does not exist" if not path.exists()
                          else f"{what} {path} is not a regular file")
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise ConfigError(f"{what} {path}: {size:,} bytes; a YAML file ligwf reads is at "
                              f"most {MAX_BYTES:,}")
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(f"{what} {path}: cannot be read ({exc.strerror})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{what} {path}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at "
                          f"offset {exc.start}); is it a binary file?") from None
    return parse_yaml(text, f"{what} {path}")


def read_yaml_mapping(path: str | Path, what: str) -> dict[str, Any]:
    """:func:`read_yaml_file` that must hold a mapping with string keys (empty file: {})."""
    data = read_yaml_file(path, what)
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(f"{what} {path}: must be a YAML mapping (key: value), "
                          f"not a {type(data).__name__}")
    bad = [k for k in data if not isinstance(k, str)]
    if bad:
        raise ConfigError(f"{what} {path}: top-level key {bad[0]!r} is not a name")
    return data
