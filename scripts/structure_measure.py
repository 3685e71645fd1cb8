"""Measure the structure of ligwf/ at one or more git revisions (issue 33: "measure the
structure before and after").

    python scripts/structure_measure.py 738ff6e^ HEAD

For each revision (read with ``git show``, nothing checked out) it prints one column:
modules and lines; import edges between ligwf modules (module level and inside functions);
modules in import cycles (the package root's lazy API import inside ``__getattr__`` left
out, as tests/test_architecture.py does); the largest module; re-export shims (``noqa: F401``); private
names imported from another module; functions of 9 or more parameters and the largest
count outside the numba kernels (whose arrays are passed one by one); and duplicated
blocks: runs of 6 or more code lines (blank lines and comments dropped, whitespace
stripped) that stand again elsewhere in ligwf/, counted once per pair of places.
"""
from __future__ import annotations

import ast
import subprocess
import sys
from collections import defaultdict

import networkx as nx

WINDOW = 6
MANY = 9


def files_at(rev: str) -> dict[str, str]:
    """Every ligwf/*.py file at ``rev``: its path and text."""
    names = subprocess.run(["git", "ls-tree", "-r", "--name-only", rev, "ligwf/"],
                           check=True, capture_output=True, text=True).stdout.split()
    return {n: subprocess.run(["git", "show", f"{rev}:{n}"], check=True,
                              capture_output=True, text=True).stdout
            for n in names if n.endswith(".py")}


def module_name(path: str) -> str:
    parts = path[:-3].split("/")
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def resolve(node: ast.ImportFrom, module: str, is_package: bool) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".")
    base = base if is_package else base[:-1]
    base = base[:len(base) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def measure(files: dict[str, str]) -> dict[str, object]:
    modules = {module_name(p): p for p in files}
    graph = nx.DiGraph()
    graph.add_nodes_from(modules)
    edges = {"module level": set(), "inside functions": set()}
    private = set()
    shims = 0
    most_params = (0, "")
    many_params = 0
    for path, text in files.items():
        me = module_name(path)
        shims += text.count("noqa: F401")
        tree = ast.parse(text)
        nested = {id(n) for f in ast.walk(tree)
                  if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))
                  for n in ast.walk(f) if n is not f}
        typing_only = {id(n) for f in ast.walk(tree) if isinstance(f, ast.If)
                       and "TYPE_CHECKING" in ast.unparse(f.test) for n in ast.walk(f)}
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = node.args
                count = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs)
                count -= bool(a.args and a.args[0].arg in ("self", "cls"))
                many_params += count >= MANY
                if count > most_params[0] and not me.endswith("_numba"):
                    most_params = (count, f"{me}.{node.name}")
            targets: list[tuple[str, list[str]]] = []
            if id(node) in typing_only:         # annotations only: no import at run time
                continue
            if isinstance(node, ast.Import):
                targets = [(a.name, []) for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = resolve(node, me, path.endswith("__init__.py"))
                targets = [(f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base,
                            [a.name]) for a in node.names]
            for target, names in targets:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if not target or target == me:
                    continue
                if me == "ligwf" and id(node) in nested:    # the root's lazy API names
                    continue
                graph.add_edge(me, target)
                edges["inside functions" if id(node) in nested else "module level"].add(
                    (me, target))
                private.update(f"{target}.{n}" for n in names
                               if n.startswith("_") and not n.startswith("__"))
    cyclic = [c for c in nx.strongly_connected_components(graph) if len(c) > 1]
    if "-v" in sys.argv:
        print(cyclic, file=sys.stderr)
    lines = {module_name(p): t.count("\n") for p, t in files.items()}
    largest = max(lines, key=lines.get)
    return {
        "modules": len(files),
        "lines": sum(lines.values()),
        "import edges (module level)": len(edges["module level"]),
        "import edges (inside functions)": len(edges["inside functions"]),
        "modules in import cycles": sum(len(c) for c in cyclic),
        "largest module (lines)": f"{largest} ({lines[largest]})",
        "re-export shims (noqa: F401)": shims,
        "private names imported from another module": len(private),
        f"functions with {MANY} or more parameters": many_params,
        "most parameters (compiled kernels aside)": f"{most_params[1]} ({most_params[0]})",
        f"duplicated blocks (>= {WINDOW} code lines)": duplicated_blocks(files),
    }


def code_lines(text: str) -> list[tuple[int, str]]:
    out = []
    for number, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if s and not s.startswith("#"):
            out.append((number, s))
    return out


def duplicated_blocks(files: dict[str, str]) -> int:
    """Pairs of places (file, first line) whose next WINDOW code lines are the same; runs
    longer than WINDOW count once (only the window that starts the run)."""
    seen: dict[tuple[str, ...], list[tuple[str, int]]] = defaultdict(list)
    for path, text in files.items():
        lines = code_lines(text)
        for i in range(len(lines) - WINDOW + 1):
            key = tuple(s for _, s in lines[i:i + WINDOW])
            if sum(len(s) for s in key) < 120:      # thin lines: brackets, returns
                continue
            seen[key].append((path, i))
    starts = set()
    for places in seen.values():
        if len(places) < 2:
            continue
        for a in places:
            for b in places:
                if a < b:
                    starts.add((a, b))
    # a run of k equal windows is one block: keep a pair whose predecessor pair is absent
    return sum(1 for (a, b) in starts if ((a[0], a[1] - 1), (b[0], b[1] - 1)) not in starts)


def main(revs: list[str]) -> None:
    columns = {rev: measure(files_at(rev)) for rev in revs}
    keys = list(next(iter(columns.values())))
    print("| measure | " + " | ".join(revs) + " |")
    print("| --- |" + " --- |" * len(revs))
    for key in keys:
        print(f"| {key} | " + " | ".join(str(columns[r][key]) for r in revs) + " |")


if __name__ == "__main__":
    main([a for a in sys.argv[1:] if a != "-v"] or ["HEAD"])
