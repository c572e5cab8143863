"""Parameter, initial-state, option and override validation: one test per misuse."""

import math

import pytest

from oscillator import InitialState, OscillatorError, Parameters, SolverOptions, load_case, simulate
from oscillator.io.expressions import parse_value
from oscillator.model.fields import kinetic_threshold, static_threshold

BASE = load_case("instance-1").parameters


def test_parameters_round_trip():
    assert BASE.P1 == pytest.approx(math.pi / 8)
    assert BASE.period == pytest.approx(2 * math.pi / 1.6)
    assert static_threshold(BASE, 1) == pytest.approx(0.2 * 9.8 + math.pi / 8)
    assert kinetic_threshold(BASE, 2) == pytest.approx(0.1 * 9.8 + math.pi / 8)


def test_nonpositive_mass_is_refused():
    # a mass must be positive; the message names the field
    with pytest.raises(OscillatorError, match="m1 must be > 0") as info:
        BASE.replace(m1=0.0)
    assert info.value.field == "m1"


def test_static_below_kinetic_friction_is_refused():
    # static friction below kinetic friction would make a mass stick and unstick forever
    with pytest.raises(OscillatorError, match="mu_s must be >= mu_k"):
        BASE.replace(mu_s=0.05)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_nonfinite_values_are_refused(bad):
    with pytest.raises(OscillatorError, match="finite"):
        BASE.replace(K1=bad)


def test_negative_spring_is_refused():
    with pytest.raises(OscillatorError, match="K3 must be >= 0"):
        BASE.replace(K3=-1.0)


def test_zero_frequency_is_refused():
    with pytest.raises(OscillatorError, match="Omega must be > 0"):
        BASE.replace(Omega=0.0)


def test_non_number_is_refused():
    with pytest.raises(OscillatorError, match="must be a number"):
        InitialState(t0=0.0, x1="3", v1=0.0, x2=0.0, v2=0.0)
    with pytest.raises(OscillatorError, match="must be a number"):
        BASE.replace(g=True)


def test_end_before_start_is_refused():
    with pytest.raises(OscillatorError, match="t_end"):
        simulate("instance-1", t_end=0.5)


def test_unknown_override_suggests_the_closest_name():
    with pytest.raises(OscillatorError, match="did you mean 'Omega'"):
        simulate("instance-1", Omgea=1.7)


def test_solver_options_are_checked():
    with pytest.raises(OscillatorError, match="rtol"):
        SolverOptions(rtol=0.0)
    with pytest.raises(OscillatorError, match="max_events"):
        SolverOptions(max_events=0)
    with pytest.raises(OscillatorError, match="max_step_fraction"):
        SolverOptions(max_step_fraction=0.5)


@pytest.mark.parametrize(
    ("text", "value"), [("pi/8", math.pi / 8), ("2*pi", 2 * math.pi), ("-(1+2)**2", -9.0), (0.5, 0.5)]
)
def test_values_may_be_expressions_of_pi(text, value):
    assert parse_value(text, field="x") == pytest.approx(value)


@pytest.mark.parametrize("text", ["__import__('os')", "pi/0", "e", "1 +", "'a'"])
def test_other_expressions_are_refused(text):
    with pytest.raises(OscillatorError, match="not a number"):
        parse_value(text, field="parameters.P1")


def test_every_parameter_name_is_the_articles():
    assert Parameters.names() == (
        "m1", "m2", "C1", "C2", "C3", "C4", "C5", "K1", "K2", "K3", "K4", "K5", "K6",
        "mu_k", "mu_s", "d", "d1", "Q1", "Q2", "Omega", "phi1", "phi2", "P1", "P2", "g",
    )  # fmt: skip
