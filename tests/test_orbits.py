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
from oscillator import InputError, Reason, resolve_case
from oscillator.model.events import EventKind
from oscillator.model.phase_space import Mode
from oscillator.model.saltation import elementary_switches
from oscillator.orbits.continuation import continue_orbit
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
    assert orbit.signature.count((2, EventKind.SLIDING_ONSET)) == 2
    assert orbit.stable and np.max(np.abs(orbit.multipliers)) < 1
    image = period_map(orbit.case, orbit.section, orbit.state, derivative=False)
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


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda: find_orbit("instance-1", period=0), "period"),
        (lambda: find_orbit("instance-1", period=1001), "period"),  # a motion to simulate, not shoot
        (lambda: find_orbit("instance-1", period=True), "period"),
        (lambda: find_orbit("instance-1", guess=(1.0, 2.0)), "guess"),
        (lambda: find_orbit("instance-1", guess="abcd"), "guess"),
        (lambda: find_orbit("instance-1", guess=(1.0, 2.0, "x", 4.0)), "guess"),
        (lambda: find_orbit("instance-1", tol="x"), "tol"),
        (lambda: find_orbit("instance-1", tol=0), "tol"),
        (lambda: find_orbit("instance-1", tol=-1), "tol"),
        (lambda: find_orbit("instance-1", tol=float("nan")), "tol"),
        (lambda: find_orbit("instance-1", max_iterations=0), "max_iterations"),
        (lambda: find_orbit("instance-1", transient=-1), "transient"),
        (lambda: find_orbit("instance-1", section=1.5), "guess"),  # another section needs a guess
        (lambda: find_orbit("instance-1", section="1.5", guess=(0, 0, 0, 0)), "section"),
        (lambda: continue_orbit("instance-1", param="nope", start=1, stop=2), "param"),
        (lambda: continue_orbit("instance-1", param="Q2", start=1, stop=1), "stop"),
        (lambda: continue_orbit("instance-1", param="Q2", start=71.5, stop=np.nextafter(71.5, 72)), "stop"),
        (lambda: continue_orbit("instance-1", param="Q2", start="71.5", stop=70.5), "start"),
        (lambda: continue_orbit("instance-1", param="Q2", start=71.5, stop=1e308), "stop"),
        (lambda: continue_orbit("instance-1", param="mu_s", start=0.2, stop=0.05), "stop"),  # below mu_k
        (lambda: continue_orbit("instance-1", param="Omega", start=1.6, stop=0), "stop"),
        (lambda: continue_orbit("instance-1", param="m1", start=1, stop=-1), "stop"),
        (lambda: continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5, Q2=3), "Q2"),
        (lambda: continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5, step=True), "step"),
        (lambda: continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5, step=1e-300), "step"),
        (lambda: continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5, locate_tol=0), "locate_tol"),
        (lambda: continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5, locate_tol=-1), "locate_tol"),
        (lambda: continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5, progress="x"), "progress"),
        (lambda: continue_orbit("instance-1", param="Q2", start=71.5, stop=70.5, max_points=1), "max_points"),
    ],
)
def test_bad_orbit_input_is_refused_naming_the_argument(call, field):
    """Each misuse: the library's InputError naming the argument, before anything runs (none of
    these hangs, computes, or raises NumPy's or Python's own error)."""
    with pytest.raises(InputError) as refused:
        call()
    assert refused.value.field == field


def test_t0_moves_the_case_s_start_and_section_names_the_section():
    """``t0`` is the case's start time (as for ``simulate``), never the orbit's section; a new
    start without an end keeps the run's length."""
    moved = resolve_case("instance-1", t0=1.91)
    assert moved.initial.t0 == 1.91 and abs(moved.t_end - (1.9 + 0.91)) < 1e-12
    period = 2 * np.pi / 1.85
    orbit = find_orbit("instance-1", Omega=1.85, t0=1.0 + period)  # the same section, a period later
    assert orbit.section == 1.0 + period
    np.testing.assert_allclose(orbit.state, find_orbit("instance-1", Omega=1.85).state, atol=1e-7)


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


def returns(case, y, periods):
    """Poincaré points of the simulated motion from ``y`` at the case's section."""
    points = [np.asarray(y, dtype=float)]
    for _ in range(periods):
        points.append(period_map(case, case.initial.t0, points[-1], derivative=False).end)
    return np.array(points)


def test_continuation_finds_the_gap_at_the_top_of_the_omega_sliding_window():
    """Up in Omega, the resting period-1 orbit ends at 1.6097374 with a rest of finite length,
    and the non-sliding orbit begins only at 1.6097413, the window's end that ``locate`` finds by
    brute force: in between no period-1 orbit exists (the motion is period-3).  Each end is
    checked by simulation 2e-8 inside and outside: inside, the motion started on the end's orbit
    stays on it; outside, it leaves."""
    branch = continue_orbit("instance-1", param="Omega", start=1.60973, stop=1.60975, step=0.5)
    assert branch.complete and branch.points.stable.all()
    first, last = branch.bifurcations.itertuples()
    assert first.after == "" and last.before == ""  # the two ends of a gap
    assert first.before.count("sliding_onset") == 1 and "sliding" not in last.after
    assert np.isnan(first.jump) and np.isnan(last.jump)
    assert abs(last.Omega - 1.6097413) < 1e-7 and 1e-6 < last.Omega - first.Omega < 1e-5
    for row, inside in ((first, -2e-8), (last, 2e-8)):
        state = [row.x1, row.v1, row.x2, row.v2]
        stays = returns(resolve_case("instance-1", Omega=row.Omega + inside, rtol=1e-12, atol=1e-12), state, 30)
        leaves = returns(resolve_case("instance-1", Omega=row.Omega - inside, rtol=1e-12, atol=1e-12), state, 30)
        assert np.max(np.abs(stays - stays[0])) < 1e-6
        assert np.max(np.abs(leaves[-10:] - stays[0])) > 1e-4
    assert branch.points.piece.iloc[-1] == branch.points.piece.iloc[0] + 1


def test_going_up_in_q2_the_resting_orbit_ends_where_simulation_says():
    """The resting orbit, continued up in Q2, ends at 1e-8 from where the simulated motion stops
    resting: started from an orbit of the branch 1e-3 below the end, the motion still rests twice
    a period 2e-8 below it and not at all 2e-8 above.  The two orbits coexist in between the
    two directions' ends (hysteresis)."""
    branch = continue_orbit("instance-1", param="Q2", start=71.0, stop=71.3, step=0.25)
    (row,) = branch.bifurcations.itertuples()
    assert row.before.count("sliding_onset") == 2 and "sliding" not in row.after and row.jump > 1e-3
    assert 71.1577416 + 1e-3 < row.Q2 < 71.18
    inside = branch.points[branch.points.Q2 < row.Q2 - 1e-3].iloc[-1]
    start = inside[["x1", "v1", "x2", "v2"]].to_numpy(float)
    for offset, rests in ((-2e-8, 2), (2e-8, 0)):
        case = resolve_case("instance-1", Q2=row.Q2 + offset, rtol=1e-12, atol=1e-12)
        settled = returns(case, start, 40)[-1]
        image = period_map(case, case.initial.t0, settled, derivative=False)
        assert np.max(np.abs(image.end - settled)) < 1e-8
        assert (image.events.kind == "sliding_onset").sum() == rests


def test_the_cyclic_signature_is_each_mass_s_own_cycle_of_switches():
    """Neither where the section cuts the orbit nor how the masses' events interleave changes
    the signature; a mass's own cycle of switches does."""
    from oscillator.orbits.signature import signature_of

    def signature(events):
        return str(signature_of([(t, mass, EventKind(kind)) for t, mass, kind in events], 2.0))

    a = signature([(0.2, 1, "passable"), (0.7, 2, "sliding_onset"), (0.9, 2, "sliding_vanish"), (1.5, 2, "passable")])
    rotated = signature([(0.1, 2, "sliding_vanish"), (0.6, 2, "passable"), (1.3, 1, "passable"),
                         (1.8, 2, "sliding_onset")])  # fmt: skip
    on_section = signature([(0.0, 2, "passable"), (0.5, 1, "passable"), (1.0, 2, "sliding_onset"),
                            (1.2, 2, "sliding_vanish"), (1.2, 1, "grazing"), (2.0, 2, "passable")])  # fmt: skip
    interleaved = signature([(0.2, 2, "passable"), (0.7, 2, "sliding_onset"), (0.9, 2, "sliding_vanish"),
                             (1.5, 1, "passable")])  # fmt: skip
    assert a == rotated == on_section == interleaved == "m1: passable; m2: passable, sliding_onset, sliding_vanish"
    extra_pair = signature([(0.2, 1, "passable"), (0.5, 2, "passable"), (0.6, 2, "passable"),
                            (0.7, 2, "sliding_onset"), (0.9, 2, "sliding_vanish"), (1.5, 2, "passable")])  # fmt: skip
    assert extra_pair != a and signature([]) == "m1: none; m2: none"


#: m1 as a hardening (Duffing) oscillator with light friction, the stops out of reach: its
#: resonance curve bends over, so the period-1 branch in Omega folds twice.
DUFFING = {"mu_k": 0.01, "mu_s": 0.015, "P1": 0.0, "P2": 0.0, "K1": 1.0, "K2": 0.1, "C1": 0.1, "C2": 0.0,
           "Q1": 0.6, "Q2": 0.4, "K4": 1.0, "K5": 0.0, "C4": 0.1, "C5": 0.0, "d": 20.0, "d1": 20.0, "x1": 0.0,
           "x2": 0.0}  # fmt: skip


def test_continuation_passes_around_the_two_folds_of_a_hardening_resonance():
    """Up in Omega the branch climbs the resonance's upper side, turns at a fold, comes back
    unstable, turns at a second fold and goes on: at each fold a multiplier is 1; between the
    folds three orbits coexist, and simulation confirms which are stable."""
    branch = continue_orbit("instance-1", param="Omega", start=1.1, stop=1.7, step=0.25, **DUFFING)
    assert branch.complete and branch.points.Omega.iloc[-1] == 1.7
    assert list(branch.bifurcations.kind) == ["fold", "fold"]
    upper, lower = branch.bifurcations.Omega
    assert 1.2 < lower < upper < 1.45
    for row in branch.bifurcations.itertuples():
        orbit = find_orbit("instance-1", guess=(row.x1, row.v1, row.x2, row.v2), Omega=row.Omega, **DUFFING)
        assert np.min(np.abs(orbit.multipliers - 1.0)) < 1e-3

    omega = 0.5 * (lower + upper)
    lam = branch.points.Omega.to_numpy()
    crossings = np.flatnonzero(np.diff(np.sign(lam - omega)) != 0)
    assert len(crossings) == 3
    case = resolve_case("instance-1", Omega=omega, rtol=1e-12, atol=1e-12, **DUFFING)
    for k, stable in zip(crossings, (True, False, True), strict=True):
        a, b = branch.points.iloc[k], branch.points.iloc[k + 1]
        w = (omega - a.Omega) / (b.Omega - a.Omega)
        guess = [(1 - w) * a[name] + w * b[name] for name in ("x1", "v1", "x2", "v2")]
        orbit = find_orbit(case, guess=guess)
        assert orbit.stable is stable and bool(a.stable) is stable
        after = returns(case, orbit.state + 1e-3, 60)[-1]
        assert bool(np.max(np.abs(after - orbit.state)) < 1e-6) is stable


#: m1 as a bilinear oscillator: a free spring and a stiff one-sided stop at x1 = 0 (K6), no
#: friction; m2 a damped linear oscillator far from it.
BILINEAR = {"mu_k": 0.0, "mu_s": 0.0, "P1": 0.0, "P2": 0.0, "K1": 1.0, "K2": 0.0, "C1": 0.05, "C2": 0.0, "K6": 20.0,
            "d1": 0.0, "Q1": 1.0, "Q2": 0.4, "K4": 1.0, "K5": 0.0, "C4": 0.1, "C5": 0.0, "d": 50.0, "x1": -0.5,
            "x2": 0.0}  # fmt: skip


def test_continuation_locates_the_period_doubling_of_an_oscillator_against_a_stop():
    """The period-1 orbit of m1 striking its stop loses stability through -1 (a multiplier of
    the located orbit is -1); beyond, the simulated motion is period-2."""
    branch = continue_orbit("instance-1", param="Omega", start=1.9, stop=2.5, step=0.5, **BILINEAR)
    assert branch.complete
    (row,) = branch.bifurcations.itertuples()
    assert row.kind == "period_doubling" and "right_contact_onset" in row.before
    orbit = find_orbit("instance-1", guess=(row.x1, row.v1, row.x2, row.v2), Omega=row.Omega, **BILINEAR)
    assert np.min(np.abs(orbit.multipliers + 1.0)) < 1e-3
    beyond = row.Omega + 0.01
    doubled = find_orbit("instance-1", period=2, Omega=beyond, **BILINEAR)
    single = find_orbit("instance-1", guess=doubled.state, Omega=beyond, **BILINEAR)
    assert doubled.stable and not single.stable
    half = period_map(doubled.case, doubled.section, doubled.state, derivative=False).end
    assert np.max(np.abs(half - doubled.state)) > 1e-2  # two distinct points: period 2, not 1


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


def test_near_a_branch_end_the_branch_keeps_its_own_orbit():
    """Up in Q2 to 2e-5 below the resting orbit's end (71.1702569), where the orbit without
    rest coexists: the branch ends on the resting orbit, with no bifurcation (it used to jump
    to the other orbit at its last point and report a sliding bifurcation there)."""
    branch = continue_orbit("instance-1", param="Q2", start=70.5, stop=71.1702369)
    assert branch.complete and branch.bifurcations.empty
    assert (branch.points.signature.str.count("sliding_onset") == 2).all()
    assert branch.points.Q2.iloc[-1] == 71.1702369


def test_newton_says_when_it_went_from_one_kind_of_motion_to_another():
    """A guess on the resting orbit's side at a Q2 where that orbit no longer exists: Newton
    converges to the orbit without rest, and says that it changed kind."""
    resting = find_orbit("instance-1", Q2=71.1)
    assert resting.signature.count((2, EventKind.SLIDING_ONSET)) == 2 and resting.note == ""
    other = find_orbit("instance-1", Q2=71.2, guess=resting.state)
    assert not any(kind.starts_rest for _, kind in other.signature)
    assert "another cycle of switches" in other.note and "sliding_onset" in other.note


def test_the_python_api_raises_interrupted_with_the_partial_branch():
    from oscillator import Interrupted, continue_orbit

    calls = []

    def progress(fraction):
        calls.append(fraction)
        if len(calls) == 2:
            raise KeyboardInterrupt

    with pytest.raises(Interrupted) as stopped:
        continue_orbit("instance-1", param="Q2", start=71.3, stop=71.0, step=0.1, progress=progress)
    branch = stopped.value.result
    assert branch.complete is False and branch.message.startswith("interrupted at Q2 = ")
    assert branch.reason is Reason.INTERRUPTED
    assert len(branch.points) == 3 and branch.points.Q2.iloc[0] == 71.3
