"""Periodic orbits: the monodromy matrix through every switch, Newton, continuation.

The monodromy matrix (variational equations and saltation matrices) is checked against central
finite differences of the map computed by the simulation itself, on constructed cases whose runs
pass every kind of switch (crossings, rest onset and release, both stops, rest while in
contact), and against ``expm(A T)`` on a linear case.
"""

import itertools

import numpy as np
import pytest
from scipy.linalg import expm

from conftest import random_case
from oscillator import InputError, resolve_case
from oscillator.model.phase_space import Mode
from oscillator.orbits.continuation import continue_orbit
from oscillator.orbits.saltation import elementary_switches
from oscillator.orbits.shooting import find_orbit, period_map

#: random_case seeds whose runs cross, rest, release, touch both stops and rest in contact
#: (tests/test_every_domain.py).
SEEDS = [1, 141, 145, 149, 179, 190, 200, 268]


def mode(s1, s2, *, left=False, right=False):
    return Mode.from_signs(s1, s2, left=left, right=right)


def finite_differences(case, t0, y0, periods, h=1e-5):
    """Central differences of the map; a resting start (v_i = 0) keeps its column exact (None)."""
    base = period_map(case, t0, y0, periods, derivative=False)
    columns = []
    for j in range(4):
        if y0[j] == 0.0:
            columns.append(None)
            continue
        e = np.zeros(4)
        e[j] = h * max(1.0, abs(y0[j]))
        plus = period_map(case, t0, y0 + e, periods, derivative=False)
        minus = period_map(case, t0, y0 - e, periods, derivative=False)
        assert plus.events.kind.tolist() == base.events.kind.tolist() == minus.events.kind.tolist()
        columns.append((plus.end - minus.end) / (2 * e[j]))
    return columns


@pytest.mark.parametrize("seed", SEEDS)
def test_monodromy_matches_finite_differences_through_every_kind_of_switch(seed):
    case = resolve_case(random_case(seed), rtol=1e-12, atol=1e-12)
    t0, y0 = case.initial.t0, np.array(case.initial.y)
    periods = max(1, round((case.t_end - t0) / case.parameters.period))
    exact = period_map(case, t0, y0, periods)
    assert len(exact.switches) > 5
    for j, column in enumerate(finite_differences(case, t0, y0, periods)):
        if column is not None:
            assert np.max(np.abs(column - exact.monodromy[:, j])) < 2e-5 + 1e-3 * np.max(np.abs(exact.monodromy))


def test_the_seeds_pass_every_kind_of_switch():
    kinds, states = set(), set()
    for seed in SEEDS:
        case = random_case(seed)
        periods = max(1, round((case.t_end - case.initial.t0) / case.parameters.period))
        image = period_map(case, case.initial.t0, np.array(case.initial.y), periods, derivative=False)
        kinds |= set(image.events.kind)
        states |= {mode.system_state for _, _, mode in image.switches}
    assert {"passable", "sliding_onset", "sliding_vanish", "left_contact_onset", "left_contact_release",
            "right_contact_onset", "right_contact_release"} <= kinds  # fmt: skip
    assert {"IV-a", "II-b", "II-c", "III-b", "III-c"} <= states  # both stops; rest in contact


def test_a_smooth_linear_case_has_the_closed_form_monodromy():
    """No friction, no stops, linear springs and dampers: P is affine and M = expm(A T)."""
    case = resolve_case("instance-1", mu_k=0, mu_s=0, P1=0, P2=0, K2=0, K5=0, C2=0, C5=0, d=1e3, d1=1e3)
    p = case.parameters
    a = np.array([[0, 1, 0, 0], [-p.K1 / p.m1, -p.C1 / p.m1, 0, 0], [0, 0, 0, 1], [0, 0, -p.K4 / p.m2, -p.C4 / p.m2]])
    orbit = find_orbit(case, tol=1e-11)
    assert np.max(np.abs(orbit.monodromy - expm(a * p.period))) < 1e-9
    assert orbit.iterations <= 2  # an affine map: one Newton step
    assert len(orbit.events) >= 4  # the velocity crossings are switches with no jump


def test_newton_converges_quadratically():
    first = find_orbit("instance-1", Omega=1.85)
    guess = first.state + np.array([0.05, -0.05, 0.03, 0.04])
    orbit = find_orbit("instance-1", Omega=1.85, guess=guess, tol=1e-11)
    r = orbit.history
    assert len(r) >= 3 and r[-1] < 1e-10
    for before, after in itertools.pairwise(r[:-1]):  # the last is at rounding level
        assert after < 1.0 * before**2
    np.testing.assert_allclose(orbit.state, first.state, atol=1e-8)


def test_the_orbit_is_a_fixed_point_of_the_simulation():
    orbit = find_orbit("instance-1", Q2=70.5)
    assert orbit.signature.count("sliding_onset") == 2
    assert orbit.stable and np.max(np.abs(orbit.multipliers)) < 1
    image = period_map(orbit.case, orbit.t0, orbit.state, derivative=False)
    assert np.max(np.abs(image.end - orbit.state)) < 1e-9
    # m2 rests: its velocity is constrained there, so one multiplier is zero
    assert np.min(np.abs(orbit.multipliers)) < 1e-12


@pytest.mark.parametrize(
    ("before", "after", "expected"),
    [
        (
            Mode.from_signs(1, 1, left=False, right=False),
            Mode.from_signs(-1, -1, left=False, right=False),
            ["v1", "v2"],
        ),
        (Mode.from_signs(1, 0, left=False, right=False), Mode.from_signs(1, 1, left=True, right=False), ["left"]),
        (Mode.from_signs(1, 0, left=False, right=False), Mode.from_signs(1, 1, left=False, right=False), ["barrier2"]),
        (
            Mode.from_signs(1, -1, left=False, right=False),
            Mode.from_signs(0, -1, left=False, right=True),
            ["right", "v1"],
        ),
    ],
)
def test_a_switch_splits_into_one_crossing_per_boundary(before, after, expected):
    steps = elementary_switches(before, after)
    assert [name for _, _, name in steps] == expected
    assert steps[0][0] == before and steps[-1][1] == after


def test_bad_orbit_input_is_refused():
    with pytest.raises(InputError, match="period"):
        find_orbit("instance-1", period=0)
    with pytest.raises(InputError, match="guess"):
        find_orbit("instance-1", guess=(1.0, 2.0))
    with pytest.raises(InputError, match="param"):
        continue_orbit("instance-1", param="nope", start=1, stop=2)
    with pytest.raises(InputError, match="start and stop"):
        continue_orbit("instance-1", param="Q2", start=1, stop=1)


def test_continuation_locates_where_sliding_sets_in_on_the_q2_branch():
    """The non-sliding period-1 orbit of Instance 1's system, continued in Q2 from 71.5 down to
    70.5: a rest interval appears where ``locate`` finds the sweep's sliding bifurcation by brute
    force (71.1577416 at rtol 1e-12, docs/bifurcation.md)."""
    branch = continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5, step=0.1)
    assert branch.complete
    assert branch.points.Q2.iloc[0] == 71.5 and branch.points.Q2.iloc[-1] == 70.5
    (row,) = branch.bifurcations.itertuples()
    assert row.kind == "sliding_vanish"  # named as Q2 increases: the rest interval vanishes above
    assert "sliding" not in row.before and row.after.count("sliding_onset") == 2
    assert abs(row.Q2 - 71.1577416) < 1e-6
    assert row.jump > 1e-6  # static > kinetic: the rest interval appears with a finite length
    assert branch.points.stable.all()


def test_continue_writes_its_tables_figures_and_an_escaped_report(tmp_path):
    """`oscillator continue` on a case file whose name is markup: the reports show it as text."""
    from pathlib import Path

    from oscillator.cli.app import main

    hostile = tmp_path / "<img src=x onerror=alert(1)>*x*.toml"
    hostile.write_text((Path(__file__).parents[1] / "cases" / "instance-1.toml").read_text(encoding="utf-8"))
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exit_:
        main(["continue", str(hostile), "--param", "Q2", "--from", "71.3", "--to", "71.0", "--step", "0.5",
              "--out", str(out), "-q"])  # fmt: skip
    assert exit_.value.code == 0
    assert {p.name for p in out.iterdir()} >= {"branch.parquet", "bifurcations.parquet", "report.md", "report.html"}
    assert {p.name for p in (out / "figures").iterdir()} == {"branch.png", "multipliers.png"}
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "<img src=x" not in html and "&lt;img src=x onerror=alert(1)&gt;" in html
    assert "\\<img src=x onerror=alert(1)\\>\\*x\\*" in (out / "report.md").read_text(encoding="utf-8")
