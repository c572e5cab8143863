"""The package's shape (docs/architecture.md): layers without import cycles, short functions, typed
public results."""

import ast
from pathlib import Path

#: The package's source, as the checkout holds it (the tests import the installed copy).
PACKAGE = Path(__file__).resolve().parents[1] / "oscillator"
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
    # a package's __init__ is imported before its modules: an edge to every parent package (but
    # from a module the package itself imports while it starts: Python runs it then)
    for name in trees:
        parent = name.rpartition(".")[0]
        while parent:
            if name not in graph[parent]:
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


#: The longest module allowed, in lines: a module holds one concept.
LONGEST_MODULE = 600


def test_no_module_is_longer_than_600_lines():
    long = [
        f"{path.relative_to(PACKAGE)}: {n} lines"
        for path in sorted(PACKAGE.rglob("*.py"))
        if (n := len(path.read_text(encoding="utf-8").splitlines())) > LONGEST_MODULE
    ]
    assert long == []


#: The layers, lowest first (docs/architecture.md): a module imports only from its own unit (a
#: subpackage, or a top-level module) or from a lower layer; the units of the first layer (the
#: base: plain modules) and of the last (the public API) also from each other.
LAYERS = (
    ("errors", "text", "compiled", "folders", "presenting", "process", "threads", "version"),
    ("model",),
    ("engines", "io"),
    ("hybrid",),
    ("analysis", "orbits"),
    ("attractors",),
    ("designing", "calibrating"),
    ("report",),
    ("exploring",),
    ("cli",),
    ("__init__", "__main__", "saved", "views"),
)
LAYER = {unit: rank for rank, units in enumerate(LAYERS) for unit in units}


def unit_of(module: str) -> str:
    """``oscillator.model.fields`` -> ``model``; ``oscillator.saved`` -> ``saved``; ``oscillator`` -> ``__init__``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def every_import(tree: ast.Module) -> list[tuple[int, str]]:
    """``(line, module)`` of every import of the package, top-level or in a function (lazy), but
    those under ``if TYPE_CHECKING:`` (annotations: never run)."""
    skipped = {id(node) for block in ast.walk(tree) if isinstance(block, ast.If)
               and getattr(block.test, "id", None) == "TYPE_CHECKING" for node in ast.walk(block)}  # fmt: skip
    found = []
    for node in ast.walk(tree):
        if id(node) in skipped:
            continue
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "oscillator":
            if node.module == "oscillator":  # from oscillator import presenting: the named modules
                found += [(node.lineno, f"oscillator.{alias.name}") for alias in node.names]
            else:
                found.append((node.lineno, node.module))
        elif isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names if a.name.split(".")[0] == "oscillator"]
    return found


def test_every_module_imports_only_its_own_layer_and_those_below():
    """No upward import anywhere in the package, lazy ones included."""
    trees = modules()
    upward = []
    for name, tree in trees.items():
        here = unit_of(name)
        for line, module in every_import(tree):
            there = unit_of(module)
            if there not in LAYER:  # `from oscillator import simulate`: the API's name
                there = "__init__"
            shared = LAYER[there] == LAYER[here] in (0, len(LAYERS) - 1)
            if there != here and LAYER[there] >= LAYER[here] and not shared:
                upward.append(f"{name}:{line} imports {module}")
    assert upward == []


def test_every_unit_has_a_layer():
    units = {unit_of(name) for name in modules()}
    assert units <= set(LAYER), units - set(LAYER)


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


def test_the_formatter_is_never_switched_off():
    """Functions are short because they are, not because ``# fmt: skip`` packs their lines."""
    packed = [f"{path.relative_to(PACKAGE)}:{n}" for path in sorted(PACKAGE.rglob("*.py"))
              for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
              if "fmt: skip" in line or "fmt: off" in line]  # fmt: skip
    assert packed == []


def test_the_package_says_what_a_run_keeps_with_save_at_only():
    """``t_eval``, ``record_trajectory`` and ``keep_events_from`` stay for users; inside the
    package every run says what it keeps with ``save=SaveAt(...)``."""
    old = {"t_eval", "record_trajectory", "keep_events_from"}
    found = [
        f"{name}:{node.lineno}"
        for name, tree in modules().items()
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and getattr(node.func, "id", getattr(node.func, "attr", "")) == "simulate"
        and old & {keyword.arg for keyword in node.keywords}
    ]
    assert found == []


ROOT = PACKAGE.parent
ARCHITECTURE = ROOT / "docs" / "architecture.md"


def documented_layers() -> list[tuple[str, ...]]:
    """The layer table of docs/architecture.md, lowest first: each row's units (``errors``, ``model``)."""
    import re

    rows = []
    for line in ARCHITECTURE.read_text(encoding="utf-8").splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if line.startswith("| ") and len(cells) == 3 and cells[1].startswith("`"):
            rows.append(tuple(name.rstrip("/") for name in re.findall(r"`([^`]+)`", cells[1])))
    return rows


def documented_modules() -> set[str]:
    """The modules docs/architecture.md's tree lists, as paths inside the package (``model/fields.py``)."""
    import re

    tree = ARCHITECTURE.read_text(encoding="utf-8").split("```\noscillator/\n", 1)[1].split("```", 1)[0]
    listed, folder = set(), ""
    for line in tree.splitlines():
        found = re.match(r"^([│ ]*)[├└]── (\S+)", line)
        if found is None:
            continue
        name = found.group(2)
        if len(found.group(1)) == 0:
            folder = name.rstrip("/") if name.endswith("/") else ""
            listed.add(f"{folder}/__init__.py" if folder else name)
        else:
            listed.add(f"{folder}/{name}")
    return listed


def test_the_documented_layers_are_the_tested_ones():
    """The layer table of docs/architecture.md lists the units in the order this file checks."""
    assert documented_layers() == [tuple(units) for units in LAYERS]


def test_the_documented_tree_lists_every_module():
    actual = {str(path.relative_to(PACKAGE)) for path in PACKAGE.rglob("*.py")}
    listed = documented_modules()
    assert sorted(actual - listed) == [] and sorted(listed - actual) == []


def test_the_repository_holds_no_stray_files():
    """What the root of a checkout holds in git: a process's ``pid`` or a ``runs/`` folder is not
    the project's (skipped outside a git checkout, e.g. from an sdist)."""
    import shutil
    import subprocess

    if shutil.which("git") is None or not (ROOT / ".git").exists():
        import pytest

        pytest.skip("not a git checkout")
    listed = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    top = {name.split("/", 1)[0] for name in listed}
    expected = {".ci", ".gitignore", "README.md", "benchmarks", "cases", "docs", "oscillator", "pyproject.toml"}
    expected |= {"scripts", "tests"}
    assert top <= expected, sorted(top - expected)


def test_the_state_names_are_read_from_the_system_not_written_again():
    """The article's state names ``x1, v1, x2, v2`` are written once, in its system
    (:mod:`oscillator.model.system`, from :class:`~oscillator.model.parameters.InitialState`): no
    module outside the model spells them as a tuple or list of their own (issue 51: a layer reads
    names and sizes from the system it is given)."""
    spelled = []
    for name, tree in modules().items():
        if name.startswith("oscillator.model"):
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Tuple | ast.List):
                words = [e.value for e in node.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)]
                if {"x1", "v1", "x2", "v2"} <= set(words):
                    spelled.append(f"{name}:{node.lineno}")
    assert not spelled, spelled


def test_a_system_says_its_shape_for_the_article_and_for_a_chain():
    from oscillator.io.cases import resolve_case
    from oscillator.model.chains import FrictionChain
    from oscillator.model.parameters import Parameters

    article = resolve_case("instance-1").system
    assert article.state == ("x1", "v1", "x2", "v2") and article.size == 4 and article.masses == (1, 2)
    assert (article.position(2), article.velocity(1), article.suffix(2)) == ("x2", "v1", "_m2")
    assert article.parameters == Parameters.names() and len(article.parameters) == 25
    chain = (
        FrictionChain(Omega=2.0)
        .mass("blade", 1.0)
        .mass("damper", 0.1)
        .jenkins("blade", "damper", kt=2.0, F=0.3, name="platform")
        .stop("damper", side="right", at=0.5, K=100.0, name="wall")
    )
    system = chain.system
    assert system.state == ("x:blade", "v:blade", "x:damper", "v:damper", "z:platform") and system.size == 5
    assert system.motion == system.state[:4] and system.position("damper") == "x:damper"
    assert system.contacts == ("wall",) and system.mode_width == 2
    assert "platform.F" in system.parameters and system.label("blade") == "blade"
    try:
        system.position("rotor")
    except KeyError as error:
        assert "'rotor' is no mass" in str(error) and "'blade', 'damper'" in str(error)
    else:
        raise AssertionError("an unknown mass was given a position")
