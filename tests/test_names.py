"""One name per concept (docs/architecture.md, "Names"): the part a program can check, on the
code itself.

* ``budget`` is the error budget only: no identifier of ligwf/ pairs it with a cost or a
  time (core, hour, wall, time, cap, cost, slurm, node, rank); the core-hour cap of a
  sequential study is ``max_core_hours``;
* in the stages that decide and report (inference, report, api, study) ``seed`` names a
  random seed (``seed``, ``<what>_seed``), never the replicas it tells apart, and nothing
  is a ``member``: a run is a run or a replica (ensemble members live in engine/, local);
* a condition is a :class:`~ligwf.study.condition.Condition`, not a ``(group, cg, rule)``
  tuple: no tuple of those three names, built or unpacked, outside study/condition.py;
* the glossary has a row for each of its words.

Each checker is first shown to see what it looks for, on a small source of its own.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from helpers import ROOT

PACKAGE = ROOT / "ligwf"
#: the packages where a seed is a random seed and nothing is a member
DECIDING = ("inference", "report", "api", "study")
#: the words of the glossary
GLOSSARY = ("case", "run", "replica", "seed", "ensemble member", "sweep group", "condition",
            "arm", "look", "round", "budget", "core-hour cap", "Slurm wall-time table",
            "CG level")

COST_OR_TIME = re.compile(r"core|hour|wall|time|cap|cost|slurm|node|rank", re.I)


def identifiers(tree: ast.AST) -> set[str]:
    """Every name a source binds or reads: functions, classes, variables, attributes,
    arguments and keyword arguments."""
    out: set[str] = set()
    for n in ast.walk(tree):
        if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(n.name)
        elif isinstance(n, ast.Name):
            out.add(n.id)
        elif isinstance(n, ast.Attribute):
            out.add(n.attr)
        elif isinstance(n, ast.arg):
            out.add(n.arg)
        elif isinstance(n, ast.keyword) and n.arg:
            out.add(n.arg)
    return out


def budget_misused(names: set[str]) -> set[str]:
    return {n for n in names if "budget" in n.lower() and COST_OR_TIME.search(n)}


def seed_misused(names: set[str]) -> set[str]:
    return {n for n in names if "seed" in n.lower()
            and not re.fullmatch(r"(\w+_)?seed", n, re.I)}


def member_named(names: set[str]) -> set[str]:
    return {n for n in names if "member" in n.lower()}


def _last(e: ast.AST) -> str | None:
    """The name an element carries: ``cg``, ``case.cg``, ``row["cg"]``, ``float(case.cg)``."""
    if isinstance(e, ast.Call) and len(e.args) == 1 and isinstance(e.func, ast.Name):
        return _last(e.args[0])
    if isinstance(e, ast.Subscript) and isinstance(e.slice, ast.Constant):
        return e.slice.value if isinstance(e.slice.value, str) else None
    return e.id if isinstance(e, ast.Name) else e.attr if isinstance(e, ast.Attribute) else None


def condition_tuples(tree: ast.AST) -> list[int]:
    """Lines of tuples holding ``group, cg, rule`` (names, attributes, string subscripts,
    each maybe converted: ``float(row["cg"])``; in that order)."""
    lines = []
    for n in ast.walk(tree):
        if isinstance(n, ast.Tuple):
            names = [_last(e) for e in n.elts]
            if any(names[i:i + 3] == ["group", "cg", "rule"] for i in range(len(names))):
                lines.append(n.lineno)
    return lines


def _sources(*under: str) -> list[Path]:
    roots = [PACKAGE / u for u in under] if under else [PACKAGE]
    return sorted(p for r in roots for p in r.rglob("*.py"))


def _rel(p: Path) -> str:
    return p.relative_to(PACKAGE).as_posix()


def test_the_checkers_see_what_they_look_for():
    src = ast.parse(
        "def plan(core_hour_budget, budget, budget_source, seed, bootstrap_seed): pass\n"
        "cg1_seeds_text = seed_spread = members = 1\n"
        "key = (case.group, case.cg, case.rule)\n"
        "for (name, group, cg, rule), d in df.groupby(keys): pass\n"
        "ok = (group, rule, cg)\n"
        "speedups.get((group, float(row['cg']), str(row['rule'])))\n")
    names = identifiers(src)
    assert budget_misused(names) == {"core_hour_budget"}
    assert seed_misused(names) == {"cg1_seeds_text", "seed_spread"}
    assert member_named(names) == {"members"}
    assert condition_tuples(src) == [3, 4, 6]


def test_budget_is_the_error_budget_only():
    found = {_rel(p): sorted(bad) for p in _sources()
             if (bad := budget_misused(identifiers(ast.parse(p.read_text()))))}
    assert not found, ("budget is the error budget only: a core-hour limit is the core-hour "
                       f"cap (max_core_hours), a time plan the Slurm wall-time table: {found}")


def test_a_seed_is_a_random_seed_and_a_run_no_member():
    found = {}
    for p in _sources(*DECIDING):
        names = identifiers(ast.parse(p.read_text()))
        if (bad := seed_misused(names) | member_named(names)):
            found[_rel(p)] = sorted(bad)
    assert not found, f"replicas and runs are replicas and runs, a seed a random seed: {found}"


def test_a_condition_is_a_condition_not_a_tuple():
    found = {_rel(p): lines for p in _sources()
             if _rel(p) != "study/condition.py"
             and (lines := condition_tuples(ast.parse(p.read_text())))}
    assert not found, ("key by ligwf.study.condition.Condition (Condition.of(case), "
                       f"case.condition), not (group, cg, rule): {found}")


def test_the_glossary_names_each_word():
    text = (ROOT / "docs" / "architecture.md").read_text()
    names = text.split("\n## Names\n", 1)[1].split("\n## ", 1)[0]
    rows = {m.group(1) for m in re.finditer(r"^\| \*\*(.+?)\*\* \|", names, re.M)}
    assert rows == set(GLOSSARY)
