"""Noise measures (docs/noise.md): spectra against closed-form Fourier series and Parseval, the
model's own half-sine contact pulse and its impulse, the impact power against the energy audit."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import oscillator as osc
from oscillator.errors import InputError
from oscillator.orbits.noise import noise
from oscillator.orbits.spectra import a_weighting, fourier_coefficients, mean_square_above

ROOT = Path(__file__).resolve().parents[1]


def half_sine_series(amplitude: float, width: float, period: float, start: float, harmonics: int) -> np.ndarray:
    """The Fourier coefficients of ``amplitude sin(pi (t - start) / width)`` on ``[start, start +
    width]``, zero elsewhere in the period: ``a (1 + exp(-i w width)) / (a^2 - w^2)``, ``a = pi /
    width``, shifted by ``start``."""
    a = np.pi / width
    w = 2 * np.pi * np.arange(harmonics + 1) / period
    return amplitude * a * (1 + np.exp(-1j * w * width)) / (a**2 - w**2) / period * np.exp(-1j * w * start)


def test_a_half_sine_pulse_trains_coefficients_are_its_closed_form_series_and_sum_to_its_mean_square():
    amplitude, width, period = 3.0, 0.37, 2.0
    pulse = [(0.25, 0.25 + width, lambda t: amplitude * np.sin(np.pi * (t - 0.25) / width))]
    coefficients = fourier_coefficients(pulse, period, 2000)
    exact = half_sine_series(amplitude, width, period, 0.25, 2000)
    assert np.abs(coefficients - exact).max() < 1e-12 * np.abs(exact).max()
    mean_square = amplitude**2 * width / (2 * period)
    parseval = abs(coefficients[0]) ** 2 + mean_square_above(coefficients, 1 / period)
    assert parseval == pytest.approx(mean_square, rel=1e-9)


def test_the_a_weighting_is_iec_61672s():
    frequency = 10.0 ** np.array([1.3, 2.0, 3.0, 4.0])  # the standard's 20 Hz, 100 Hz, 1 kHz, 10 kHz
    assert a_weighting(frequency) == pytest.approx([-50.5, -19.1, 0.0, -2.5], abs=0.1)


def test_a_mass_struck_once_by_the_elastic_stop_feels_a_half_sine_force_and_twice_its_momentum():
    """m1 free of springs, dampers, forcing and (to 1e-12) friction meets the stop ``K6`` at speed
    ``v0``: the force is ``m1 v0 w sin(w t)`` for ``pi / w`` s, ``w^2 = K6 / m1``."""
    p = osc.resolve_case("instance-1").parameters
    free = {"K1": 0, "K2": 0, "C1": 0, "C2": 0, "Q1": 0, "Q2": 0, "P1": 0, "P2": 0, "mu_k": 1e-12, "mu_s": 2e-12}
    start = {"t0": 0.0, "x1": p.d1 - 0.1, "v1": 1.0, "x2": 0.0, "v2": 0.0}
    case = osc.resolve_case("instance-1", **free, K6=2.5, d=100, **start, rtol=1e-14, atol=1e-14)
    right = noise(case, 1, 120).contacts["right"]
    m1, w, period = case.parameters.m1, np.sqrt(2.5 / case.parameters.m1), case.parameters.period
    exact = half_sine_series(m1 * 1.0 * w, np.pi / w, period, 0.1, 120)
    assert np.abs(right.coefficients - exact).max() < 1e-9 * np.abs(exact).max()
    assert right.onsets == 1 and right.impulse == pytest.approx(2 * m1 * 1.0, rel=1e-9)
    assert right.energy == right.power == 0.0  # K6 has no damper
    assert noise(case, 1, 120).contacts["left"].rate == 0.0


def test_the_impact_power_is_the_energy_the_contacts_damper_dissipates():
    orbit = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.5)
    found, response = orbit.noise(), orbit.response()
    left, period = found.contacts["left"], orbit.case.parameters.period
    assert left.power * period == pytest.approx(response.energy["contact"], rel=1e-9)
    assert left.energy * left.onsets == pytest.approx(response.energy["contact"] * orbit.period, rel=1e-9)
    assert left.rate == pytest.approx(response.contact["left"]["onsets"] / period, rel=1e-12)
    assert found.power == left.power and left.impact_max == response.contact["left"]["impact_max"]
    columns = found.columns(cutoff=1.0)
    assert columns["force_level_left"] == pytest.approx(left.level(1.0)) and left.level(1.0) < left.level()
    spectrum = left.spectrum()
    assert spectrum.frequency[1] == pytest.approx(1 / (orbit.period * period))
    assert spectrum.amplitude[0] == pytest.approx(left.impulse_rate, rel=1e-12)  # the mean force


def test_the_page_prints_what_it_shows(capsys):
    page = (ROOT / "docs" / "noise.md").read_text(encoding="utf-8")
    code = page.split("```python\n", 1)[1].split("```", 1)[0]
    shown = page.split("```text\n", 1)[1].split("```", 1)[0]
    exec(compile(code, "docs/noise.md", "exec"), {})
    assert capsys.readouterr().out == shown


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda: noise("instance-1", 1), "case"),
        (lambda: noise(osc.resolve_case("instance-1"), 0), "periods"),
        (lambda: noise(osc.resolve_case("instance-1"), 1, -1), "harmonics"),
        (lambda: fourier_coefficients([], 0.0, 3), "period"),
    ],
)
def test_bad_arguments_are_refused_naming_the_field(call, field):
    with pytest.raises(InputError) as refused:
        call()
    assert refused.value.field == field
