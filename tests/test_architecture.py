"""The package's shape (docs/architecture.md): layers without import cycles, short functions, typed
public results."""

import ast
from pathlib import Path

import oscillator

PACKAGE = Path(oscillator.__file__).parent
#: The longest function allowed, in lines, docstrings aside.
LONGEST = 60


def modules() -> dict[str, ast.Module]:
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        found[name] = ast.parse(path.read_text(encoding="utf-8"))
    return found


def top_level_imports(tree: ast.Module, known: set[str]) -> set[str]:
    """The package's modules imported when this one is imported (not in functions or TYPE_CHECKING)."""
    imported = set()
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("oscillator"):
            for alias in node.names:
                child = f"{node.module}.{alias.name}"
                imported.add(child if child in known else node.module)
        elif isinstance(node, ast.Import):
            imported |= {a.name for a in node.names if a.name.startswith("oscillator")}
    return imported


def test_no_import_cycles():
    trees = modules()
    graph = {name: top_level_imports(tree, set(trees)) & set(trees) for name, tree in trees.items()}
    # a package's __init__ is imported before its modules: an edge to every parent package
    for name in trees:
        parent = name.rpartition(".")[0]
        while parent:
            graph[name].add(parent)
            parent = parent.rpartition(".")[0]
    state: dict[str, int] = {}
    cycles = []

    def visit(node, path):
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1 and nxt != node:
                cycles.append([*path[path.index(nxt) :], nxt] if nxt in path else [node, nxt])
            elif nxt not in state:
                visit(nxt, [*path, nxt])
        state[node] = 2

    for name in sorted(graph):
        if name not in state:
            visit(name, [name])
    assert cycles == []


def test_no_function_is_longer_than_60_lines():
    long = []
    for name, tree in modules().items():
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                first = node.body[0]
                if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                    lines -= first.end_lineno - first.lineno + 1
                if lines > LONGEST:
                    long.append(f"{name}.{node.name}: {lines} lines")
    assert long == []


def test_the_model_does_not_know_the_layers_above_it():
    """model/ is the article's system: it imports no engine, supervisor, file, report or command."""
    above = ("oscillator.engines", "oscillator.hybrid", "oscillator.io", "oscillator.analysis", "oscillator.report",
             "oscillator.cli")  # fmt: skip
    trees = modules()
    for name, tree in trees.items():
        if name.startswith("oscillator.model"):
            for node in ast.walk(tree):
                if isinstance(node, ast.ImportFrom) and node.module:
                    assert not node.module.startswith(above), f"{name} imports {node.module}"
