"""Smooth phases and switching times with closed forms (cubic, contact and feedback terms off)."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from oscillator import simulate as simulate_default


def simulate(case, **options):
    """Closed forms are compared at tight tolerances, not the defaults."""
    return simulate_default(case, **{"rtol": 1e-12, "atol": 1e-12, **options})


def test_coulomb_oscillator_turning_points_and_final_rest(build):
    """x'' = -w^2 x - s mu_k g: half-swings of pi/w, amplitude shrinking by 2 mu_k g / w^2.

    m1 (w = 2) leaves rest at t0 since K1 x0 > mu_s m1 g, passes its velocity boundary while
    |x_k| > mu_k g / w^2 and comes to rest at the first turning point inside that band.
    m2 (w = 1, domains reversed) leaves towards Omega_2(2) and rests after one half-swing.
    """
    t0, x0 = 0.5, 3.0
    case = build(14.0, initial=(t0, x0, 0.0, -2.0, 0.0))
    result = simulate(case)
    events = result.events
    w, delta = 2.0, 0.1 * 9.8 / 4.0

    m1 = events[events.mass == 1].reset_index(drop=True)
    assert m1.loc[0, "kind"] == "sliding_vanish" and m1.loc[0, "t"] == t0 and m1.loc[0, "to_domain"] == 2
    turning = [(-1) ** k * (x0 - 2 * k * delta) for k in range(1, 7)]
    expected_kinds = ["passable"] * 5 + ["sliding_onset"]
    assert list(m1.kind[1:]) == expected_kinds
    np.testing.assert_allclose(m1.t[1:], t0 + np.arange(1, 7) * math.pi / w, rtol=0, atol=1e-9)
    np.testing.assert_allclose(m1.x1[1:], turning, rtol=0, atol=1e-9)
    assert abs(turning[-1]) < delta  # why it rests there

    m2 = events[events.mass == 2].reset_index(drop=True)
    assert list(m2.kind) == ["sliding_vanish", "sliding_onset"]
    assert m2.loc[0, "to_domain"] == 2  # v2 > 0 is Omega_2 for m2
    assert m2.loc[1, "t"] == pytest.approx(t0 + math.pi, abs=1e-9)
    assert m2.loc[1, "x2"] == pytest.approx(2.0 - 2 * 0.98, abs=1e-9)  # mirror image, minus 2 delta

    # after the last event both stay at rest exactly
    tail = result.trajectory[result.trajectory.t > m1.t.iloc[-1] + 1e-9]
    assert (tail.v1 == 0).all() and (tail.v2 == 0).all()
    assert (tail.domain1 == 0).all() and (tail.domain2 == 0).all()


def test_a_mass_that_cannot_overcome_static_friction_stays(build):
    # K1 x0 = 1.6 lies between mu_k m1 g = 0.98 and mu_s m1 g = 1.96: static friction holds.
    result = simulate(build(3.0, initial=(0.0, 0.4, 0.0, 0.0, 0.0)))
    assert result.events.empty
    assert (result.trajectory.x1 == 0.4).all()


def forced_position(t, t0, x0, v0, s, w, q, omega, mu_g):
    """Closed form of x'' + w^2 x = -s mu_g + q sin(omega t) from (t0, x0, v0)."""
    b = q / (w**2 - omega**2)
    c = -s * mu_g / w**2
    # x = A cos w(t-t0) + B sin w(t-t0) + c + b sin(omega t)
    a_coef = x0 - c - b * math.sin(omega * t0)
    b_coef = (v0 - b * omega * math.cos(omega * t0)) / w
    tau = t - t0
    x = a_coef * math.cos(w * tau) + b_coef * math.sin(w * tau) + c + b * math.sin(omega * t)
    v = -a_coef * w * math.sin(w * tau) + b_coef * w * math.cos(w * tau) + b * omega * math.cos(omega * t)
    return x, v


def test_forced_leave_rest_and_velocity_zero_have_closed_forms(build):
    """A(t) = Q1 sin(t) - K1 x0 reaches mu_s g at t = arcsin((K1 x0 + mu_s g)/Q1); the forced
    flow that follows is a closed form whose velocity zero is found by bisection."""
    x0, q = 0.5, 5.0
    case = build(4.0, initial=(0.0, x0, 0.0, 0.0, 0.0), Q1=q, Omega=1.0, mu_s=0.25)
    events = simulate(case).events
    m1 = events[events.mass == 1].reset_index(drop=True)
    t_leave = math.asin((4.0 * x0 + 0.25 * 9.8) / q)
    assert m1.loc[0, "kind"] == "sliding_vanish"
    assert m1.loc[0, "t"] == pytest.approx(t_leave, abs=1e-10)
    assert m1.loc[0, "to_domain"] == 1
    assert m1.loc[0, "G0_alpha"] == pytest.approx(0.0, abs=1e-9)  # the flow barrier G-function

    def velocity(t):
        return forced_position(t, t_leave, x0, 0.0, 1, 2.0, q, 1.0, 0.98)[1]

    t_zero = brentq(velocity, t_leave + 0.1, t_leave + 2.5, xtol=1e-14)
    assert m1.loc[1, "t"] == pytest.approx(t_zero, abs=1e-9)
    x_zero = forced_position(t_zero, t_leave, x0, 0.0, 1, 2.0, q, 1.0, 0.98)[0]
    assert m1.loc[1, "x1"] == pytest.approx(x_zero, abs=1e-9)


def test_turning_short_of_the_right_stop_is_reported_as_grazing(build):
    """x'' = -4 x - mu_k g from x = 0 with v0 chosen so that the turning point is 0.5 mm short of
    x1 = d1 = 1: rule 6 reports grazing of ∂Ω13(1) at the velocity zero, t = atan2(...)/w."""
    w, c, gap = 2.0, 0.1 * 9.8 / 4.0, 5e-4
    amplitude = 1.0 + c - gap
    v0 = w * math.sqrt(amplitude**2 - c**2)
    case = build(1.0, initial=(0.0, 0.0, v0, -5.0, 0.0), d1=1.0, d=100.0)
    events = simulate(case).events.query("mass == 1")
    t_turn = math.atan2(v0 / w, c) / w  # x = -c + c cos(w t) + (v0/w) sin(w t) peaks here
    grazing = events[events.kind == "grazing"]
    assert len(grazing) == 1
    row = grazing.iloc[0]
    assert row.boundary == "∂Ω13(1)" and row.theorem == "Def. 5.2" and row.equation == "(5.6)"
    assert row.from_domain == row.to_domain == 1  # touched in Omega_1, as it reached v1 = 0
    assert row.t == pytest.approx(t_turn, abs=1e-9)
    assert row.distance == pytest.approx(gap, abs=1e-9)
    assert "right_contact_onset" not in set(events.kind)
    # and with a smaller reporting distance it is not called grazing
    assert "grazing" not in set(simulate(case, grazing_displacement_tolerance=1e-4).events.kind)
