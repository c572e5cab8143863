"""Noise measures (docs/noise.md): spectra against closed-form Fourier series and Parseval, the
model's own half-sine contact pulse and its impulse, the impact power against the energy audit."""

from __future__ import annotations

import functools
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
    assert np.abs(right.force.coefficients - exact).max() < 1e-9 * np.abs(exact).max()
    assert right.onsets == 1 and right.impulse == pytest.approx(2 * m1 * 1.0, rel=1e-9)
    assert right.energy == right.power == 0.0  # K6 has no damper
    assert noise(case, 1, 120).contacts["left"].rate == 0.0


def test_the_impact_power_is_the_energy_the_contacts_damper_dissipates():
    orbit = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.5)
    found, response = orbit.noise(), orbit.response()
    left, period = found.contacts["left"], orbit.case.parameters.period
    assert left.power * period == pytest.approx(response.energy["contact"], rel=1e-9)
    e = response.energy  # the audit: what goes in less what the dampers and friction take out
    assert left.power * period == pytest.approx(e["forcing"] + e["feedback"] - e["dampers"] - e["friction"], rel=1e-9)
    assert left.energy * left.onsets == pytest.approx(response.energy["contact"] * orbit.period, rel=1e-9)
    assert left.rate == pytest.approx(response.contact["left"]["onsets"] / period, rel=1e-12)
    assert found.power == left.power and left.impact_max == response.contact["left"]["impact_max"]
    columns = found.columns(cutoff=1.0)
    assert columns["force_level_left"] == left.force.level(1.0) < left.force.level()
    table = left.force.table()
    assert table.frequency[1] == pytest.approx(1 / (orbit.period * period))
    assert table.amplitude[0] == pytest.approx(left.impulse_rate, rel=1e-12)  # the mean force


def test_the_accelerations_steps_where_a_mass_sticks_and_slips_are_cvodes_slopes_either_side():
    """At each of m2's rest onsets and ends on this orbit, the step of its acceleration against
    the slopes of ``v2`` on either side in CVODE's own trajectory (a cubic through its steps
    up to the neighbouring event, 0.02 s at most)."""
    orbit = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.6)
    m2 = orbit.noise(0).masses[2]
    run = osc.simulate(orbit.one_period())
    events, trajectory = run.events, run.trajectory
    times = np.sort(events.t.unique())
    rests = events[(events.mass == 2) & events.kind.isin(["sliding_onset", "sliding_vanish"])].t.to_numpy()
    assert m2.slips == len(rests) == 4 and orbit.noise(0).masses[1].slips == 0

    def slope(t: float, side: int) -> float:
        near = times[(side * (times - t)) > 1e-9]
        edge = near[np.argmin(np.abs(near - t))] if len(near) else t + side * 0.02
        edge = t + side * min(abs(edge - t), 0.02)  # a cubic over at most 0.02 s
        rows = trajectory[(side * (trajectory.t - t) > 1e-9) & (side * (trajectory.t - edge) < 0)]
        return float(np.polyval(np.polyder(np.polyfit(rows.t, rows.v2, 3)), t)) if len(rows) > 4 else 0.0

    steps = [abs(slope(t, 1) - slope(t, -1)) for t in rests]
    assert m2.step_max == pytest.approx(max(steps), rel=1e-3)
    assert min(steps) > 0.5  # every transition steps


def test_the_page_prints_what_it_shows(capsys):
    page = (ROOT / "docs" / "noise.md").read_text(encoding="utf-8")
    code = page.split("```python\n", 1)[1].split("```", 1)[0]
    shown = page.split("```text\n", 1)[1].split("```", 1)[0]
    exec(compile(code, "docs/noise.md", "exec"), {})
    assert capsys.readouterr().out == shown


def test_the_levels_section_prints_what_it_shows(capsys):
    page = (ROOT / "docs" / "noise.md").read_text(encoding="utf-8").split("## The levels' derivatives", 1)[1]
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


def test_the_spectra_figure_has_a_panel_per_contact_that_struck_and_per_mass_with_omega_named():
    orbit = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.6)
    fig = orbit.noise(300).plot()
    panels = [ax for ax in fig.axes if ax.get_ylabel()]
    assert [ax.get_title(loc="left") for ax in panels] == [
        "contact force, right stop (x1 = d1)", "contact force, m1 on m2's stop", "acceleration of m1",
        "acceleration of m2",
    ]  # fmt: skip
    assert [ax.get_ylabel() for ax in panels] == ["level (dB re 1 N)"] * 2 + ["level (dB re 1e-6 m/s^2)"] * 2
    assert all(ax.get_xscale() == "log" for ax in panels)
    omega = orbit.case.parameters.Omega / (2 * np.pi)
    top = panels[0].child_axes[0]  # the secondary axis on top
    named = {tick.get_text(): position for tick, position in zip(top.get_xticklabels(), top.get_xticks(), strict=True)}
    assert named["Ω"] == pytest.approx(omega) and named["100Ω"] == pytest.approx(100 * omega)
    free = osc.find_orbit("instance-1", Omega=1.8).noise().plot()  # no contact: the masses alone
    titles = [ax.get_title(loc="left") for ax in free.axes if ax.get_ylabel()]
    assert titles == ["acceleration of m1", "acceleration of m2"]


def test_the_orbit_command_prints_the_noise_measures_the_library_finds(monkeypatch):
    from typer.testing import CliRunner

    from oscillator.cli import console
    from oscillator.cli.app import app

    monkeypatch.setattr(console.out, "width", 200)  # as COLUMNS sets it for the command: no column cut
    done = CliRunner().invoke(app, ["orbit", "instance-1", "--set", "d=1", "--set", "d1=3.5", "--set", "Omega=1.6",
                                    "--noise"])  # fmt: skip
    assert done.exit_code == 0, done.output
    found = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.6).noise()
    lines = {line.split()[0]: line.split()[1:] for line in done.stdout.splitlines() if line.strip()}
    left, m2 = found.contacts["left"], found.masses[2]
    assert lines["left"] == [f"{left.rate:.6g}", f"{left.impulse:.6g}", f"{left.energy:.6g}", f"{left.power:.6g}",
                             f"{left.force.level():.2f}"]  # fmt: skip
    assert lines["m2"] == [f"{m2.acceleration.level():.2f}", "4", f"{m2.step_max:.6g}"]
    assert "Noise measures of the contacts" in done.stdout and "Noise measures of the masses" in done.stdout


def test_the_orbit_command_draws_the_spectra_to_a_file_it_checks_before_computing(tmp_path, monkeypatch):
    """``--noise-figure FILE`` prints the measures and draws the spectra (a whole PNG); a name that
    is not a figure's, or in a folder that does not exist, is refused at once (exit 2) and nothing
    is written."""
    from typer.testing import CliRunner

    from oscillator.cli.app import app

    monkeypatch.chdir(tmp_path)
    orbit = ["orbit", "instance-1", "--set", "d=1", "--set", "d1=3.5", "--set", "Omega=1.6"]
    done = CliRunner().invoke(app, [*orbit, "--noise-figure", "spectra.png"])
    assert done.exit_code == 0, done.output
    assert "Noise measures of the contacts" in done.stdout and "spectra drawn to spectra.png" in done.stdout
    assert (tmp_path / "spectra.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for name, words in (("spectra.txt", "must end in .png, .svg or .pdf"), ("no/spectra.svg", "does not exist")):
        refused = CliRunner().invoke(app, [*orbit, "--noise-figure", name])
        assert refused.exit_code == 2 and words in refused.stderr and "--noise-figure" in refused.stderr
        assert "Noise measures" not in refused.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spectra.png"]
    (tmp_path / "taken.png").mkdir()  # a figure that cannot be written: the measures are printed all the same
    failed = CliRunner().invoke(app, [*orbit, "--noise-figure", "taken.png"])
    assert failed.exit_code == 1 and "the measures above are complete" in failed.stderr
    assert "Noise measures of the masses" in failed.stdout and (tmp_path / "taken.png").is_dir()


def test_the_orbit_command_writes_the_spectra_table_the_library_gives(tmp_path, monkeypatch):
    """``--noise-table FILE`` writes :meth:`Noise.spectra` (CSV or Parquet by its name): each
    signal's harmonics with their frequency, amplitude and level, the contact force's mean at
    harmonic 0 (the impulse rate); a name that is not a table's, or the figure's own, is refused
    before anything is computed, and a file that cannot be written exits 1 after the measures."""
    import pandas as pd
    from typer.testing import CliRunner

    from oscillator.cli.app import app

    monkeypatch.chdir(tmp_path)
    orbit = ["orbit", "instance-1", "--set", "d=1", "--set", "d1=3.5", "--set", "Omega=1.6"]
    done = CliRunner().invoke(app, [*orbit, "--noise-table", "spectra.parquet", "--noise-figure", "spectra.svg"])
    assert done.exit_code == 0, done.output
    assert "spectra written to spectra.parquet" in done.stdout and "spectra drawn to spectra.svg" in done.stdout
    found = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.6).noise()
    written, expected = pd.read_parquet(tmp_path / "spectra.parquet"), found.spectra()
    assert list(written.signal.unique()) == ["force_right", "force_left", "acceleration_m1", "acceleration_m2"]
    assert (written.groupby("signal").size() == 201).all()
    numbers = ["harmonic", "frequency", "amplitude", "level"]
    assert np.allclose(written[numbers].to_numpy(), expected[numbers].to_numpy(), rtol=1e-6, atol=1e-12)
    means = written[written.harmonic == 0].set_index("signal").amplitude
    assert means["force_left"] == pytest.approx(found.contacts["left"].impulse_rate, rel=1e-6)
    assert written[written.signal == "acceleration_m1"].unit.iloc[0] == "m/s^2"
    same = ["--noise-table", "same.png", "--noise-figure", "same.png"]
    for extra, words in ((["--noise-table", "spectra.txt"], "must end in .csv or .parquet"), (same, "the same file")):
        refused = CliRunner().invoke(app, [*orbit, *extra])
        assert refused.exit_code == 2 and words in refused.stderr and "Noise measures" not in refused.stdout
    (tmp_path / "taken.csv").mkdir()
    failed = CliRunner().invoke(app, [*orbit, "--noise-table", "taken.csv"])
    assert failed.exit_code == 1 and "--noise-table" in failed.stderr and "Noise measures" in failed.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["spectra.parquet", "spectra.svg", "taken.csv"]


def test_a_frequency_responses_noise_is_each_points_and_draws_against_the_parameter():
    case = osc.resolve_case("instance-1", d=1, d1=3.5)
    found = osc.frequency_response(case, "Omega", (1.45, 1.6), seeds=2, sweep=3, max_points=12, workers=1)
    table = found.noise(harmonics=20, cutoff=1.0)
    assert len(table) == len(found.points) and list(table.columns[:4]) == ["branch", "Omega", "stable", "piece"]
    assert (table.branch.to_numpy() == found.points.branch.to_numpy()).all()
    assert np.allclose(table.Omega, found.points.Omega, rtol=0, atol=0)
    row, branch = table.iloc[5], found.branches[int(table.branch.iloc[5])]
    point = branch.points[branch.points.Omega == row.Omega].iloc[0]
    state = {name: float(point[name]) for name in case.system.state}
    alone = noise(osc.resolve_case(branch.case, Omega=row.Omega, t0=branch.section, **state), branch.period, 20)
    assert alone.columns(1.0)["impact_power_left"] == row.impact_power_left > 0
    fig = found.plot_noise(table, "impact_power_left")
    assert fig.axes[0].get_ylabel() == "impact power left (W)" and len(fig.axes[0].lines) >= len(found.branches)
    with pytest.raises(InputError, match="column must be one of"):
        found.plot_noise(table, "x_pp_m1")


@pytest.mark.slow
def test_the_frc_command_writes_every_points_noise_and_spectra_and_the_report_keeps_them(tmp_path, monkeypatch):
    """``oscillator frc ... --noise``: noise.parquet is the frequency response's noise table
    (:meth:`FrequencyResponse.noise`), spectra.parquet each point's spectra (201 harmonics of four
    signals), the figure is drawn and the report names them; ``oscillator report DIR`` written
    again keeps them."""
    import pandas as pd
    from typer.testing import CliRunner

    from oscillator.cli.app import app

    monkeypatch.chdir(tmp_path)
    frc = ["frc", "instance-1", "--set", "d=1", "--set", "d1=3.5", "--param", "Omega", "1.5", "1.6", "--seeds", "2",
           "--sweep", "3", "--max-points", "6", "--workers", "1"]  # fmt: skip
    done = CliRunner().invoke(app, [*frc, "--noise", "--out", "frc"])
    assert done.exit_code == 0, done.output
    found = osc.read_run(tmp_path / "frc")
    written, spectra = (
        pd.read_parquet(tmp_path / "frc" / "noise.parquet"),
        pd.read_parquet(tmp_path / "frc" / "spectra.parquet"),
    )
    expected = found.noise()
    assert list(written.columns) == list(expected.columns) and len(written) == len(found.points) > 0
    assert np.allclose(written.impact_power_left, expected.impact_power_left, rtol=1e-9, atol=0)
    assert len(spectra) == len(found.points) * 4 * 201
    assert list(spectra.columns[:4]) == ["branch", "point", "Omega", "stable"]
    figure = tmp_path / "frc" / "figures" / "frequency-spectra.png"
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    report = (tmp_path / "frc" / "report.md").read_text(encoding="utf-8")
    assert "## Noise" in report and "figures/frequency-spectra.png" in report
    figure.unlink()
    again = CliRunner().invoke(app, ["report", "frc"])
    assert again.exit_code == 0, again.output
    assert figure.is_file() and "## Noise" in (tmp_path / "frc" / "report.md").read_text(encoding="utf-8")


def test_the_impact_rates_energies_impulses_and_powers_are_response_measures_with_exact_derivatives():
    """``impact_rate``, ``impact_energy``, ``impact_power``, ``impulse``, ``impulse_rate`` and
    ``force_rms`` of each contact are response measures (so the atlas, the frequency response and the design take them),
    equal to the noise measures' own, and their derivatives in the contact's damper and Omega
    (which moves the span) agree with Richardson differences to 1e-7 (test_sensitivities.check).
    The impulse, integrated along the pieces with the state, is the contact force spectrum's mean
    (its own quadrature on the pieces' dense output) times the return over the impacts."""
    from test_sensitivities import NEWTON, TIGHT, check

    orbit = osc.find_orbit("instance-1", Omega=1.5, d=1, d1=3.5, tol=NEWTON, **TIGHT)
    found_noise = orbit.noise()
    columns, heard = orbit.response().columns(), found_noise.columns()
    for name in ("impact_rate", "impact_energy", "impact_power", "impulse", "impulse_rate"):
        for stop in ("right", "left"):
            column = f"{name}_{stop}"
            assert columns[column] == pytest.approx(heard[column], rel=1e-9, abs=1e-12), column
    for stop, contact in found_noise.contacts.items():
        assert contact.onsets > 0
        mean_force = contact.force.mean  # the spectrum's own integral, not the response's
        assert columns[f"impulse_rate_{stop}"] == pytest.approx(mean_force, rel=1e-9)
        assert columns[f"impulse_{stop}"] == pytest.approx(mean_force * found_noise.span / contact.onsets, rel=1e-9)
    # Parseval: the force's mean square about its mean is all its harmonics above 0 Hz; a spectrum
    # of K harmonics falls short by its tail, as 1/K^3 for the stop's force (a kink at each end: its
    # harmonics fall as 1/k^2) and as 1/K for the damped contact's (it jumps: 1/k)
    more = orbit.noise(600)
    for stop, power in (("right", 3), ("left", 1)):
        square = columns[f"force_rms_{stop}"] ** 2
        short = [
            square / mean_square_above(spectrum.force.coefficients, spectrum.force.fundamental) - 1
            for spectrum in (found_noise.contacts[stop], more.contacts[stop])
        ]
        assert 0 < short[1] < short[0] < (1e-5 if stop == "right" else 2e-2), stop
        assert short[0] / short[1] == pytest.approx(3**power, rel=0.1), stop
    period = orbit.case.parameters.period
    assert columns["impact_power_left"] == pytest.approx(columns["energy_contact"] / period, rel=1e-15)
    assert columns["impact_rate_left"] == 2 / period and columns["impact_power_right"] == 0.0
    found = check(orbit, ["Omega", "C3"], steps={"Omega": 2e-4})
    slopes = found.measures.loc["impact_rate_left"]
    assert slopes["d/dOmega"] == pytest.approx(2 / (2 * np.pi), rel=1e-12) and slopes["d/dC3"] == 0.0
    assert found.measures.loc["impact_power_left", "d/dC3"] != 0.0
    assert found.measures.loc[["impulse_left", "impulse_right", "force_rms_left"], "d/dC3"].abs().min() > 0.0


def test_the_levels_above_a_cut_off_are_every_harmonic_above_it():
    """``orbit.sensitivities(params).levels(cutoff)``: each level is every harmonic above the
    cut-off (the RMS of the response integrals less the harmonics below it), so a spectrum of 600
    harmonics gives it but for its tail (1/K^3 on the stop, 1/K on the damped contact); above 0 Hz
    a force's level is ``20 log10(force_rms)``; a contact that never closes has no level."""
    orbit = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.6)
    found = orbit.sensitivities(["C3"])
    levels, heard = found.levels(cutoff=1.0), orbit.noise(600).columns(1.0)
    for name, tail in (("force_level_right", 1e-5), ("force_level_left", 0.03), ("acceleration_level_m1", 1e-3)):
        assert heard[name] == pytest.approx(levels.loc[name, "value"], abs=tail), name
    assert heard["force_level_left"] < levels.loc["force_level_left", "value"]  # the tail is missing
    whole = found.levels(0.0)
    for stop in ("right", "left"):
        rms = found.measures.loc[f"force_rms_{stop}", "value"]
        assert whole.loc[f"force_level_{stop}", "value"] == pytest.approx(20 * np.log10(rms), abs=1e-12)
    with pytest.raises(InputError, match="cutoff must be a frequency"):
        found.levels(-1.0)
    apart = osc.find_orbit("instance-1", Omega=1.6).sensitivities(["C3"]).levels(1.0)  # the masses never touch
    assert apart.loc["force_level_left", "value"] == -np.inf and np.isnan(apart.loc["force_level_left", "d/dC3"])


def test_the_levels_above_a_cut_off_move_as_richardson_says():
    """The levels' derivatives in C3, Omega (which moves the harmonics) and d1 (which moves the
    stop's switches) equal Richardson differences of the levels of the orbits found nearby, each
    level to 1e-7 of its own scale."""
    from test_sensitivities import NEWTON, richardson

    orbit = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.6, tol=NEWTON)
    params = ["C3", "Omega", "d1"]
    levels = orbit.sensitivities(params).levels(cutoff=1.0)

    def seen(name: str, value: float) -> np.ndarray:
        moved = osc.find_orbit(osc.resolve_case(orbit.case, **{name: value}), guess=orbit.state, tol=NEWTON)
        return moved.sensitivities(["C3"]).levels(1.0)["value"].to_numpy()

    differences = []
    for name in params:
        value = getattr(orbit.case.parameters, name)
        differences.append(richardson(functools.partial(seen, name), value, 1e-4 * max(1.0, abs(value))))
    exact = levels[[f"d/d{name}" for name in params]].to_numpy()
    error = np.abs(np.array(differences).T - exact).max(axis=1)
    assert (error <= 1e-7 * np.abs(exact).max(axis=1)).all(), dict(zip(levels.index, error, strict=True))


#: docs/noise.md's worked design: the clearance between the masses and their contact's damper that
#: make the worst impact power between them over Omega in [1.45, 1.6] least, the right stop struck
#: no faster than 4.6 m/s (scripts/noise_figures.py draws its figures).
QUIETER = {
    "vary": {"d": (0.5, 2.2), "C3": (0.2, 2.0)},
    "over": {"Omega": (1.45, 1.6)},
    "objective": "impact_power_left",
    "constraints": ["impact_max_right <= 4.6"],
    "band": 7,
    "starts": 2,
    "candidates": 8,
}


@pytest.fixture(scope="module")
def quieter():
    from oscillator.io.cases import resolve_case

    case = resolve_case("instance-1", d=1, d1=3.5)
    return osc.design(case, settings=osc.AttractorSettings(transient=100, record=8), **QUIETER)


@pytest.mark.slow  # an end-to-end worked example of 20 s: CI runs it with the slow tier
def test_the_quieter_design_rattles_less_and_strikes_the_stop_at_its_bound(quieter):
    """The masses touching shield the right stop: the optimum opens the clearance and softens the
    contact's damper until the stop is struck at its bound (the constraint active, to 1e-6), inside
    the ranges; its worst impact power is a third of the global search's best and an eighth of
    the page's start (d = 1, C3 = 1), which also strikes the stop too fast."""
    from oscillator.designing.judging import survey

    best = quieter.best
    assert best.feasible and quieter.runs["refine"] > 0
    assert best.worst["impact_max_right"] == pytest.approx(4.6, abs=1e-6)
    assert 1.5 < quieter.values["d"] < 1.7 and 0.3 < quieter.values["C3"] < 0.6
    assert 0 < best.objective < quieter.start.objective / 3
    start = survey(quieter.problem, osc.AttractorSettings(transient=100, record=8), np.array([1.0, 1.0]))
    assert best.objective < start.objective / 8 and not start.feasible


@pytest.mark.slow
def test_a_brute_force_grid_finds_no_quieter_design_than_the_optimum(quieter):
    """Independent grids, each design surveyed from fresh starts: no feasible design of an 8 x 4
    grid over the whole ranges is quieter than the optimum, and the best feasible design of a
    9 x 7 grid around it is within one step of it in each parameter."""
    from oscillator.designing.judging import Judged, survey

    problem, settings = quieter.problem, osc.AttractorSettings(transient=100, record=8)
    plane = [
        survey(problem, settings, np.array([a, b])) for a in np.linspace(0.5, 2.2, 8) for b in (0.2, 0.8, 1.4, 2.0)
    ]
    assert min(j.objective for j in plane if j.feasible) >= quieter.best.objective - 1e-9
    axes = np.linspace(1.4, 1.8, 9), np.linspace(0.2, 0.8, 7)
    near = [survey(problem, settings, np.array([a, b])) for a in axes[0] for b in axes[1]]
    best = min((j for j in near if j.feasible), key=Judged.key)
    steps = np.array([axes[0][1] - axes[0][0], axes[1][1] - axes[1][0]])
    assert (np.abs(best.design - quieter.best.design) <= steps + 1e-12).all()
    assert best.objective >= quieter.best.objective - 1e-9
