"""A friction chain's orbit followed through folds (issue 52: oscillator/orbits/chain_branch.py):
a hardening oscillator's branch turns twice, its stability changes exactly there, and it passes
three times between the folds; up and down the same folds; a linear chain's branch is its closed
form; the refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

import oscillator
from oscillator.errors import InputError
from oscillator.model.chains import FrictionChain
from oscillator.orbits.chain_branch import continue_chain_orbit
from oscillator.orbits.chain_orbits import find_chain_orbit
from test_chain_orbits import OMEGA, linear_chain


def hardening() -> FrictionChain:
    """``x'' + 0.1 x' + x + 0.4 x^3 = 0.25 sin(Omega t)``: its resonance bends to the right."""
    return FrictionChain(Omega=0.8).mass("m", 1.0).spring("m", k=1.0, k3=0.4).damper("m", c=0.1).force("m", Q=0.25)


@pytest.fixture(scope="module")
def branches():
    up = continue_chain_orbit(hardening(), param="Omega", start=0.8, stop=1.6, step=0.1, transient=200)
    down = continue_chain_orbit(hardening(), param="Omega", start=1.6, stop=0.8, step=0.1, transient=200)
    return up, down


def test_the_hardening_branch_turns_twice_and_changes_stability_at_each_fold(branches):
    """Two folds, the upper first; the points' stability flips exactly at the fold points (a
    multiplier through +1); between the folds the branch passes 1.3 three times: large and stable,
    unstable, small and stable, in that order; followed down, the same folds (1e-4)."""
    up, down = branches
    assert up.ended == "the end of the span" and list(up.folds.kind) == ["fold", "fold"]
    upper, lower = up.folds.Omega
    assert 1.3 < upper < 1.5 and 1.1 < lower < 1.3 and lower < upper
    stable = up.points.stable.to_numpy()
    flips = np.flatnonzero(stable[1:] != stable[:-1])
    assert flips.tolist() == up.folds.point.tolist()
    side = np.sign(up.points.Omega.to_numpy() - 1.3)
    crossings = np.flatnonzero(side[1:] != side[:-1])
    assert len(crossings) == 3 and stable[crossings].tolist() == [True, False, True]
    sizes = up.points["x_pp:m"].to_numpy()[crossings]
    assert sizes[0] > sizes[1] > sizes[2]
    np.testing.assert_allclose(sorted(down.folds.Omega), sorted(up.folds.Omega), rtol=0, atol=1e-4)


def test_every_point_of_the_branch_is_an_orbit(branches):
    """Newton from a branch point's state at its value returns it at once (1e-8)."""
    up, _ = branches
    for k in (0, len(up.points) // 2, len(up.points) - 2):
        row = up.points.iloc[k]
        state = row[["x:m", "v:m"]].to_numpy(float)
        again = find_chain_orbit(hardening().with_values({"Omega": float(row.Omega)}), state, transient=0)
        np.testing.assert_allclose(again.state, state, rtol=0, atol=1e-8)
        assert again.iterations <= 1


def test_a_linear_chains_branch_is_its_closed_form():
    """``oscillator.continue_orbit(chain, ...)``: every point's amplitudes ``x_pp / 2`` are
    ``|X(Omega)|`` (1e-9), no fold, no change of stability."""
    branch = oscillator.continue_orbit(linear_chain(), param="Omega", start=OMEGA, stop=1.5, transient=5)
    assert branch.bifurcations.empty and branch.points.stable.all()
    mass, damping = np.diag([1.0, 0.5]), np.diag([0.1, 0.05])
    stiffness = np.array([[3.0, -1.0], [-1.0, 1.0]])
    for _, row in branch.points.iterrows():
        w = float(row.Omega)
        amplitude = np.abs(np.linalg.solve(stiffness - w**2 * mass + 1j * w * damping, [1.0, 0.0]))
        assert math.isclose(row["x_pp:a"] / 2, amplitude[0], rel_tol=1e-9)
        assert math.isclose(row["x_pp:b"] / 2, amplitude[1], rel_tol=1e-9)


def test_what_the_continuation_cannot_take_is_refused():
    with pytest.raises(InputError, match="did you mean 'Omega'"):
        continue_chain_orbit(hardening(), param="Omegaa", start=0.8, stop=1.6)
    with pytest.raises(InputError, match="must differ"):
        continue_chain_orbit(hardening(), param="Omega", start=0.8, stop=0.8)
