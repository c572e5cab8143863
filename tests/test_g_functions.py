"""First-order G-functions are the exact time derivatives of the 0th-order ones along the flow.

Each G^(1) (Definitions 5.1-5.4) is compared with a central difference of G^(0) along the mode's
own flow (integrated with SciPy's DOP853 at rtol 1e-13), Richardson-extrapolated to O(h^4).
"""

import itertools

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from oscillator import Mode, load_case
from oscillator.model.fields import kinetic_threshold, state_derivative, static_threshold
from oscillator.model.g_functions import displacement_g, flow_barrier_g, velocity_g

PARAMS = load_case("instance-3").parameters.replace(Q1=7.0, phi1=0.4, phi2=1.1, P1=0.3, P2=0.2)
H = 1e-3
MODES = [
    Mode.from_signs(s1, s2, left=left, right=right)
    for s1, s2, left, right in itertools.product((1, -1, 0), (1, -1, 0), (False, True), (False, True))
]


def flow(mode, t, y, dt):
    """The state a time ``dt`` along the mode's flow from ``(t, y)``."""
    if dt == 0:
        return np.asarray(y)
    sol = solve_ivp(
        lambda s, u: state_derivative(s, u, PARAMS, mode),
        (t, t + dt),
        y,
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
    )
    return sol.y[:, -1]


def central_difference(g0, mode, t, y):
    def diff(h):
        return (g0(t + h, flow(mode, t, y, h)) - g0(t - h, flow(mode, t, y, -h))) / (2 * h)

    return (4 * diff(H / 2) - diff(H)) / 3


def state_for(mode, rng):
    y = rng.uniform(-2, 2, size=4)
    for mass in (1, 2):
        y[2 * mass - 1] = mode.sign(mass) * rng.uniform(0.2, 2.0)
    return y


@pytest.mark.parametrize("mode", MODES, ids=str)
def test_velocity_g1_is_the_derivative_of_g0(mode):
    rng = np.random.default_rng(abs(hash((mode.domain1, mode.domain2, mode.left, mode.right))) % 2**32)
    t, y = rng.uniform(0, 5), state_for(mode, rng)
    for mass in (1, 2):
        s = mode.sign(mass)
        if not s:
            continue
        g0, g1 = velocity_g(t, y, PARAMS, mode, mass, s)
        numeric = central_difference(
            lambda tt, yy, mass=mass, s=s: velocity_g(tt, yy, PARAMS, mode, mass, s)[0], mode, t, y
        )
        assert g1 == pytest.approx(numeric, rel=1e-8, abs=1e-8)
        assert g0 == pytest.approx(state_derivative(t, y, PARAMS, mode)[2 * mass - 1])


@pytest.mark.parametrize("mode", [m for m in MODES if 0 in (m.domain1, m.domain2)], ids=str)
def test_flow_barrier_g1_is_the_derivative_of_g0(mode):
    rng = np.random.default_rng(7)
    t, y = rng.uniform(0, 5), state_for(mode, rng)
    for mass in (1, 2):
        if not mode.resting(mass):
            continue
        for side in (1, -1):
            _, g1 = flow_barrier_g(t, y, PARAMS, mode, mass, side)
            numeric = central_difference(
                lambda tt, yy, mass=mass, side=side: flow_barrier_g(tt, yy, PARAMS, mode, mass, side)[0], mode, t, y
            )
            assert g1 == pytest.approx(numeric, rel=1e-8, abs=1e-8)
            # the two sides differ by twice the static threshold
        plus, minus = (
            flow_barrier_g(t, y, PARAMS, mode, mass, 1)[0],
            flow_barrier_g(t, y, PARAMS, mode, mass, -1)[0],
        )
        assert minus - plus == pytest.approx(2 * static_threshold(PARAMS, mass))


@pytest.mark.parametrize("mode", MODES[:12], ids=str)
def test_displacement_g1_is_the_derivative_of_g0(mode):
    rng = np.random.default_rng(11)
    t, y = rng.uniform(0, 5), state_for(mode, rng)
    for boundary in ("right", "left"):
        _, g1 = displacement_g(t, y, PARAMS, mode, boundary)
        numeric = central_difference(
            lambda tt, yy, boundary=boundary: displacement_g(tt, yy, PARAMS, mode, boundary)[0], mode, t, y
        )
        assert g1 == pytest.approx(numeric, rel=1e-8, abs=1e-8)


def test_velocity_g_across_a_boundary_differs_by_twice_the_kinetic_threshold():
    mode = Mode.from_signs(1, -1, left=False, right=False)
    y = np.array([0.5, 0.0, 1.0, -0.3])
    here = velocity_g(0.3, y, PARAMS, mode, 1, 1)[0]
    across = velocity_g(0.3, y, PARAMS, mode, 1, -1)[0]
    assert across - here == pytest.approx(2 * kinetic_threshold(PARAMS, 1))
