"""The compiled re-integration of a smooth piece (issue 53, oscillator.orbits.pieces) against SciPy's
``solve_ivp(method="DOP853")`` with the same field, which it replaces: the same steps, the same end,
the same dense output and the same extrema, on the article's pieces and on a chain's."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from oscillator import find_orbit, load_system
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.simulate import simulate
from oscillator.model.fields import C3, K3, coefficients
from oscillator.model.kernels import rates
from oscillator.orbits.chain_tangents import NumberData
from oscillator.orbits.pieces import (
    ARTICLE_PIECE,
    CHAIN_PIECE,
    article_data,
    chain_data,
    chain_tangent_rates,
    integrate_piece,
)
from oscillator.orbits.sensitivity import columns_of
from oscillator.orbits.tangent import INTEGRALS, tangent_rates

TOL = 1e-12


def _article_pieces():
    """The pieces of one period of Instance 1's orbit at Omega = 1.6 (stick, slip and contacts)."""
    orbit = find_orbit("instance-1", Omega=1.6)
    run = simulate(orbit.one_period(), save=SaveAt(steps=False, segments=True))
    return orbit.case.parameters, [s for s in run.segments if s.t1 > s.t0]


def _flags(mode):
    return mode.sign(1), mode.sign(2), mode.left, mode.right


def _extremum_functions(c, flags):
    s1, s2, left, right = flags

    def function(which):
        def event(t, y):
            r = rates(t, y[0], y[1], y[2], y[3], c, s1, s2, left, right)
            if which == 2:
                return c[K3] * (y[1] - y[3]) + c[C3] * (r[1] - r[3]) if left else 1.0
            return r[2 * which + 1] if (s1, s2)[which] else 1.0

        return event

    return [function(which) for which in range(3)]


@pytest.mark.parametrize("params", [(), ("d1", "Omega")], ids=["response", "tangents"])
def test_an_article_piece_takes_scipys_steps_to_its_end_dense_output_and_extrema(params):
    p, pieces = _article_pieces()
    c, columns = coefficients(p), columns_of(params)
    k, found = len(columns), 0
    assert len(pieces) >= 4
    for segment in pieces:
        flags = _flags(segment.mode)
        start = np.concatenate([segment.y0, np.zeros(INTEGRALS), np.ones(4 * k), np.zeros(INTEGRALS * k)])

        def field(t, y, flags=flags):
            out = np.empty_like(y)
            tangent_rates(t, y, c, columns, *flags, out)
            return out

        span = (segment.t0, segment.t1)
        expected = solve_ivp(field, span, start, method="DOP853", rtol=TOL, atol=TOL, dense_output=True,
                             events=_extremum_functions(c, flags))  # fmt: skip
        data = article_data(flags, columns, c)
        ours = integrate_piece(ARTICLE_PIECE, data, span, start, rtol=TOL, atol=TOL, dense=True)
        assert abs(len(ours.starts) - (len(expected.t) - 1)) <= 1  # the step control's rounding may differ
        scale = 1.0 + np.abs(expected.y).max(axis=1)
        assert np.max(np.abs(ours.end - expected.y[:, -1]) / scale) < 1e-11
        inside = np.linspace(*span, 41)
        assert np.max(np.abs(ours(inside) - expected.sol(inside)) / scale[:, None]) < 1e-11
        for which, times in enumerate(expected.t_events):
            assert np.sort(ours.times[ours.which == which]) == pytest.approx(np.sort(times), abs=1e-10)
            found += len(times)
    assert found >= 2  # the speeds' extrema inside the pieces were there to find


def test_a_chain_piece_takes_scipys_steps_with_its_tangents():
    """The hardening oscillator (a cubic spring: the Jacobian changes along the piece) over two
    seconds, with its monodromy block and the derivative in the spring's cubic coefficient."""
    chain = load_system(Path(__file__).resolve().parents[1] / "docs" / "systems" / "hardening.toml")
    params = tuple(name for name in chain.parameter_names() if name.endswith(".k3"))
    assert len(params) == 1
    data = NumberData(chain, params)
    n = data.arrays.size
    mode = np.zeros(len(data.arrays.kind))
    d, plus, minus = data.of(mode)
    start = np.concatenate([np.arange(1.0, n + 1) / n, np.hstack([np.eye(n), np.zeros((n, 1))]).ravel()])

    def field(t, y):
        out = np.empty_like(y)
        chain_tangent_rates(t, y, d, plus, minus, data.steps, out)
        return out

    expected = solve_ivp(field, (0.0, 2.0), start, method="DOP853", rtol=1e-11, atol=1e-12, dense_output=True)
    ours = integrate_piece(CHAIN_PIECE, chain_data(d, plus, minus, data.steps), (0.0, 2.0), start, rtol=1e-11,
                           atol=1e-12, dense=True)  # fmt: skip
    assert abs(len(ours.starts) - (len(expected.t) - 1)) <= 1 and len(ours.starts) > 5
    # Psi's columns are central differences at a step of 1e-6: rounding of 1e-16 in the state is
    # 1e-10 in them, the state and Phi agree to the tolerance.
    np.testing.assert_allclose(ours.end, expected.y[:, -1], rtol=1e-9, atol=1e-11)
    phi = [0, 1, 2, 3, 5, 6]
    np.testing.assert_allclose(ours.end[phi], expected.y[phi, -1], rtol=1e-11, atol=1e-12)
    inside = np.linspace(0.0, 2.0, 23)
    np.testing.assert_allclose(ours(inside)[phi], expected.sol(inside)[phi], rtol=1e-11, atol=1e-12)
    assert not len(ours.which)  # a chain's pieces look for no extrema


def test_a_piece_of_no_length_is_its_start():
    start = np.arange(13.0)
    c = coefficients(find_orbit("instance-1").case.parameters)
    data = article_data((1, 1, False, False), np.zeros(0, np.int64), c)
    piece = integrate_piece(ARTICLE_PIECE, data, (2.0, 2.0), start, rtol=TOL, atol=TOL)
    assert np.array_equal(piece.end, start) and not len(piece.which)
    with pytest.raises(ValueError, match="dense output"):
        piece(2.0)
