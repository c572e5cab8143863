"""The generated documentation is what the case files give now."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_reproduction_page_is_up_to_date():
    done = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "reproduction.py"), "--check"], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr


def test_model_page_names_every_theorem_function():
    import oscillator.theorems as theorems

    text = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    for name in theorems.__all__:
        if name.startswith("theorem_"):
            assert f"`{name}`" in text, name


def test_readme_python_example_runs_and_prints_what_it_says(capsys):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = text.split("```python\n", 1)[1].split("```", 1)[0]
    exec(compile(block, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "1.174583     2  sliding_vanish  ∂Ω12(2)          1     5.4   (5.28)" in out
    assert "1.289000     1  sliding_vanish  ∂Ω12(1)          2     5.4   (5.28)" in out


def test_docstring_examples_run():
    """The examples in the installed package's docstrings (doctest), e.g. ``simulate``."""
    import doctest
    import importlib
    import pkgutil

    import oscillator

    failed = tested = 0
    for info in pkgutil.iter_modules(oscillator.__path__, "oscillator."):
        module = importlib.import_module(info.name)
        outcome = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
        failed, tested = failed + outcome.failed, tested + outcome.attempted
    assert tested >= 2 and failed == 0


def test_the_case_file_example_loads_and_runs(tmp_path):
    from oscillator import load_case, simulate

    text = (ROOT / "docs" / "cases.md").read_text(encoding="utf-8")
    block = text.split("```toml\n", 1)[1].split("```", 1)[0]
    path = tmp_path / "example.toml"
    path.write_text(block, encoding="utf-8")
    case = load_case(path)
    assert case.parameters.phi2 == __import__("math").pi / 4 and case.expected[0].kind == "sliding_vanish"
    assert len(simulate(case, t_end=2.0).events) >= 1


def test_error_lines_quoted_in_the_cli_guide_are_what_the_command_prints():
    from typer.testing import CliRunner

    from oscillator.cli import app

    guide = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    for args in (["run", "instance-1", "--set", "Omgea=1.7"], ["run", "instance-1", "--set", "mu_s=0.01"]):
        printed = CliRunner().invoke(app, args).stderr.strip()
        quoted = printed.split(" (")[0] if "Omgea" in printed else printed
        assert quoted in guide, printed


def test_the_solver_settings_listed_in_the_case_guide_are_every_option_with_its_default():
    from oscillator import SolverOptions

    text = (ROOT / "docs" / "cases.md").read_text(encoding="utf-8")
    listed = text.split("# optional solver settings, with their defaults:\n", 1)[1].split("\n\n", 1)[0]
    defaults = {}
    for line in listed.splitlines():
        name, _, value = line.lstrip("# ").partition(" = ")
        defaults[name.strip()] = float(value.split("#")[0])
    assert set(defaults) == set(SolverOptions.names())
    for name, value in defaults.items():
        assert getattr(SolverOptions(), name) == value, name
