"""Exact parameter sensitivities of periodic orbits (issue 39): against Richardson-extrapolated
central differences of the map and of the orbits that `simulate` builds, on orbits that slide,
rest all period, re-stick, strike each stop, and have period 2; refused at a grazing."""

from __future__ import annotations

import functools

import numpy as np
import pandas as pd
import pytest

import oscillator as osc
from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.io.cases import resolve_case
from oscillator.orbits.shooting import find_orbit, period_map
from test_orbits import BILINEAR

#: CVODE's tolerances for the differences: the map is smooth in the parameters to about 1e-12 there.
TIGHT = {"rtol": 1e-14, "atol": 1e-14}
#: The differences' step, relative to the parameter (or absolute below 1), and Newton's tolerance.
STEP, NEWTON = 2e-3, 1e-11


def richardson(f, value: float, h: float | None = None):
    """``(4 D(h/2) - D(h)) / 3`` with ``D(h)`` the central difference of ``f`` at ``value``: the
    truncation error falls from ``h^2`` to ``h^4``.  ``h`` is :data:`STEP` relative to the value
    (absolute below 1) unless given: within the orbit's regime either side."""
    h = STEP * max(abs(value), 1.0) if h is None else h

    def central(step):
        return (np.asarray(f(value + step)) - np.asarray(f(value - step))) / (2 * step)

    return (4 * central(h / 2) - central(h)) / 3


def close(exact, differenced, size, step, rel=1e-7):
    """Agreement to ``rel`` of the derivative, or of a thousandth of the quantity's size where the
    derivative nearly vanishes, or to the differences' resolution: the map's rounding (1e-12 at
    CVODE's 1e-14) over the step."""
    exact, differenced, size = (np.asarray(v, dtype=float) for v in (exact, differenced, size))
    return np.abs(exact - differenced) <= rel * np.maximum(np.abs(exact), 1e-3 * np.abs(size)) + 1e-12 / step


def check(orbit, params, steps=None):
    """Every derivative of ``sensitivities(orbit, params)`` against the differences: the map at the
    orbit's state, the orbit's state, every response measure and every simple multiplier of the
    orbits either side (``steps``: a difference step for some of the parameters)."""
    found = osc.sensitivities(orbit, params)
    steps = steps or {}
    p = orbit.case.parameters
    base = found.multipliers["value"].to_numpy()
    for name in params:
        column = f"d/d{name}"

        def image(value, name=name):
            case = resolve_case(orbit.case, **{name: value})
            return period_map(case, orbit.section, orbit.state, orbit.period, derivative=False).end

        @functools.cache
        def moved(value, name=name):
            found = find_orbit(orbit.case, guess=orbit.state, period=orbit.period, tol=NEWTON, **{name: value})
            return found.state, pd.Series(found.response().columns()), found.multipliers

        value = getattr(p, name)
        step = steps.get(name, STEP * max(abs(value), 1.0))
        assert close(found.map[column], richardson(image, value, step), orbit.state, step).all(), name
        moving = richardson(lambda v: moved(v)[0], value, step)
        assert close(found.state[column], moving, orbit.state, step).all(), name
        measured = richardson(lambda v: moved(v)[1][found.measures.index], value, step)
        ok = close(found.measures[column], measured, found.measures["value"], step)
        assert ok.all(), (name, found.measures.index[~ok].tolist(), measured[~ok], found.measures[column][~ok])

        def matched(v, moved=moved):  # each multiplier of the moved orbit nearest the orbit's own
            values = moved(v)[2]
            return np.array([values[np.argmin(np.abs(values - mu))] for mu in base])

        exact, differenced = found.multipliers[column].to_numpy(), richardson(matched, value, step)
        simple = np.isfinite(exact)
        assert simple.sum() >= 2, name
        gap = np.abs(exact - differenced)
        assert (gap[simple] <= 1e-7 * np.maximum(np.abs(exact), 1e-3 * np.abs(base))[simple] + 1e-12 / step).all(), (
            name,
            exact,
            differenced,
        )
    return found


def test_sensitivities_of_an_orbit_that_slides_all_period():
    """Instance 1 at Omega = 1.85: both masses slide all period (reversals only, no rest)."""
    orbit = find_orbit("instance-1", Omega=1.85, tol=NEWTON, **TIGHT)
    found = check(orbit, ["Omega", "mu_k"])
    assert found.measures.loc["rest_m1", "value"] == 0 and found.margin > 0.1
    # the switch times move: each reversal's dt/dOmega is finite and the table has one per switch
    assert len(found.switches) == len(orbit.events) and np.isfinite(found.switches["dt/dOmega"]).all()


def test_sensitivities_of_an_orbit_in_which_a_mass_rests_all_period():
    """m2 forced too weakly to leave rest: it stays where it stuck (dx2 = 0, rest fraction 1)."""
    orbit = find_orbit("instance-1", Omega=1.85, Q2=1.0, tol=NEWTON, **TIGHT)
    assert orbit.resting == (2,)
    found = check(orbit, ["Q1", "K1"])
    assert (found.state.loc[["x2", "v2"]] == 0).all().all()
    assert found.measures.loc["rest_m2", "value"] == 1
    assert (abs(found.measures.loc["rest_m2"].iloc[1:]) < 1e-12).all()


def test_sensitivities_of_an_orbit_that_sticks_and_leaves_rest_through_its_flow_barrier():
    """Attractor A1 of docs/attractors.md (Q2 = 71.165, Omega = 1.6): m2 rests twice a period and
    leaves rest by crossing its flow barrier, whose position moves with Q2 and mu_s (A1 ends at
    Q2 = 71.17025: the differences' steps stay inside)."""
    orbit = find_orbit("instance-1", Omega=1.6, Q2=71.165, x2=6.0, v2=0.0, transient=200, tol=NEWTON, **TIGHT)
    found = check(orbit, ["Q2", "mu_s"], steps={"Q2": 1e-3, "mu_s": 1e-4})
    kinds = set(orbit.events.kind)
    assert {"sliding_onset", "sliding_vanish"} <= kinds and found.measures.loc["rest_m2", "value"] > 0
    assert found.measures.loc["rest_m2", "d/dmu_s"] > 0  # a higher static threshold holds m2 longer


def test_sensitivities_of_an_orbit_striking_the_right_stop_and_the_other_mass():
    """The impacting system of docs/frequency.md (d = 1, d1 = 3.5) at Omega = 1.5: one impact a
    period on the right stop, two between the masses; the contact parameters and the clearances."""
    orbit = find_orbit("instance-1", Omega=1.5, d=1, d1=3.5, tol=NEWTON, **TIGHT)
    found = check(orbit, ["d1", "C3"])
    assert found.measures.loc["onsets_right", "value"] == 1 and found.measures.loc["onsets_left", "value"] == 2
    assert found.measures.loc["force_peak_right", "d/dd1"] < 0  # a stop moved out is struck more softly


@pytest.mark.slow
def test_sensitivities_of_the_impacting_orbit_in_the_stop_stiffness_and_the_gap():
    orbit = find_orbit("instance-1", Omega=1.5, d=1, d1=3.5, tol=NEWTON, **TIGHT)
    found = check(orbit, ["K6", "d"])
    assert found.measures.loc["force_peak_right", "d/dK6"] > 0


def test_sensitivities_of_an_oscillator_against_a_stop_and_its_period_2_orbit():
    """The bilinear oscillator of docs/orbits.md: its period-1 orbit (right stop only) below the
    period doubling and its period-2 orbit beyond; both section points of the period-2 orbit."""
    single = find_orbit("instance-1", Omega=2.3, tol=NEWTON, **BILINEAR, **TIGHT)
    check(single, ["d1", "C1"])
    doubled = find_orbit("instance-1", period=2, Omega=2.44, tol=NEWTON, **BILINEAR, **TIGHT)
    found = check(doubled, ["Omega", "K6"], steps={"Omega": 5e-4})  # its amplitude grows as a root beyond the doubling
    points = found.points.pivot(index="variable", columns="point", values="d/dOmega")
    assert np.allclose(points[0].loc[["x1", "v1", "x2", "v2"]], found.state["d/dOmega"], rtol=1e-9, atol=1e-12)

    def second(value):
        moved = find_orbit(doubled.case, guess=doubled.state, period=2, tol=NEWTON, Omega=value)
        case = resolve_case(moved.case, Omega=value)
        return period_map(case, moved.section, moved.state, 1, derivative=False).end

    differenced = richardson(second, doubled.case.parameters.Omega, 5e-4)
    assert close(points[1].loc[["x1", "v1", "x2", "v2"]], differenced, doubled.state, 5e-4).all()


def test_sensitivities_are_refused_at_a_grazing_and_given_beside_it():
    """The impacting system's second contact between the masses vanishes at a grazing near Omega =
    1.7306: located by bisection on the number of onsets, the orbit there is refused with its
    distance; 1e-6 below it the derivatives are given with the margin measured."""
    kw = {"d": 1, "d1": 3.5, "rtol": 1e-13, "atol": 1e-13}
    low, high = 1.72, 1.74
    guess = find_orbit("instance-1", Omega=low, tol=1e-11, **kw).state
    for _ in range(40):
        middle = 0.5 * (low + high)
        orbit = find_orbit("instance-1", Omega=middle, guess=guess, tol=1e-11, **kw)
        if orbit.response().columns()["onsets_left"] == 2:
            low, guess = middle, orbit.state
        else:
            high = middle
    assert 1.7300 < low < 1.7310
    at = find_orbit("instance-1", Omega=low, guess=guess, tol=1e-11, **kw)
    with pytest.raises(SimulationFailed, match="not differentiable") as refused:
        at.sensitivities("Omega")
    assert refused.value.reason == Reason.NOT_DIFFERENTIABLE and "relative distance" in str(refused.value)
    beside = find_orbit("instance-1", Omega=low - 1e-6, guess=guess, tol=1e-11, **kw).sensitivities("Omega")
    assert 1e-6 < beside.margin < 1e-2 and np.isfinite(beside.of("impact_max_left")).all()


def test_the_margins_see_the_sliding_onset_and_the_grazing_the_continuation_locates():
    """Instance 1's sliding onset (1.5994) and grazing (1.6071), as continue_orbit locates them:
    at each, m2 reaches zero velocity with its force on the kinetic threshold, where Theorem 5.1
    decides between passing and resting; the margins measured the static one (1 % away, so the
    command gave one side's derivative: of rest_m2, +2.60 or -2.63 at the grazing).  Now the
    orbit at the grazing is refused; below the onset the margin names it and falls in proportion
    to the distance to it (refused 1e-8 below it); at it, Newton lands on the orbit beyond the
    onset's jump, which has derivatives of its own."""
    branch = osc.continue_orbit("instance-1", param="Omega", start=1.595, stop=1.608)
    rows = branch.bifurcations.set_index("kind")

    def orbit_at(kind, offset=0.0):
        value, state = float(rows.loc[kind, "Omega"]), rows.loc[kind, ["x1", "v1", "x2", "v2"]].to_numpy(float)
        return find_orbit("instance-1", Omega=value + offset, guess=state)

    with pytest.raises(SimulationFailed, match="kinetic threshold") as refused:
        orbit_at("grazing").sensitivities("Omega")
    assert refused.value.reason == Reason.NOT_DIFFERENTIABLE
    with pytest.raises(SimulationFailed, match="kinetic threshold"):
        orbit_at("sliding_onset", -1e-8).sensitivities("Omega")
    below = [orbit_at("sliding_onset", -offset).sensitivities("Omega") for offset in (1e-6, 1e-4)]
    assert all("kinetic threshold" in found.margins.what.iloc[0] for found in below)
    assert below[1].margin / below[0].margin == pytest.approx(100, rel=0.1)


def test_the_largest_of_tied_values_has_a_derivative_only_where_they_move_alike():
    """A symmetric orbit's two velocity peaks tie: Omega keeps the symmetry (a derivative); two tied
    candidates that move apart give the largest a kink (nan, refused rather than one side's)."""
    from oscillator.orbits.response_derivatives import _largest

    orbit = find_orbit("instance-1", Omega=1.85, tol=NEWTON, **TIGHT)
    assert np.isfinite(orbit.sensitivities("Omega").of("v_peak_m1")).all()
    alike = _largest([(2.0, np.array([1.0, 3.0])), (2.0, np.array([1.0, 3.0])), (1.0, np.array([9.0, 9.0]))], 2)
    assert alike[0] == 2.0 and np.array_equal(alike[1], [1.0, 3.0])
    apart = _largest([(2.0, np.array([1.0, 3.0])), (2.0 - 1e-12, np.array([1.0, -3.0]))], 2)
    assert apart[1][0] == 1.0 and np.isnan(apart[1][1])


def test_the_jacobians_derivative_is_exact_in_the_state_and_in_every_parameter():
    """The compiled dJ/dy . u + dJ/dc_p of the second-order pass against differences of the
    compiled Jacobian, with the cubic springs and dampers on, in modes with each contact and a
    mass at rest: in the state exactly (J is quadratic there), in the parameters to 1e-8."""
    from oscillator.model.fields import coefficients
    from oscillator.model.kernels import jacobian
    from oscillator.orbits.tangent import jacobian_gradient

    c = coefficients(resolve_case("instance-1", K2=0.7, C2=0.3, K5=0.4, C5=0.2).parameters).copy()
    rng = np.random.default_rng(7)
    y, u = rng.normal(size=4), rng.normal(size=4)

    def jac(y, c, flags):
        out = np.empty(16)
        jacobian(*y, c, *flags, out)
        return out

    found = np.empty(16)
    for flags in [(1, 1, True, True), (1, -1, False, True), (0, 1, True, False), (-1, 0, True, True)]:
        jacobian_gradient(y, c, u, -1, *flags, found)
        assert np.allclose(found, (jac(y + u, c, flags) - jac(y - u, c, flags)) / 2, rtol=0, atol=1e-14)
        assert np.any(found != 0) or flags[0] == 0
        for position in range(len(c)):
            jacobian_gradient(y, c, np.zeros(4), position, *flags, found)
            moved = c.copy()
            moved[position] += 1e-6
            ahead = jac(y, moved, flags)
            moved[position] -= 2e-6
            assert np.allclose(found, (ahead - jac(y, moved, flags)) / 2e-6, rtol=1e-6, atol=1e-8), position


def test_a_repeated_multiplier_has_no_derivative():
    """``w^H dM v / (w^H v)`` only for a simple multiplier: a double one gives nan, the others theirs."""
    from oscillator.orbits.monodromy_derivative import multiplier_derivatives

    monodromy = np.diag([0.5, 0.5, 0.2, 0.1])
    derivative = np.array([np.diag([1.0, 2.0, 3.0, 4.0])])
    values, moved = multiplier_derivatives(monodromy, derivative)
    assert np.allclose(values, [0.5, 0.5, 0.2, 0.1])
    assert np.isnan(moved[:2]).all() and np.allclose(moved[2:, 0], [3.0, 4.0])


def test_a_parameter_named_twice_is_computed_once(capsys):
    """3000 copies of d1 made 3000 columns (131 s): each parameter once, in the order first named;
    the command's table the same."""
    from oscillator.cli.app import main

    orbit = find_orbit("instance-1", Omega=1.85)
    assert orbit.sensitivities(["d1", "Omega", "d1"] * 1000).params == ("d1", "Omega")
    with pytest.raises(SystemExit) as done:
        main(["orbit", "instance-1", "--set", "Omega=1.85", "--sensitivities", ",".join(["d1"] * 3000)])
    assert done.value.code == 0
    header = next(line for line in capsys.readouterr().out.splitlines() if "multiplier" in line and "d/d" in line)
    assert header.split() == ["multiplier", "d/dd1"]


def test_the_command_says_why_a_repeated_multiplier_has_no_derivative(capsys):
    """The period-2 orbit of Instance 1, in which both masses rest: two multipliers are zero to
    rounding, repeated; the table says ``none`` and why (it printed ``nan``)."""
    from oscillator.cli.app import main

    with pytest.raises(SystemExit) as done:
        main(["orbit", "instance-1", "--period", "2", "--sensitivities", "Omega"])
    shown = capsys.readouterr().out
    assert done.value.code == 0 and "nan" not in shown
    rows = [line.split() for line in shown.split("Sensitivities of the Floquet multipliers")[1].splitlines()]
    assert sum(1 for row in rows if len(row) == 2 and row[1] == "none") == 2
    assert "none: a repeated multiplier" in shown and "zero ones come from the rests" in shown
    table = find_orbit("instance-1", period=2).sensitivities("Omega").multipliers
    assert table.simple.tolist() == [True, True, False, False] and table.loc[~table.simple, "d/dOmega"].isna().all()


def test_bad_parameters_are_refused_with_the_field():
    orbit = find_orbit("instance-1", Omega=1.85)
    with pytest.raises(InputError, match="params") as bad:
        orbit.sensitivities("Omegaa")
    assert bad.value.field == "params"
    with pytest.raises(InputError, match="params"):
        orbit.sensitivities([])
    with pytest.raises(InputError, match="measure"):
        orbit.sensitivities("Omega").of("impact")


def test_the_documented_example_prints_what_the_page_shows(capsys):
    """docs/sensitivities.md: its Python block prints the block under it."""
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "sensitivities.md").read_text(encoding="utf-8")
    code = page.split("```python\n", 1)[1].split("```", 1)[0]
    shown = page.split("```text\n", 1)[1].split("```", 1)[0]
    exec(compile(code, "docs/sensitivities.md", "exec"), {})
    assert capsys.readouterr().out == shown


def test_the_orbit_command_prints_the_sensitivities_and_refuses_a_bad_name(capsys):
    """`oscillator orbit ... --sensitivities d1,Omega`: the library's derivatives, as printed."""
    from oscillator.cli.app import main

    args = ["orbit", "instance-1", "--set", "d=1", "--set", "d1=3.5", "--set", "Omega=1.5"]
    with pytest.raises(SystemExit) as done:
        main([*args, "--sensitivities", "d1, Omega"])
    assert done.value.code == 0
    shown = capsys.readouterr().out
    expected = find_orbit("instance-1", d=1, d1=3.5, Omega=1.5).sensitivities(["d1", "Omega"])
    line = next(line for line in shown.splitlines() if line.strip().startswith("impact_max_right"))
    assert [float(v) for v in line.split()[1:]] == pytest.approx(
        expected.measures.loc["impact_max_right"].to_list(), rel=1e-5
    )
    assert "nearest point without a derivative: m1 nearly sticking" in shown
    with pytest.raises(SystemExit) as refused:
        main([*args, "--sensitivities", "d1,Omegaa"])
    assert refused.value.code == 2
    assert "--sensitivities 'Omegaa' is not a parameter; did you mean 'Omega'?" in capsys.readouterr().err
