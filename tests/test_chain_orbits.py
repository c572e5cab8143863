"""Periodic orbits of friction chains (issue 52, first step: oscillator/orbits/chain_orbits.py):
known answers (a linear chain's steady response and its monodromy ``expm(A T)``; Den Hartog's
amplitude), a friction damper's stick-slip orbit that the map returns to and whose multipliers the
decay of a disturbance confirms, a mass stuck all period, and the refusals."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

import oscillator as osc
from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.io.chains import load_system
from oscillator.model.chains import FrictionChain
from oscillator.orbits.chain_orbits import ChainOrbit, chain_period_map, find_chain_orbit
from test_chain_runs import _den_hartog

SYSTEMS = Path(__file__).resolve().parents[1] / "docs" / "systems"
OMEGA = 1.3


def linear_chain() -> FrictionChain:
    """Two masses, springs and dampers to the ground and between them, forced on the first."""
    return (
        FrictionChain(Omega=OMEGA)
        .mass("a", 1.0)
        .mass("b", 0.5)
        .spring("a", k=2.0)
        .spring("a", "b", k=1.0)
        .damper("a", c=0.1)
        .damper("b", c=0.05)
        .force("a", Q=1.0, phi=0.3)
    )


def test_a_linear_chains_orbit_is_its_steady_response_and_its_monodromy_the_exponential():
    """``M X'' + C X' + K X = F sin(Omega t + phi)``: the orbit at t0 is ``Im(X e^{i phi})`` with
    ``(K - Omega^2 M + i Omega C) X = F`` (1e-9), and ``dP/dy`` is ``expm(A T)`` (1e-6: central
    differences)."""
    orbit = osc.find_orbit(linear_chain(), transient=5)
    assert isinstance(orbit, ChainOrbit) and orbit.free == ("x:a", "v:a", "x:b", "v:b")
    mass, damping = np.diag([1.0, 0.5]), np.diag([0.1, 0.05])
    stiffness = np.array([[3.0, -1.0], [-1.0, 1.0]])
    amplitude = np.linalg.solve(stiffness - OMEGA**2 * mass + 1j * OMEGA * damping, [1.0, 0.0]) * np.exp(0.3j)
    steady = np.ravel(np.column_stack([amplitude.imag, (1j * OMEGA * amplitude).imag]))
    np.testing.assert_allclose(orbit.state, steady, rtol=0, atol=1e-9)
    a = np.zeros((4, 4))
    a[0, 1] = a[2, 3] = 1.0
    a[np.ix_([1, 3], [0, 2])] = -np.linalg.solve(mass, stiffness)
    a[np.ix_([1, 3], [1, 3])] = -np.linalg.solve(mass, damping)
    exact = scipy.linalg.expm(a * 2 * math.pi / OMEGA)
    np.testing.assert_allclose(orbit.monodromy, exact, rtol=0, atol=1e-6)
    np.testing.assert_allclose(np.abs(orbit.multipliers), np.sort(np.abs(np.linalg.eigvals(exact)))[::-1], atol=1e-6)
    assert orbit.stable and orbit.residual <= 1e-10 and orbit.verdict == "stable"


def test_den_hartogs_orbit_turns_at_his_amplitude():
    """The forced Coulomb oscillator's orbit (section a quarter period after the turn at -X):
    it turns at +X and -X half a period apart (1e-8), never sticking."""
    amplitude, phi = _den_hartog()
    chain = (
        FrictionChain(Omega=0.6)
        .mass("m", m=1.0)
        .spring("m", k=1.0)
        .force("m", Q=1.0, phi=phi)
        .friction("m", mu_s=0.2, mu_k=0.2, N=1.0)
    )
    period = 2 * math.pi / 0.6
    orbit = find_chain_orbit(chain, section=period / 4, transient=30)
    turns = orbit.events[orbit.events.kind == "passable"]
    assert len(turns) == 2 and (orbit.events.kind != "sticks").all()
    np.testing.assert_allclose(turns.t.to_numpy(), period * np.array([0.5, 1.0]), rtol=0, atol=1e-8)
    at = orbit.run.trajectory.drop_duplicates("t", keep="last").set_index("t")["x:m"]
    np.testing.assert_allclose(at.loc[turns.t.to_numpy()].to_numpy(), [amplitude, -amplitude], rtol=0, atol=1e-8)
    assert orbit.stable and orbit.free == ("x:m", "v:m")


def test_a_friction_dampers_stick_slip_orbit_returns_and_a_disturbance_decays_as_its_multipliers_say():
    """The blade with its Jenkins damper (docs/systems/blade-damper.toml): the slider sticks and
    slips twice a period; the map returns to the orbit (1e-10 of its scale); a disturbance along the largest
    multiplier's eigenvector shrinks by that multiplier a period (to 2 %, over 8 periods)."""
    chain = load_system(SYSTEMS / "blade-damper.toml")
    orbit = find_chain_orbit(chain, transient=60)
    kinds = set(orbit.events.kind)
    assert {"slider_sticks", "slider_slips"} <= kinds and orbit.free == chain.system.state
    image = chain_period_map(chain, orbit.section, orbit.state)
    assert np.max(np.abs(image.y_end[:5] - orbit.state)) <= 1e-10 * np.max(np.abs(orbit.state))
    values, vectors = np.linalg.eig(orbit.monodromy)
    k = int(np.argmax(np.abs(values)))
    assert abs(values[k].imag) < 1e-12 and 0 < abs(values[k]) < 1 and orbit.stable
    push = 1e-5 * np.real(vectors[:, k]) / np.max(np.abs(vectors[:, k]))
    state, periods = orbit.state + push, 8
    for _ in range(periods):
        state = chain_period_map(chain, orbit.section, state).y_end[:5]
    grown = np.max(np.abs(state - orbit.state)) / np.max(np.abs(push))
    assert grown == pytest.approx(abs(values[k]) ** periods, rel=0.02)


def test_the_transient_is_the_run_simulate_makes_and_newton_refines_it_to_the_same_orbit():
    """Without a guess, the orbit starts where ``simulate_chain`` at its own tolerances leaves the
    motion after the transient (as the article's system's does: Newton's path from there is the
    same to the bit), a tight run's end more than 1e-9 away; from either, Newton at the map's
    tolerances gives the same orbit (1e-10: at Omega = 1.1 the slider sticks and slips, the orbit
    is one, not a family)."""
    from oscillator.hybrid.chain_run import simulate_chain
    from oscillator.orbits.chain_orbits import ORBIT_OPTIONS

    chain = load_system(SYSTEMS / "blade-damper.toml").with_values({"Omega": 1.1})
    size, end = chain.system.size, chain.t0 + 40 * chain.period
    plain = simulate_chain(chain, end).y_end[:size]
    tight = simulate_chain(chain, end, options=ORBIT_OPTIONS).y_end[:size]
    assert np.max(np.abs(plain - tight)) > 1e-9
    orbit = find_chain_orbit(chain, transient=40)
    assert np.max(np.abs(find_chain_orbit(chain, plain, transient=0).state - orbit.state)) == 0.0
    assert np.max(np.abs(find_chain_orbit(chain, tight, transient=0).state - orbit.state)) <= 1e-10


def test_a_mass_stuck_all_period_keeps_its_place_and_velocity():
    """A second mass held by friction far above the force it feels: it rests the whole period,
    neutral in its place; Newton moves the first mass only."""
    chain = (
        linear_chain()
        .friction("b", mu_s=50.0, mu_k=40.0)
        .mass("c", 1.0, x=0.3)
        .spring("c", k=1.0)
        .friction("c", mu_s=10.0, mu_k=8.0)
    )
    orbit = find_chain_orbit(chain, transient=10)
    assert orbit.neutral == ("x:b", "x:c") and orbit.free == ("x:a", "v:a")
    assert orbit.state[4] == 0.3 and orbit.state[5] == 0.0 and "neutral in x:c" in orbit.verdict


def test_bad_input_and_a_motion_without_an_orbit_are_refused():
    chain = linear_chain()
    with pytest.raises(InputError, match="guess must be 4 finite numbers") as said:
        find_chain_orbit(chain, guess=[0.0, 1.0])
    assert said.value.field == "guess"
    with pytest.raises(InputError, match="period must be a whole number"):
        find_chain_orbit(chain, period=0)
    # the rattling conveyor has no period-1 orbit near its motion
    with pytest.raises(SimulationFailed, match="did not converge") as failed:
        find_chain_orbit(load_system(SYSTEMS / "conveyor.toml"), transient=20, max_iterations=4)
    assert failed.value.reason == Reason.NO_CONVERGENCE


@pytest.mark.slow  # an end-to-end worked example of 20 s: CI runs it with the slow tier
def test_the_python_examples_of_the_systems_page_run(tmp_path, monkeypatch, capsys):
    """docs/systems.md's ```python blocks run as shown (in a fresh folder holding docs/systems/, as
    the repository does), and the orbit's, its sensitivities', the sweeps', the branch's and the
    attractors' and spectrum's printed lines are those the page says."""
    import shutil

    text = (SYSTEMS.parent / "systems.md").read_text(encoding="utf-8")
    blocks = [part.split("```", 1)[0] for part in text.split("```python\n")[1:]]
    assert len(blocks) == 8
    shutil.copytree(SYSTEMS, tmp_path / "docs" / "systems")
    monkeypatch.chdir(tmp_path)
    for block in blocks:
        exec(compile(block, "docs/systems.md", "exec"), {"__name__": "__main__"})
    printed = capsys.readouterr().out.splitlines()
    assert printed[0] == "stable" and printed[1] == "['0.9388', '0.7622', '0.3493', '0.3493', '0.0000']"
    assert "slider_slips" in printed[3] and printed[3].split()[1] == "0.137144"
    derivative = next(line.removeprefix("# ") for line in blocks[2].splitlines() if line.startswith("# {"))
    assert derivative in printed
    said = [line.removeprefix("# ") for line in blocks[3].splitlines() if line.startswith("# F = ")]
    assert printed[-12:-9] == said and len(said) == 3
    folds = next(line.removeprefix("# ") for line in blocks[4].splitlines() if line.startswith("# ["))
    said = [line.removeprefix("# ") for line in blocks[5].splitlines() if line.startswith("# ")]
    assert printed[-9:-4] == [folds, printed[-8], *said] and printed[-8].startswith("the end of the span")
    ends = [line.removeprefix("# ") for line in blocks[6].splitlines() if line.startswith("# period")]
    regimes = [line.removeprefix("# ") for line in blocks[7].splitlines() if line.startswith("# ")]
    assert printed[-4:] == [*ends, *regimes] and len(ends) == 2 and len(regimes) == 2


def den_hartog_chain() -> FrictionChain:
    """Den Hartog's forced Coulomb oscillator ``x'' + x + 0.2 sgn(x') = sin(Omega t)``."""
    return (
        FrictionChain(Omega=0.55)
        .mass("m", m=1.0)
        .spring("m", k=1.0)
        .force("m", Q=1.0)
        .friction("m", mu_s=0.2, mu_k=0.2, N=1.0, name="floor")
    )


def _den_hartog_amplitude(omega: float, friction: float = 0.2) -> float:
    """Den Hartog's amplitude of the continuous motion of ``x'' + x + F sgn(x') = sin(Omega t)``."""
    u = math.sin(math.pi / omega) / (omega * (1 + math.cos(math.pi / omega)))
    return math.sqrt(1 / (1 - omega**2) ** 2 - (friction * u) ** 2)


def test_a_sweep_over_omega_gives_the_linear_chains_frequency_response():
    """The sweep's amplitudes ``x_pp / 2`` are ``|X(Omega)|`` of the closed form, each mass, to 1e-9,
    and ``x_max`` the same (the extremes found between steps, exact to the solver)."""
    from oscillator.orbits.chain_response import frequency_sweep

    values = np.linspace(0.5, 2.0, 7)
    table = frequency_sweep(linear_chain(), values, transient=10)
    assert list(table.status) == ["followed"] * 7 and table.stable.all()
    mass, damping = np.diag([1.0, 0.5]), np.diag([0.1, 0.05])
    stiffness = np.array([[3.0, -1.0], [-1.0, 1.0]])
    for value, (_, row) in zip(values, table.iterrows(), strict=True):
        exact = np.abs(np.linalg.solve(stiffness - value**2 * mass + 1j * value * damping, [1.0, 0.0]))
        assert row["x_pp:a"] / 2 == pytest.approx(exact[0], abs=1e-9) and row["x_max:a"] == pytest.approx(
            exact[0], abs=1e-9
        )
        assert row["x_pp:b"] / 2 == pytest.approx(exact[1], abs=1e-9), value


def test_a_sweep_gives_den_hartogs_amplitude_along_a_band():
    """The forced Coulomb oscillator over Omega in [0.55, 0.75] (continuous motion: it never
    sticks): ``x_max = -x_min = X(Omega)`` of Den Hartog's closed form to 1e-8."""
    from oscillator.orbits.chain_response import frequency_sweep

    chain = den_hartog_chain()
    values = [0.55, 0.6, 0.65, 0.7, 0.75]
    table = frequency_sweep(chain, values, transient=40)
    for value, (_, row) in zip(values, table.iterrows(), strict=True):
        amplitude = _den_hartog_amplitude(value)
        assert row["x_max:m"] == pytest.approx(amplitude, abs=1e-8) and row["x_min:m"] == pytest.approx(
            -amplitude, abs=1e-8
        )
        assert row["stuck:floor"] == 0.0 and row.stable, value


def test_a_friction_dampers_stuck_share_is_read_from_its_events_and_a_lost_orbit_is_said():
    """The blade's damper holds between its sticking and its slipping events: its stuck share is
    their spans over the period; a value where no orbit is found is a failed row, with why, and
    the sweep goes on."""
    from oscillator.orbits.chain_response import frequency_sweep, orbit_measures

    chain = load_system(SYSTEMS / "blade-damper.toml")
    orbit = find_chain_orbit(chain, transient=60)
    events = orbit.events
    held = sum(
        b - a
        for a, b in zip(
            events.t[events.kind == "slider_sticks"], events.t[events.kind == "slider_slips"][1:], strict=False
        )
    )
    held += events.t.iloc[0] - orbit.section + orbit.section + chain.period - events.t.iloc[-1]
    assert orbit_measures(orbit)["stuck:platform"] == pytest.approx(held / chain.period, abs=1e-12)
    with pytest.raises(InputError, match="kt") as refused:
        frequency_sweep(chain, [2.0, -1.0], param="platform.kt")
    assert refused.value.field == "kt"
    conveyor = load_system(SYSTEMS / "conveyor.toml")  # rattles: no period-1 orbit near its motion
    table = frequency_sweep(conveyor, [3.0, 3.1], transient=20, max_iterations=3)
    assert list(table.status) == ["failed", "failed"] and table.message.str.contains("did not converge").all()


def test_a_friction_dampers_response_tends_to_its_two_linear_limits():
    """The blade's damper swept over ``Omega``: with ``F = 0`` the slider never holds and the blade
    answers as alone (``|X| = Q / |k - m Omega^2 + i c Omega|``); with ``F`` far above any force it
    holds all period and the blade answers as the two masses coupled by ``kt`` (their linear
    system's ``|X_blade|``): ``x_pp / 2`` equals each closed form to 1e-8."""
    from oscillator.orbits.chain_response import frequency_sweep

    machine = load_system(SYSTEMS / "blade-damper.toml")
    values = np.array([0.6, 0.8, 1.3, 1.6])
    alone = frequency_sweep(machine.with_values({"platform.F": 0.0}), values, transient=20)
    stuck = frequency_sweep(machine.with_values({"platform.F": 1e4}), values, transient=20)
    mass, damping = np.diag([1.0, 0.1]), np.diag([0.02, 0.0])
    stiffness = np.array([[1.0 + 2.0, -2.0], [-2.0, 2.0 + 0.5]])
    for k, omega in enumerate(values):
        single = 0.5 / abs(1.0 - omega**2 + 0.02j * omega)
        coupled = np.linalg.solve(stiffness - omega**2 * mass + 1j * omega * damping, [0.5, 0.0])
        assert math.isclose(alone["x_pp:blade"][k] / 2, single, rel_tol=1e-8), omega
        assert math.isclose(stuck["x_pp:blade"][k] / 2, abs(coupled[0]), rel_tol=1e-8), omega
        assert stuck["stuck:platform"][k] == 1.0 and alone["stuck:platform"][k] == 0.0
