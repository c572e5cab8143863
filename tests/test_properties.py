"""Invariants on random valid systems (hypothesis): labels, rest intervals, time order."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from conftest import make_case
from oscillator import simulate
from oscillator.model.fields import non_friction_force, static_threshold
from oscillator.model.phase_space import contacts_of_state, velocity_sign


def positive(lo, hi):
    """A float in [lo, hi]; magnitudes below 1e-100 (refused as below any physical scale) as 0."""
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False).map(lambda v: 0.0 if abs(v) < 1e-100 else v)


@st.composite
def systems(draw):
    p = {name: draw(positive(0.3, 3.0)) for name in ("m1", "m2")}
    p |= {name: draw(positive(0.0, 1.0)) for name in ("C1", "C2", "C3", "C4", "C5", "K2", "K5")}
    p |= {name: draw(positive(0.2, 5.0)) for name in ("K1", "K3", "K4", "K6")}
    p["mu_k"] = draw(positive(0.0, 0.3))
    p["mu_s"] = p["mu_k"] * draw(positive(1.0, 2.0))
    p |= {name: draw(positive(0.1, 2.5)) for name in ("d", "d1")}
    p |= {name: draw(positive(0.0, 15.0)) for name in ("Q1", "Q2")}
    p |= {name: draw(positive(0.0, 6.3)) for name in ("phi1", "phi2")}
    p |= {name: draw(positive(0.0, 0.5)) for name in ("P1", "P2")}
    p["Omega"] = draw(positive(0.5, 3.0))
    x1 = draw(positive(-1.5, 1.5))
    x2 = x1 + draw(positive(-1.0, 3.0))
    v1 = draw(st.one_of(st.just(0.0), positive(-3.0, 3.0)))
    v2 = draw(st.one_of(st.just(0.0), positive(-3.0, 3.0)))
    t_end = 2 * (2 * np.pi / p["Omega"])
    return make_case(t_end, initial=(0.0, x1, v1, x2, v2), **p)


@given(systems())
def test_invariants_hold_on_random_systems(case):
    result = simulate(case)
    p = case.parameters
    trajectory, events = result.trajectory, result.events

    # event and trajectory times never decrease
    assert np.all(np.diff(events.t) >= 0)
    assert np.all(np.diff(trajectory.t) >= 0)

    eps = 1e-7
    for row in trajectory.itertuples(index=False):
        left, right = contacts_of_state(row.system_state)
        # contact flags agree with the constraint functions (to the solver's accuracy)
        assert (row.x1 - p.d1 >= -eps) if right else (row.x1 - p.d1 <= eps)
        z = row.x1 - row.x2 + p.d
        assert (z <= eps) if left else (z >= -eps)
        forces = non_friction_force(row.t, (row.x1, row.v1, row.x2, row.v2), p, left, right)
        for mass, domain, v in ((1, row.domain1, row.v1), (2, row.domain2, row.v2)):
            if domain == 0:
                # at rest: v = 0 exactly and the force inside the static band
                assert v == 0.0
                assert abs(forces[mass - 1]) <= static_threshold(p, mass) * (1 + 1e-9) + 1e-9
            else:
                # the velocity sign is the domain's (v may be 0 at the instant of a switch)
                assert velocity_sign(mass, domain) * v >= -eps
        if row.domain1:
            assert (row.domain1 >= 5, row.domain1 in (3, 4, 7, 8)) == (left, right)
        if row.domain2:
            assert (row.domain2 >= 5) == left

    # every event row's domains are the article's
    assert set(events.from_domain[events.mass == 2]) | set(events.to_domain[events.mass == 2]) <= {0, 1, 2, 5, 6}
    assert np.isfinite(result.energy.residual)
