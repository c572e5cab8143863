"""The generated documentation is what the case files give now."""

import math
import re
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
    import oscillator.model.theorems as theorems

    text = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    for name in theorems.__all__:
        if name.startswith("theorem_"):
            assert f"`{name}`" in text, name


def test_readme_python_example_runs_and_prints_what_it_says(capsys, tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = text.split("```python\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(tmp_path)  # it saves a run folder under runs/
    names: dict = {}
    exec(compile(block, "README.md", "exec"), names)
    out = capsys.readouterr().out
    assert "1.174583     2  sliding_vanish  ∂Ω12(2)          1     5.4   (5.28)" in out
    assert "1.289000     1  sliding_vanish  ∂Ω12(1)          2     5.4   (5.28)" in out
    assert (tmp_path / "runs" / "omega-1.7-python" / "report.md").is_file()
    assert names["again"].events.equals(names["longer"].events)
    assert names["figure"].axes[0].get_xlim()[0] >= 19.0


def test_docstring_examples_run():
    """The examples in the installed package's docstrings (doctest), e.g. ``simulate``."""
    import doctest
    import importlib
    import pkgutil

    import oscillator

    failed = tested = 0
    for info in pkgutil.walk_packages(oscillator.__path__, "oscillator."):
        module = importlib.import_module(info.name)
        outcome = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
        failed, tested = failed + outcome.failed, tested + outcome.attempted
    assert tested >= 2 and failed == 0


def test_the_case_file_example_does_what_its_title_says(tmp_path):
    """m1 strikes its right stop: contact starts at x1 = d1 = 3.5 with v1 > 0 and ends, twice."""
    from oscillator import load_case, simulate
    from oscillator.analysis.reproduction import compare

    text = (ROOT / "docs" / "cases.md").read_text(encoding="utf-8")
    block = text.split("```toml\n", 1)[1].split("```", 1)[0]
    path = tmp_path / "my-case.toml"
    path.write_text(block, encoding="utf-8")
    case = load_case(path)
    assert case.parameters.d1 == 3.5 and case.parameters.phi2 == math.pi / 4
    events = simulate(case).events
    onsets = events[events.kind == "right_contact_onset"]
    releases = events[events.kind == "right_contact_release"]
    assert len(onsets) == len(releases) == 2
    assert (onsets.x1 - 3.5).abs().max() < 1e-9 and (onsets.v1 > 0).all() and (releases.v1 < 0).all()
    assert {"sliding_onset", "sliding_vanish"} <= set(events.kind)  # "both masses rest and leave rest"
    table = compare(case, events)
    assert table.within_article.all() and table.within_reference.all() and len(table) == 2


def test_the_readme_says_what_the_reproduction_page_shows():
    from oscillator import load_case, simulate
    from oscillator.analysis.reproduction import compare
    from oscillator.report.reproduction import _summary

    tables = {name: compare(load_case(name), simulate(name, record_trajectory=False).events)
              for name in (f"instance-{i}" for i in range(1, 6))}  # fmt: skip
    summary = _summary(tables)
    readme = " ".join((ROOT / "README.md").read_text(encoding="utf-8").split())
    given, close = re.findall(r"Of the (\d+) times the article gives, (\d+) are within", summary)[0]
    assert f"Of the {given} switching times the article gives for them, {close} are within 1e-3 s" in readme
    assert "differs by 6.9e-03 s" in summary and "differs by 6.9e-3 s" in readme
    references, equal = re.findall(r"Of the (\d+) reference times, (\d+) equal", summary)[0]
    assert references == equal and f"All {references} times of an independent implementation" in readme


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


def test_the_python_examples_of_the_docs_pages_run(tmp_path, monkeypatch):
    """Every ```python block of docs/attractors.md runs as shown (in a fresh folder; a block under
    a ``__main__`` guard runs as a script would)."""
    from pathlib import Path

    text = (Path(__file__).parents[1] / "docs" / "attractors.md").read_text(encoding="utf-8")
    blocks = [part.split("```", 1)[0] for part in text.split("```python\n")[1:]]
    assert len(blocks) == 2
    monkeypatch.chdir(tmp_path)
    for block in blocks:
        if "__main__" in block:
            block = block.replace("workers=2", "workers=1")  # the guard's example, in this process
        exec(compile(block, "docs/attractors.md", "exec"), {"__name__": "__main__"})
    assert (tmp_path / "runs" / "q2-saved" / "found.json").is_file()
