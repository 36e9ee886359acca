"""The package's shape: ``python benchmarks/architecture.py [package_dir]``.

Prints the figures of the before/after table of the layout redesign: number of modules, lines, the
largest module and function, the import levels (the longest chain of intra-package imports) and the
import cycles. Every import counts, also those inside functions and under ``TYPE_CHECKING``: a lazy
import hides a cycle from Python, not from the reader.

``tests/test_architecture.py`` loads this file and asserts on the same graph.
"""

from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path


def _module_name(root: Path, path: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _resolve(name: str, modules: set[str]) -> str | None:
    """The package module that ``import name`` loads (its longest existing prefix)."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def import_graph(root: Path) -> dict[str, set[str]]:
    """module -> package modules it imports (every import statement, at any depth of the file)."""
    paths = {_module_name(root, p): p for p in sorted(root.rglob("*.py"))}
    modules = set(paths)
    graph: dict[str, set[str]] = {}
    for name, path in paths.items():
        is_pkg = path.name == "__init__.py"
        package = name if is_pkg else name.rpartition(".")[0]
        edges: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text())):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = package.split(".")
                    anchor = anchor[: len(anchor) - (node.level - 1)]
                    base = ".".join([*anchor, base] if base else anchor)
                # "from pkg import sub" imports the submodule when there is one, else pkg itself
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
            for target in targets:
                hit = _resolve(target, modules)
                if hit is not None and hit != name and not name.startswith(hit + "."):
                    edges.add(hit)  # a module's own parent packages load implicitly: not an edge
        graph[name] = edges
    return graph


def strongly_connected(graph: dict[str, set[str]]) -> list[set[str]]:
    """Tarjan's strongly connected components; a component of more than one module is a cycle."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[set[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.add(w)
                if w == v:
                    break
            out.append(comp)

    sys.setrecursionlimit(max(10_000, sys.getrecursionlimit()))
    for v in graph:
        if v not in index:
            visit(v)
    return out


def levels(graph: dict[str, set[str]]) -> dict[str, int]:
    """Import level of each module: 1 + the highest level it imports (a cycle counts as one level)."""
    comp_of = {m: i for i, c in enumerate(strongly_connected(graph)) for m in c}
    memo: dict[int, int] = {}

    def level(c: int) -> int:
        if c not in memo:
            members = [m for m, i in comp_of.items() if i == c]
            below = {comp_of[w] for m in members for w in graph[m]} - {c}
            memo[c] = 1 + max((level(b) for b in below), default=0)
        return memo[c]

    return {m: level(comp_of[m]) for m in graph}


#: Loader methods the import system hands a module to fill: writing its attributes is their contract.
IMPORT_PROTOCOL = ("exec_module",)


def foreign_writes(root: Path) -> list[str]:
    """Places where a module writes attributes into an object it was handed (``file:line what``).

    Flags every use of ``__dict__``, every ``setattr(...)`` and ``object.__setattr__(...)`` whose target is
    not ``self``, and every assignment to an attribute of a function's parameter other than ``self``/``cls``
    (except an exception's ``args``, re-worded before it is raised again, and an import loader's
    ``exec_module``, whose module is handed to it to fill). Objects a function creates itself may be configured
    freely.
    """
    found = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root.parent).as_posix()
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and node.attr == "__dict__":
                found.append(f"{rel}:{node.lineno} __dict__")
            if isinstance(node, ast.Call):
                fn = node.func
                name = fn.id if isinstance(fn, ast.Name) else fn.attr if isinstance(fn, ast.Attribute) else ""
                if name in ("setattr", "__setattr__") and node.args:
                    target = node.args[0]
                    if not (isinstance(target, ast.Name) and target.id == "self"):
                        found.append(f"{rel}:{node.lineno} {name}")
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.name not in IMPORT_PROTOCOL:
                params = {a.arg for a in (*node.args.posonlyargs, *node.args.args, *node.args.kwonlyargs)}
                params -= {"self", "cls"}
                for sub in ast.walk(node):
                    targets = sub.targets if isinstance(sub, ast.Assign) else [getattr(sub, "target", None)]
                    if not isinstance(sub, ast.Assign | ast.AugAssign | ast.AnnAssign):
                        continue
                    for t in targets:
                        if t is None or not isinstance(t, ast.Attribute) or t.attr == "args":
                            continue  # ``exc.args = ...``: an exception re-worded before it is raised again
                        if isinstance(t.value, ast.Name) and t.value.id in params:
                            found.append(f"{rel}:{sub.lineno} {t.value.id}.{t.attr} =")
    return sorted(set(found))


def code_lines(path: Path) -> int:
    """Lines that hold code: not blank, not a comment, not part of a docstring."""
    text = path.read_text()
    doc: set[int] = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) and node.body:
            first = node.body[0]
            if (
                isinstance(first, ast.Expr)
                and isinstance(first.value, ast.Constant)
                and isinstance(first.value.value, str)
            ):
                doc.update(range(first.lineno, (first.end_lineno or first.lineno) + 1))
    return sum(
        1
        for i, line in enumerate(text.splitlines(), 1)
        if line.strip() and not line.strip().startswith("#") and i not in doc
    )


def long_functions(path: Path, limit: int = 60) -> int:
    """How many functions or methods of one file are longer than ``limit`` lines."""
    return sum(
        (node.end_lineno or node.lineno) - node.lineno + 1 > limit
        for node in ast.walk(ast.parse(path.read_text()))
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
    )


def longest_function(path: Path) -> tuple[int, str]:
    """(lines, name) of the longest function or method in one file."""
    best = (0, "")
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            n = (node.end_lineno or node.lineno) - node.lineno + 1
            best = max(best, (n, node.name))
    return best


def main(root: Path) -> None:
    files = sorted(root.rglob("*.py"))
    sizes = {f: len(f.read_text().splitlines()) for f in files}
    rel = {f: f.relative_to(root.parent).as_posix() for f in files}
    top_level = [f for f in files if f.parent == root]
    big = max(files, key=sizes.__getitem__)
    fn_len, fn_name, fn_file = max((*longest_function(f), rel[f]) for f in files)
    graph = import_graph(root)
    cycles = [sorted(c) for c in strongly_connected(graph) if len(c) > 1]
    depth = levels(graph)
    print(f"modules                 {len(files)}  ({len(top_level)} flat at the top)")
    print(f"packages                {sorted({rel[f].rsplit('/', 1)[0] for f in files})}")
    print(f"lines                   {sum(sizes.values())}  ({sum(map(code_lines, files))} of code)")
    print(f"largest module          {rel[big]} ({sizes[big]} lines)")
    print(f"largest function        {fn_file}:{fn_name} ({fn_len} lines)")
    print(f"modules over 400 lines  {sum(s > 400 for s in sizes.values())}")
    print(f"functions over 60 lines {sum(map(long_functions, files))}")
    print(f"import levels           {max(depth.values())}")
    print(f"import cycles           {len(cycles)}  {cycles}")
    writes = foreign_writes(root)
    print(f"foreign attribute writes {len(writes)}  {writes}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("package", nargs="?", type=Path, default=Path(__file__).resolve().parents[1] / "gausspp")
    main(parser.parse_args().package)
