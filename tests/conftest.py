"""Shared builders for constructed cases."""

import pytest

from oscillator import Case, InitialState, Parameters, SolverOptions

#: A system with every nonlinear and contact term off; stops far away.
LINEAR = dict(
    m1=1.0, m2=2.0, C1=0.0, C2=0.0, C3=0.0, C4=0.0, C5=0.0,
    K1=4.0, K2=0.0, K3=0.0, K4=2.0, K5=0.0, K6=0.0,
    mu_k=0.1, mu_s=0.2, d=1e6, d1=1e6, Q1=0.0, Q2=0.0, Omega=1.0,
    phi1=0.0, phi2=0.0, P1=0.0, P2=0.0, g=9.8,
)  # fmt: skip


def make_case(t_end, *, initial, name="constructed", options=None, **params):
    values = {**LINEAR, **params}
    return Case(
        name=name,
        parameters=Parameters(**values),
        initial=InitialState(*initial),
        t_end=t_end,
        options=options or SolverOptions(),
    )


@pytest.fixture
def build():
    return make_case
