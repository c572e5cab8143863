"""A declared machine's design over an operating band (issue 52: oscillator/designing/
chain_design.py): the worst over a band is a linear oscillator's resonance peak with its closed-form
derivatives; a design whose worst falls all the way to a bound ends there; the friction damper's
best normal load is the smallest worst of a grid, with the worst larger at no friction and at a
stuck damper; docs/damper-design.md runs as shown; the refusals."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from scipy.optimize import minimize_scalar

import oscillator
from oscillator.designing.chain_design import chain_design, worst_over
from oscillator.errors import InputError
from oscillator.model.chains import FrictionChain

ROOT = Path(__file__).resolve().parents[1]
M, K, C, Q = 1.0, 1.0, 0.1, 1.0


def oscillator_chain() -> FrictionChain:
    """``m x'' + c x' + k x = Q sin(Omega t)``."""
    return FrictionChain(Omega=1.0).mass("m", M).spring("m", k=K).damper("m", c=C).force("m", Q=Q)


def amplitude(omega: float, k: float = K, c: float = C) -> float:
    return Q / math.sqrt((k - M * omega**2) ** 2 + (c * omega) ** 2)


def test_the_worst_over_a_band_is_the_resonance_peak_with_its_closed_form_derivatives():
    """The worst ``x_max`` over [0.5, 1.5] is ``max |X(Omega)|`` (1e-8), at the peak's place
    (1e-4: the peak is flat), and its derivatives in ``k`` and ``c`` are ``d|X|/dk`` and
    ``d|X|/dc`` at the peak (the envelope: the peak's own motion does not count; 1e-6 at the place found)."""
    peak = minimize_scalar(lambda w: -amplitude(w), bounds=(0.5, 1.5), method="bounded", options={"xatol": 1e-12})
    at = float(peak.x)
    found = worst_over(oscillator_chain(), "x_max:m", ("Omega", 0.5, 1.5), names=("spring-1.k", "damper-2.c"))
    assert math.isclose(found.value, amplitude(at), rel_tol=1e-8)
    assert abs(found.at - at) <= 1e-4
    h, there = 1e-6, found.at  # the derivative at the orbit's own place
    for name, moved in (
        ("spring-1.k", lambda s: amplitude(there, k=K + s)),
        ("damper-2.c", lambda s: amplitude(there, c=C + s)),
    ):
        expected = (moved(h) - moved(-h)) / (2 * h)
        assert math.isclose(found.gradient[name], expected, rel_tol=1e-6), name


def test_a_design_whose_worst_falls_to_a_bound_ends_there_and_says_which_way():
    """More damping always lowers the peak: the best ``c`` in [0.05, 0.3] is the bound 0.3 (to
    the tolerance asked), its worst the closed-form peak there (found between 7 values of the
    band), its derivative negative."""
    design = chain_design(
        oscillator_chain(), {"damper-2.c": (0.05, 0.3)}, {"Omega": (0.5, 1.5)}, "x_max:m", sweep=7, xtol=1e-2
    )
    assert 0.3 - design.value <= 1e-2 * 0.25
    peak = -minimize_scalar(
        lambda w: -amplitude(w, c=design.value), bounds=(0.5, 1.5), method="bounded", options={"xatol": 1e-12}
    ).fun
    assert math.isclose(design.worst.value, peak, rel_tol=1e-7)
    assert design.worst.gradient["damper-2.c"] < 0
    assert list(design.history.columns) == ["damper-2.c", "worst", "at", "d/ddamper-2.c"]
    assert design.history["damper-2.c"].is_monotonic_increasing
    assert design.summary.startswith(f"damper-2.c = {design.value:.6g}: the worst x_max:m over the band is ")


def test_what_a_design_cannot_take_is_refused_by_name():
    chain = oscillator_chain()
    with pytest.raises(InputError, match="one number over one band") as caught:
        chain_design(chain, {"damper-2.c": (0.05, 0.3), "spring-1.k": (1, 2)}, {"Omega": (0.5, 1.5)}, "x_max:m")
    assert caught.value.field == "vary"
    with pytest.raises(InputError, match=r"did you mean 'damper-2\.c'"):
        chain_design(chain, {"damper-2.k": (0.05, 0.3)}, {"Omega": (0.5, 1.5)}, "x_max:m")
    with pytest.raises(InputError, match=r"no measure named x_max:blade; choose one of x_max:m"):
        worst_over(chain, "x_max:blade", ("Omega", 0.5, 1.5), sweep=3)
    with pytest.raises(InputError, match="low < high"):
        chain_design(chain, {"damper-2.c": (0.3, 0.05)}, {"Omega": (0.5, 1.5)}, "x_max:m")
    with pytest.raises(InputError, match="one objective"):
        oscillator.design(chain, {"damper-2.c": (0.05, 0.3)}, {"Omega": (0.5, 1.5)}, ["x_max:m", "x_pp:m"])


@pytest.mark.slow
def test_the_damper_design_page_runs_as_shown_and_its_best_load_beats_a_grid(tmp_path, monkeypatch, capsys):
    """docs/damper-design.md's ```python blocks run as shown (in a folder holding docs/systems/)
    and print the lines the page says; the best ``platform.F`` in [0.05, 3] makes the worst blade
    amplitude over [0.6, 1.6] no larger than at any load of a grid (a brute-force check), the
    worst at 0.05 N and at 3 N far larger (the optimum lies between the two limits), and its
    derivative at the best small against the slopes the design met."""
    import shutil

    text = (ROOT / "docs" / "damper-design.md").read_text(encoding="utf-8")
    blocks = [part.split("```", 1)[0] for part in text.split("```python\n")[1:]]
    shutil.copytree(ROOT / "docs" / "systems", tmp_path / "docs" / "systems")
    monkeypatch.chdir(tmp_path)
    names: dict[str, object] = {"__name__": "__main__"}
    for block in blocks:
        exec(compile(block, "docs/damper-design.md", "exec"), names)
    printed = capsys.readouterr().out.splitlines()
    said = [line.removeprefix("# ") for block in blocks for line in block.splitlines() if line.startswith("# ")]
    assert printed == said
    design, machine = names["design"], names["machine"]
    grid = {
        load: worst_over(machine.with_values({"platform.F": load}), "x_max:blade", ("Omega", 0.6, 1.6)).value
        for load in (0.05, 0.3, 0.6, 1.5, 3.0)
    }
    assert design.worst.value <= min(grid.values()) + 1e-9
    assert 0.05 < design.value < 3.0
    assert grid[0.05] > 3 * design.worst.value and grid[3.0] > 2 * design.worst.value
    slopes = design.history["d/dplatform.F"].abs()
    assert abs(design.worst.gradient["platform.F"]) <= 0.02 * slopes.max()
