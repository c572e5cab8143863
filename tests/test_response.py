"""The response measures of a periodic motion (issue 38): against the linear oscillator's closed
form, against the run's own energy audit and events, and against the trajectory's samples."""

import math

import numpy as np
import pytest

from conftest import random_case
from oscillator import InputError, Response, find_orbit, resolve_case, response, simulate
from oscillator.analysis.intervals import rest_intervals
from oscillator.model.events import EventKind

#: Two linear oscillators side by side: no friction, no coupling, the stops far away.
LINEAR = dict(
    m1=1.0, m2=1.5, K1=2.0, K2=0.0, C1=0.1, C2=0.0, K3=0.0, C3=0.0, K4=1.0, K5=0.0, C4=0.2, C5=0.0, K6=1.0,
    mu_k=0.0, mu_s=0.0, P1=0.0, P2=0.0, d=1000.0, d1=1000.0, Q1=1.0, Q2=0.7, Omega=1.3, phi1=0.0, phi2=0.0,
)  # fmt: skip


def test_the_linear_oscillators_steady_response_is_the_closed_form():
    """``X = Q / sqrt((K - m W^2)^2 + (C W)^2)``: peaks +-X, RMS X / sqrt 2, peak speed W X, RMS
    acceleration W^2 X / sqrt 2, and pi C W X^2 lost in the damper and given by the force a period."""
    case = resolve_case("instance-1", **LINEAR)
    omega, t0 = LINEAR["Omega"], case.initial.t0
    state, amplitudes = [], []
    for m, k, c, q in ((1.0, 2.0, 0.1, 1.0), (1.5, 1.0, 0.2, 0.7)):
        amplitude, lag = q / math.hypot(k - m * omega**2, c * omega), math.atan2(c * omega, k - m * omega**2)
        state += [amplitude * math.sin(omega * t0 - lag), omega * amplitude * math.cos(omega * t0 - lag)]
        amplitudes.append(amplitude)
    measured = response(resolve_case(case, x1=state[0], v1=state[1], x2=state[2], v2=state[3]))
    for mass, amplitude in zip((1, 2), amplitudes, strict=True):
        m = measured.mass[mass]
        expected = {
            "x_max": amplitude,
            "x_min": -amplitude,
            "x_pp": 2 * amplitude,
            "x_rms": amplitude / math.sqrt(2),
            "v_peak": omega * amplitude,
            "a_rms": omega**2 * amplitude / math.sqrt(2),
            "rest": 0.0,
        }
        for name, value in expected.items():
            assert m[name] == pytest.approx(value, abs=1e-9), (mass, name)
    lost = math.pi * omega * (0.1 * amplitudes[0] ** 2 + 0.2 * amplitudes[1] ** 2)
    assert measured.energy["dampers"] == pytest.approx(lost, abs=1e-9)
    assert measured.energy["forcing"] == pytest.approx(lost, abs=1e-9)
    assert abs(measured.balance) < 1e-9
    assert all(value == 0.0 for stop in measured.contact.values() for value in stop.values())


@pytest.mark.parametrize("seed", [145, 200, 268, 1])
def test_the_measures_are_the_runs_own(seed):
    """Random systems with contacts, rests and re-sticking, over three forcing periods: the energies
    are the run's energy audit, the rests and contacts its events, the peaks bound every sample."""
    case = random_case(seed)
    p, periods = case.parameters, 3
    measured = response(case, periods)
    run = simulate(case, t_end=case.initial.t0 + periods * p.period)
    audit, events, rows = run.energy, run.events, run.trajectory
    e = measured.energy
    assert e["forcing"] * periods == pytest.approx(audit.forcing, rel=1e-7, abs=1e-8)
    assert e["friction"] * periods == pytest.approx(audit.friction, rel=1e-7, abs=1e-8)
    assert (e["dampers"] + e["contact"]) * periods == pytest.approx(audit.damping, rel=1e-7, abs=1e-8)
    assert e["feedback"] * periods == pytest.approx(audit.feedback, rel=1e-7, abs=1e-8)
    assert measured.balance * periods == pytest.approx(audit.E1 - audit.E0, abs=1e-7 * (1 + abs(audit.forcing)))
    span, t_from, t_to = periods * p.period, case.initial.t0, case.initial.t0 + periods * p.period
    for mass in (1, 2):
        resting = int(rows[f"domain{mass}"].iloc[0]) == 0
        rest = sum(b - a for a, b in rest_intervals(events, mass, resting, t_from, t_to)) / span
        m = measured.mass[mass]
        assert m["rest"] == pytest.approx(rest, abs=1e-9)
        x, v = rows[f"x{mass}"].to_numpy(), np.abs(rows[f"v{mass}"].to_numpy())
        assert m["x_min"] <= x.min() + 1e-9 and x.max() <= m["x_max"] + 1e-9
        assert v.max() <= m["v_peak"] + 1e-9 and m["v_peak"] <= v.max() * (1 + 1e-3) + 1e-9
    kinds = zip(events.kind, events["mass"], strict=True)
    onsets = [EventKind(k).contact_starts and EventKind(k).stands_for_event(int(m)) for k, m in kinds]
    total = measured.contact["right"]["onsets"] + measured.contact["left"]["onsets"]
    assert total * periods == sum(onsets)
    left, right = rows[rows.x1 - rows.x2 + p.d < 0], rows[rows.x1 > p.d1]  # in contact, by the geometry
    forces = {
        "left": np.abs(p.K3 * (left.x1 - left.x2 + p.d) + p.C3 * (left.v1 - left.v2)),
        "right": p.K6 * (right.x1 - p.d1),
    }
    for stop, force in forces.items():
        peak = measured.contact[stop]["force_peak"]
        assert (peak > 0) == (len(force) > 0)
        if len(force):
            assert force.max() <= peak + 1e-9 and peak <= force.max() * 1.01


def test_bad_periods_are_refused():
    from oscillator import InputError

    with pytest.raises(InputError, match="periods") as caught:
        response(resolve_case("instance-1"), 0)
    assert caught.value.field == "periods"


def test_an_orbit_with_a_rest_returns_its_energy():
    """Instance 1's orbit in which m2 rests twice a period: the energy balance closes to the
    integration's tolerance, and m2's rest and the contacts are the orbit's."""
    orbit = find_orbit("instance-1", Q2=71.165, guess=(3.0, 0.0, 6.0, 0.0), transient=60)
    measured = orbit.response()
    assert isinstance(measured, Response) and abs(measured.balance) < 1e-7 * measured.energy["forcing"]
    assert measured.mass[2]["rest"] > 0.0 and measured.mass[1]["rest"] == 0.0
    assert measured.mass[1]["x_pp"] > 0 and measured.mass[2]["x_max"] > measured.mass[2]["x_min"]
    flat = measured.columns()
    assert flat["rest_m2"] == measured.mass[2]["rest"] and "impact_max_left" in flat and "energy_forcing" in flat


def test_the_documented_example_prints_what_the_page_shows(capsys):
    """docs/orbits.md, section 6: its Python block prints the lines shown under it."""
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "orbits.md").read_text(encoding="utf-8")
    section = text.split("## 6. Response measures", 1)[1]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    shown = section.split("```text\n", 1)[1].split("```", 1)[0]
    exec(compile(code, "docs/orbits.md", "exec"), {})
    assert capsys.readouterr().out == shown


def den_hartog(m, k, friction, force, omega):
    """Den Hartog's (1931) steady motion without stops of ``m x'' + k x + F sgn(x') = P cos(W t)``:
    the half period with ``x' < 0`` solved exactly, ``x = A cos(wn t) + B sin(wn t) + F / k +
    P / (k - m W^2) cos(W t + phi)`` from ``(X0, 0)`` to ``(-X0, 0)``: four equations linear in
    ``A, B, X0, sin(phi)`` for a given ``cos(phi)``, and ``cos^2 + sin^2 = 1``.  The amplitude X0."""
    wn = math.sqrt(k / m)
    r, theta = force / (k - m * omega**2), wn * math.pi / omega
    matrix = np.array(
        [
            [1.0, 0.0, -1.0, 0.0],
            [0.0, wn, 0.0, -r * omega],
            [math.cos(theta), math.sin(theta), 1.0, 0.0],
            [-wn * math.sin(theta), wn * math.cos(theta), 0.0, r * omega],
        ]
    )
    u0 = np.linalg.solve(matrix, [-friction / k, 0.0, -friction / k, 0.0])
    u1 = np.linalg.solve(matrix, [-r, 0.0, r, 0.0])
    roots = np.roots([1 + u1[3] ** 2, 2 * u0[3] * u1[3], u0[3] ** 2 - 1])
    return max(abs(float((u0 + c * u1)[2])) for c in roots.real if abs(c) <= 1)


def test_den_hartogs_coulomb_oscillator_over_a_frequency_band():
    """Mass 1 alone with Coulomb friction (mu_s = mu_k) and no damper, m2 parked: along the
    continued branch over Omega in [1.2, 2.5] (continuous sliding) the amplitude is Den Hartog's to
    1e-8, symmetric, and friction takes 4 F X0 of the forcing's work a period."""
    from oscillator import continue_orbit

    friction = 0.1
    over = dict(
        m1=1.0, K1=1.0, K2=0.0, C1=0.0, C2=0.0, K3=0.0, C3=0.0, P1=0.0, P2=0.0, mu_k=friction / 9.8,
        mu_s=friction / 9.8, d=1e4, d1=1e4, Q1=1.0, Q2=0.0, Omega=1.2, phi1=0.0, phi2=0.0, x1=1.0, v1=0.0,
        x2=0.0, v2=0.0, K4=1.0, K5=0.0, C4=0.0, C5=0.0,
    )  # fmt: skip
    branch = continue_orbit(resolve_case("instance-1", **over), param="Omega", start=1.2, stop=2.5, transient=300)
    table = branch.responses()
    assert branch.complete and len(table) > 50 and table.Omega.min() == 1.2 and table.Omega.max() == 2.5
    exact = np.array([den_hartog(1.0, 1.0, friction, 1.0, omega) for omega in table.Omega])
    assert np.max(np.abs(table.x_max_m1 - exact)) < 1e-8
    assert np.max(np.abs(table.x_min_m1 + exact)) < 1e-8
    assert (table.rest_m1 == 0).all() and np.allclose(table.rest_m2, 1.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(table.energy_friction, 4 * friction * exact, rtol=1e-8)
    np.testing.assert_allclose(table.energy_forcing, table.energy_friction, rtol=1e-8)


def test_the_linear_oscillators_response_over_a_frequency_band():
    """The two linear oscillators along a branch over Omega in [1.6, 2.6], above both resonances:
    every point's peaks and RMS values are the closed form's to 1e-9."""
    from oscillator import continue_orbit

    case = resolve_case("instance-1", **(LINEAR | {"Omega": 1.6}))
    branch = continue_orbit(case, param="Omega", start=1.6, stop=2.6, transient=400)
    table = branch.responses()
    assert branch.complete and len(table) > 40
    for mass, (m, k, c, q) in ((1, (1.0, 2.0, 0.1, 1.0)), (2, (1.5, 1.0, 0.2, 0.7))):
        omega = table.Omega.to_numpy()
        amplitude = q / np.hypot(k - m * omega**2, c * omega)
        assert np.max(np.abs(table[f"x_max_m{mass}"] - amplitude)) < 1e-9
        assert np.max(np.abs(table[f"x_rms_m{mass}"] - amplitude / math.sqrt(2))) < 1e-9
        assert np.max(np.abs(table[f"v_peak_m{mass}"] - omega * amplitude)) < 1e-9


def test_the_atlas_impact_velocity_is_the_responses():
    """``features.impact_velocity`` (the atlas's column) reads the same onsets as the response:
    m1 hitting the right stop moved in to d1 = 3.5 once a period."""
    from oscillator import find_attractors
    from oscillator.attractors.features import impact_velocity

    found = find_attractors("instance-1", Q2=71.165, d1=3.5, transient=100, record=8)
    (attractor,) = [a for a in found.attractors if a.contacts]
    assert attractor.orbit is not None
    measured = attractor.orbit.response()
    assert measured.contact["right"]["onsets"] == 1.0 and measured.contact["left"]["onsets"] == 0.0
    assert impact_velocity(attractor.orbit.case, attractor) == pytest.approx(
        measured.contact["right"]["impact_max"], rel=1e-6
    )
    assert measured.contact["right"]["impact_max"] > 1.0


def test_the_atlas_colours_by_any_response_measure_it_was_computed_with(tmp_path):
    """``regime_atlas(..., measures=...)``: a column for each measure named, per attractor; with m1
    on the stop moved in (d1 = 3.5) the largest impact speed on it equals the atlas's own
    ``impact_velocity`` (measured apart, by ``features.impact_velocity``), 0 where the stop is far
    (d1 = 5); the figure coloured by it; a name that is not a measure refused; an atlas without
    measures keeps the identity it had (its folders still resume)."""
    from oscillator.analysis.axes import Axis
    from oscillator.attractors.atlas import AtlasSettings, atlas_store, regime_atlas
    from oscillator.report.plane import atlas_figure

    x, y = Axis("Omega", 1.55, 1.65, 2), Axis("d1", 3.5, 5.0, 2)
    atlas = regime_atlas(
        resolve_case("instance-1"), x, y, settings=AtlasSettings(), measures=("impact_max_right", "x_pp_m1")
    )
    table = atlas.table
    assert atlas.measures == ("impact_max_right", "x_pp_m1") and (table.period == 1).all()
    near, far = table[table.d1 == 3.5], table[table.d1 == 5.0]
    assert (near.impact_max_right > 1.0).all() and (far.impact_max_right == 0).all()
    np.testing.assert_allclose(table.impact_max_right, table.impact_velocity, rtol=1e-6)
    assert (table.x_pp_m1 > 5).all()
    label = atlas_figure(atlas, by="impact_max_right").axes[-1].get_ylabel()
    assert label == "largest impact_max_right over the attractors (m/s)"
    with pytest.raises(InputError, match="measures: 'loudness' is not a response measure"):
        regime_atlas(resolve_case("instance-1"), x, y, measures=("loudness",))
    plain = atlas_store(tmp_path / "a", resolve_case("instance-1"), x, y, AtlasSettings())
    assert "measures" not in plain.identity


def test_newton_asked_for_less_than_the_maps_accuracy_stops_at_its_best_iterate():
    """At CVODE's 1e-12 the period map is accurate to about 1e-10: Newton asked for 1e-13 with
    ``floor`` stops where the residual no longer halves and returns its best iterate (the orbit to
    the map's accuracy), in a few maps instead of chasing the noise."""
    from oscillator.orbits.shooting import FLOOR, _scale, newton, tightened

    orbit = find_orbit("instance-1", Omega=1.6)
    case = tightened(orbit.case, {})
    state, image, history = newton(case, orbit.section, orbit.state, 1, tol=1e-13, max_iterations=20, floor=True)
    assert len(history) <= 4 and history[-1] == min(history) <= FLOOR * _scale(case)
    assert np.max(np.abs(image.end - state)) == history[-1]
    assert np.max(np.abs(state - find_orbit(case, guess=orbit.state, tol=1e-10).state)) < 1e-9


def test_a_branchs_measures_are_those_of_its_orbits_refined():
    """branch_responses measures each point's orbit refined to the map's accuracy (on Newton's last
    run, not a run of its own): the measures of the orbit Newton finds there to 1e-10."""
    from oscillator import continue_orbit
    from oscillator.orbits.response import branch_responses

    branch = continue_orbit("instance-1", param="Omega", start=1.79, stop=1.80, step=0.005, max_points=8)
    table = branch_responses(branch)
    assert len(table) == 8
    for row, point in zip(table.itertuples(index=False), branch.points.itertuples(index=False), strict=True):
        state = [point.x1, point.v1, point.x2, point.v2]
        refined = find_orbit(resolve_case("instance-1", Omega=point.Omega), guess=state, tol=1e-10).response()
        for name in ("energy_forcing", "x_max_m1", "v_peak_m2", "rest_m2"):
            assert getattr(row, name) == pytest.approx(refined.columns()[name], rel=1e-10, abs=1e-10), name


def test_impact_speeds_read_from_a_runs_event_rows_are_those_of_its_event_table():
    """The measures read contact onsets from a run's event rows without building its table: the
    same speeds, in the same order, as from ``Result.events``, on both stops (stops moved in: m1
    strikes the right one and the masses strike each other, dozens of times in 20 periods).  Once
    the table is built the rows are let go (a long run's events are held once)."""
    from oscillator.orbits.response import impact_speeds

    case = resolve_case("instance-1", d=1, d1=3.5, Omega=1.5)
    result = simulate(case, t_end=case.initial.t0 + 20 * case.parameters.period)
    rows = result.event_rows
    assert rows is not None
    from_rows = {stop: impact_speeds(rows, stop) for stop in ("right", "left")}
    assert result.event_rows is not None  # reading the rows built no table
    for stop, least in (("right", 10), ("left", 20)):
        from_table = impact_speeds(result.events, stop)
        assert len(from_table) >= least and np.array_equal(from_table, from_rows[stop])
        assert np.all(from_rows[stop] > 0)
    assert result.event_rows is None
