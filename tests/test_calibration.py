"""Calibration to measured steady responses (docs/calibration.md): parameters recovered from
noisy data simulated with known ones, intervals that cover them as often as they claim and shrink
as 1/sqrt(n), what the data cannot identify named, bad data refused by row and column."""

from __future__ import annotations

import json
import subprocess
import sys
from functools import cache
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import oscillator as osc
from oscillator.calibrating.fit import calibrate
from oscillator.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
#: Instance 1 with its stops close in: m1 strikes both every period (docs/frequency.md).
IMPACTING = {"d": 1.0, "d1": 3.5}
TRUE = {"mu_k": 0.1, "K3": 2.0, "K6": 1.0}


@cache
def _responses(frequencies: tuple[float, ...], measures: tuple[str, ...], **values: float) -> pd.DataFrame:
    """Noise-free measurements: each frequency's orbit (settled from the case's start) measured."""
    case = osc.resolve_case("instance-1", **IMPACTING, **values)
    rows = []
    for omega in frequencies:
        found = osc.find_orbit(case, Omega=omega).response().columns()
        rows += [(omega, name, found[name]) for name in measures]
    return pd.DataFrame(rows, columns=["Omega", "measure", "value"])


def _noisy(clean: pd.DataFrame, sigma: float, rng: np.random.Generator, repeats: int = 1) -> pd.DataFrame:
    table = pd.concat([clean] * repeats, ignore_index=True)
    return table.assign(value=table.value + rng.normal(0, sigma, len(table)), sigma=sigma)


def _inside(found, truth: dict[str, float]) -> pd.Series:
    table = found.table.loc[list(truth)]
    return (table.ci_low <= pd.Series(truth)) & (pd.Series(truth) <= table.ci_high)


def test_three_parameters_of_the_impacting_system_are_recovered_from_noisy_responses():
    clean = _responses((1.3, 1.4, 1.5, 1.6, 1.7, 1.8), ("x_pp_m1", "x_pp_m2", "impact_max_left", "impact_max_right"))
    data = _noisy(clean, 0.01, np.random.default_rng(1))
    start = osc.resolve_case("instance-1", **IMPACTING, mu_k=0.13, K3=2.5, K6=1.3)
    found = calibrate(start, data, {"mu_k": (0.05, 0.2), "K3": (1, 4), "K6": (0.5, 3)})
    assert found.success and found.warnings == ()
    assert _inside(found, TRUE).all(), found.table
    for name, truth in TRUE.items():  # within three standard errors, and those are small
        assert abs(found.estimate[name] - truth) < 3 * found.table.stderr[name], name
    assert found.table.stderr.mu_k < 0.002 and found.table.stderr.K3 < 0.05
    assert found.table.start.tolist() == [0.13, 2.5, 1.3]
    # the residuals are the measurements minus the fitted model, which is the model at the estimate
    fitted = osc.find_orbit(found.fitted, Omega=1.5).response().columns()["impact_max_left"]
    row = found.residuals[(found.residuals.Omega == 1.5) & (found.residuals.measure == "impact_max_left")].iloc[0]
    assert row.fitted == pytest.approx(fitted, abs=1e-7)
    assert row.residual == pytest.approx(row.value - row.fitted, abs=1e-15)
    assert abs(found.residuals.residual).max() < 0.04  # four sigma


def test_the_intervals_shrink_as_one_over_the_root_of_the_number_of_measurements():
    clean = _responses((1.4, 1.5, 1.7), ("x_pp_m1", "impact_max_left", "impact_max_right"))
    rng = np.random.default_rng(3)
    vary = {"mu_k": (0.05, 0.2), "K6": (0.5, 3)}
    case = osc.resolve_case("instance-1", **IMPACTING)
    once = calibrate(case, _noisy(clean, 0.02, rng), vary)
    four = calibrate(case, _noisy(clean, 0.02, rng, repeats=4), vary)
    ratio = once.table.stderr / four.table.stderr
    assert ratio.to_numpy() == pytest.approx([2.0, 2.0], rel=0.03)
    assert once.uncertainty.scale == 1.0  # sigma given: the noise is known, not estimated


@pytest.mark.slow
def test_the_95_percent_intervals_cover_the_truth_in_at_least_90_of_100_noisy_draws():
    """One frequency's four measures, two parameters, a known noise: about 0.2 s a fit."""
    clean = _responses((1.5,), ("x_pp_m1", "x_pp_m2", "impact_max_left", "force_peak_left"))
    rng = np.random.default_rng(2026)
    case = osc.resolve_case("instance-1", **IMPACTING)
    covered = pd.Series(0, index=["mu_k", "K3"])
    for _ in range(100):
        found = calibrate(case, _noisy(clean, 0.01, rng), {"mu_k": (0.05, 0.2), "K3": (1, 4)})
        covered += _inside(found, {"mu_k": 0.1, "K3": 2.0}).astype(int)
    assert (covered >= 90).all(), covered
    assert (covered < 100).all(), covered  # intervals that are not simply huge


def test_two_parameters_that_enter_only_as_their_product_are_named_and_a_stop_never_reached_too():
    """Where neither mass ever rests, friction enters only as ``mu_k g``: the data fix the product.
    Instance 1's own stops are never reached below Omega 1.7: nothing depends on K6."""
    case = osc.resolve_case("instance-1")
    rows = []
    for omega in (1.4, 1.5, 1.7):
        found = osc.find_orbit(case, Omega=omega).response().columns()
        assert found["rest_m1"] == found["rest_m2"] == 0 and found["onsets_right"] == 0
        rows += [(omega, name, found[name]) for name in ("x_pp_m1", "x_pp_m2")]
    data = pd.DataFrame(rows, columns=["Omega", "measure", "value"])
    start = osc.resolve_case(case, mu_k=0.12)
    found = calibrate(start, data, {"mu_k": (0.05, 0.2), "g": (5, 15), "K6": (0.5, 3)}, max_evaluations=30)
    assert np.isinf(found.table.stderr).all()
    said = " ".join(found.warnings)
    assert "mu_k and g are not identifiable from these data, only a combination of them" in said
    assert "% of mu_k and -" in said and "% of g" in said  # the product: both up or down by the same share
    assert "K6 is not identifiable from these data: no fitted value depends on it" in said
    assert found.estimate.mu_k * found.estimate.g == pytest.approx(0.1 * 9.8, rel=1e-6)


def test_a_robust_loss_lets_an_outlier_count_little():
    clean = _responses((1.3, 1.4, 1.5, 1.6, 1.7, 1.8), ("x_pp_m1", "x_pp_m2", "impact_max_left", "impact_max_right"))
    data = _noisy(clean, 0.01, np.random.default_rng(7))
    data.loc[5, "value"] += 0.5  # fifty sigma: a misread
    case = osc.resolve_case("instance-1", **IMPACTING)
    vary = {"mu_k": (0.05, 0.2), "K3": (1, 4)}
    plain = calibrate(case, data, vary)
    robust = calibrate(case, data, vary, loss="soft_l1", f_scale=2.0)
    assert not _inside(plain, {"mu_k": 0.1, "K3": 2.0}).all()
    assert _inside(robust, {"mu_k": 0.1, "K3": 2.0}).all(), robust.table
    assert robust.residuals.weight[5] < 0.1 and robust.residuals.weight.drop(5).min() > 0.6  # r = 2 sigma: 0.71


def test_several_starts_keep_the_best_and_say_each():
    clean = _responses((1.4, 1.5, 1.7), ("x_pp_m1", "impact_max_left", "impact_max_right"))
    data = _noisy(clean, 0.02, np.random.default_rng(4))
    found = calibrate(
        osc.resolve_case("instance-1", **IMPACTING), data, {"mu_k": (0.05, 0.2), "K6": (0.5, 3)}, starts=2
    )
    assert len(found.starts) == 2 and found.starts.mu_k[0] == 0.1 and found.starts.K6[0] == 1.0
    assert found.cost == pytest.approx(found.starts.cost.min(), rel=1e-9)
    assert found.runs >= sum(found.starts.evaluations)  # every evaluation ran at least one simulation


def test_a_calibration_kept_in_its_folder_resumes_with_the_starts_it_finished(tmp_path):
    """Each start's fit is kept as it ends: run again, the folder's starts are read back (no
    simulation) and a missing one is fitted again, to the same estimate and counts; a damaged
    part is refused by name, and a folder of another calibration is refused."""
    from oscillator.calibrating.store import calibration_store
    from oscillator.hybrid.counting import runs

    data = _noisy(_responses((1.4, 1.6), ("x_pp_m1", "impact_max_right")), 0.02, np.random.default_rng(8))
    case, vary = osc.resolve_case("instance-1", **IMPACTING), {"mu_k": (0.05, 0.2), "K6": (0.5, 3)}

    def store():
        return calibration_store(tmp_path / "fit", case, data, vary, starts=3)

    first_store, done = store(), []
    first = calibrate(case, data, vary, starts=3, store=first_store, progress=lambda k, n: done.append((k, n)))
    assert done == [(1, 3), (2, 3), (3, 3)] and sorted(p.name for p in (tmp_path / "fit" / "parts").iterdir()) == [
        "start-000.parquet", "start-001.parquet", "start-002.parquet"
    ]  # fmt: skip
    before, again = runs(), store()
    resumed = calibrate(case, data, vary, starts=3, store=again)
    assert runs() == before and again.reused == 3
    pd.testing.assert_frame_equal(resumed.table, first.table)
    pd.testing.assert_frame_equal(resumed.starts, first.starts)
    assert resumed.runs == first.runs == first.starts.runs.sum() and resumed.cost == first.cost
    (tmp_path / "fit" / "parts" / "start-001.parquet").unlink()
    partial = store()
    refitted = calibrate(case, data, vary, starts=3, store=partial)
    assert partial.reused == 2 and runs() - before == first.starts.runs[1]
    pd.testing.assert_frame_equal(refitted.starts, first.starts)
    (tmp_path / "fit" / "parts" / "start-002.parquet").write_bytes(b"garbage")
    with pytest.raises(InputError, match=r"start-002.parquet is damaged \(it cannot be read\)"):
        calibrate(case, data, vary, starts=3, store=store())
    other = calibration_store(tmp_path / "fit", case, data, vary, starts=3, loss="soft_l1")
    with pytest.raises(InputError, match="holds another calibration computation"):
        other.check()
    with pytest.raises(InputError, match="store: it was made for another calibration"):
        calibrate(case, data, vary, starts=2, store=store())  # the store's starts are 3


def test_a_declared_systems_friction_is_recovered_by_element_and_field():
    chain = osc.load_system(ROOT / "docs" / "systems" / "blade-damper.toml")
    truth = {"platform.F": 0.3, "blade damping.c": 0.02}
    rows = []
    for omega in (0.8, 0.9, 1.1, 1.2):
        from oscillator.orbits.chain_response import orbit_measures

        measures = orbit_measures(osc.find_orbit(chain, Omega=omega))
        rows += [(omega, name, measures[name]) for name in ("x_pp:blade", "x_pp:damper")]
    data = _noisy(pd.DataFrame(rows, columns=["Omega", "measure", "value"]), 0.005, np.random.default_rng(11))
    start = chain.with_values({"platform.F": 0.4, "blade damping.c": 0.03})
    found = calibrate(start, data, {"platform.F": (0.1, 1.0), "blade damping.c": (0.005, 0.1)})
    assert found.success and _inside(found, truth).all(), found.table
    assert abs(found.estimate["platform.F"] - 0.3) < 0.01
    assert (
        isinstance(found.fitted, osc.FrictionChain) and found.fitted.value("platform.F") == found.estimate["platform.F"]
    )


GOOD = pd.DataFrame({"Omega": [1.4, 1.5, 1.6], "measure": ["x_pp_m1"] * 3, "value": [7.7, 7.8, 7.8]})


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        (lambda d: d.drop(columns="value"), "data", "data has no column 'value'"),
        (lambda d: d.assign(sd=0.1), "data", "a column the fit does not read: 'sd'"),
        (lambda d: d.assign(value=[7.7, np.nan, 7.8]), "value", "data row 2 (Omega = 1.5): value is nan"),
        (lambda d: d.assign(value=["7.7", "seven", "7.8"]), "value", "data row 2 (Omega = 1.5): value is 'seven'"),
        (lambda d: d.assign(sigma=[0.1, 0.1, 0.0]), "sigma", "data row 3 (Omega = 1.6): sigma is 0"),
        (lambda d: d.assign(measure=["x_pp_m1", "x_pp_m3", "x_pp_m1"]), "measure", "no response measure named"),
        (lambda d: d.assign(value=[7.7, -7.8, 7.8]), "value", "data row 2 (Omega = 1.5): x_pp_m1 = -7.8 cannot be"),
        (lambda d: d.assign(measure="rest_m2", value=[0, 40, 0]), "value", "rest_m2 = 40 is a share of a period"),
        (lambda d: d.assign(Omega=[1.4, -1.5, 1.6]), "Omega", "data row 2: the model refuses Omega = -1.5"),
        (lambda d: d.iloc[:2], "data", "data has 2 row(s) for 2 parameter(s)"),
        (lambda d: [1, 2, 3], "data", "data must be a pandas DataFrame"),
    ],
)
def test_bad_data_is_refused_by_row_and_column_before_any_simulation(change, field, words):
    from oscillator.hybrid.counting import runs

    before = runs()
    with pytest.raises(InputError, match=None) as refused:
        calibrate("instance-1", change(GOOD.copy()), {"mu_k": (0.05, 0.2), "K3": (1, 4)})
    assert refused.value.field == field and words in str(refused.value), str(refused.value)
    assert runs() == before


@pytest.mark.parametrize(
    ("vary", "options", "words"),
    [
        ({"mu_kk": (0.05, 0.2)}, {}, "mu_kk"),
        ({"mu_k": (0.2, 0.05)}, {}, "range must be two numbers low < high"),
        ({"Omega": (1, 2)}, {}, "Omega is the measured parameter"),
        ({"mu_k": (0.05, 0.2)}, {"loss": "l1"}, "loss must be one of linear, soft_l1"),
        ({"mu_k": (0.05, 0.2)}, {"level": 95}, "level must be a probability"),
        ({"mu_k": (0.05, 0.2)}, {"starts": 0}, "starts"),
        ({"mu_k": (0.05, 0.2)}, {"seed": "x"}, "seed"),
        ({"m1": (-1, 2)}, {}, "vary: the model refuses m1 = -1"),
    ],
)
def test_bad_options_are_refused_naming_the_field(vary, options, words):
    with pytest.raises(InputError) as refused:
        calibrate("instance-1", GOOD, vary, **options)
    assert words in str(refused.value), str(refused.value)


def _page_block(capsys, monkeypatch, *after: str) -> dict:
    """The first Python block of docs/calibration.md after each of ``after`` in turn, run from the
    repository (it reads docs/systems/), having printed the text block under it; its names."""
    part = (ROOT / "docs" / "calibration.md").read_text(encoding="utf-8")
    for marker in after:
        part = part.split(marker, 1)[1]
    code = part.split("```python\n", 1)[1].split("```", 1)[0]
    shown = part.split("```text\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(ROOT)
    namespace: dict = {}
    exec(compile(code, "docs/calibration.md", "exec"), namespace)
    assert capsys.readouterr().out == shown
    return namespace


@pytest.mark.slow  # an end-to-end worked example of 20 s: CI runs it with the slow tier
def test_the_worked_calibration_prints_what_the_page_shows(capsys, monkeypatch):
    """docs/calibration.md: its Python block prints the block under it."""
    _page_block(capsys, monkeypatch)


def test_the_page_quotes_the_warning_as_the_fit_words_it():
    """docs/calibration.md's example of an unidentifiable pair is the message, word for word."""
    page = (ROOT / "docs" / "calibration.md").read_text(encoding="utf-8")
    quoted = " ".join(
        page.split("Where neither\nmass ever rests", 1)[1].split("```text\n")[1].split("```", 1)[0].split()
    )
    case = osc.resolve_case("instance-1")
    rows = [(omega, name, osc.find_orbit(case, Omega=omega).response().columns()[name])
            for omega in (1.4, 1.5, 1.7) for name in ("x_pp_m1", "x_pp_m2")]  # fmt: skip
    data = pd.DataFrame(rows, columns=["Omega", "measure", "value"])
    found = calibrate(osc.resolve_case(case, mu_k=0.12), data, {"mu_k": (0.05, 0.2), "g": (5, 15)}, max_evaluations=30)
    assert found.warnings == (quoted,)


# -- time series -------------------------------------------------------------------------------

TIGHT = {"rtol": 1e-14, "atol": 1e-14}


def _richardson(f, value: float, h: float) -> np.ndarray:
    def central(step):
        return (np.asarray(f(value + step)) - np.asarray(f(value - step))) / (2 * step)

    return (4 * central(h / 2) - central(h)) / 3


def test_the_trajectorys_sensitivities_through_stick_slip_and_impact_are_richardsons_differences():
    """Forward sensitivities at fixed times of a run that strikes both stops, rests and slips
    again (every kind below), against Richardson-extrapolated central differences of ``simulate``
    at CVODE's 1e-14, to 1e-7 of each derivative (or of a thousandth of the state's size where the
    derivative nearly vanishes) plus the differences' resolution (the runs' rounding, up to 5e-12
    with the event times', over the step); times 0.02 s or more from any event, where the state
    is smooth in the parameters."""
    from oscillator.calibrating.series import trajectory_sensitivities

    case = osc.resolve_case("instance-1", **IMPACTING, **TIGHT)
    events = osc.simulate(case, t_end=13).events
    assert {"left_contact_onset", "right_contact_onset", "sliding_onset", "sliding_vanish"} <= set(events.kind)
    grid = np.linspace(case.initial.t0 + 0.5, case.initial.t0 + 12, 40)
    times = np.array([t for t in grid if np.abs(events.t.to_numpy() - t).min() > 0.02])
    names = ("mu_k", "mu_s", "K3", "K6", "Omega")
    states, derivatives, _ = trajectory_sensitivities(case, names, times)
    for j, name in enumerate(names):
        value = getattr(case.parameters, name)
        step = 1e-4 * max(abs(value), 1.0)  # 1e-3 of mu_k or Omega ends m2's brief rest at 11.5 s

        def at(v, name=name):
            run = osc.simulate(osc.resolve_case(case, **{name: v}), t_end=times[-1] + 0.01, save=osc.SaveAt(ts=times))
            return run.trajectory[["x1", "v1", "x2", "v2"]].to_numpy()

        exact, differenced = derivatives[:, :, j], _richardson(at, value, step)
        bound = 1e-7 * np.maximum(np.abs(exact), 1e-3 * np.abs(states)) + 5e-12 / step
        assert (np.abs(exact - differenced) <= bound).all(), (name, np.abs(exact - differenced).max())
        assert np.abs(exact).max() > 1e-3, name  # a derivative that is there


def _series(case, times, sigma, rng):
    run = osc.simulate(osc.resolve_case(case, **TIGHT), t_end=times[-1] + 0.01, save=osc.SaveAt(ts=times))
    rows = [(t, name, value) for t, *values in run.trajectory[["t", "x1", "x2"]].itertuples(index=False)
            for name, value in zip(("x1", "x2"), values, strict=True)]  # fmt: skip
    table = pd.DataFrame(rows, columns=["t", "variable", "value"])
    return table.assign(value=table.value + rng.normal(0, sigma, len(table)))


def test_friction_and_a_stops_stiffness_are_recovered_from_a_noisy_measured_time_series():
    case = osc.resolve_case("instance-1", **IMPACTING)
    data = _series(case, np.linspace(case.initial.t0 + 0.25, case.initial.t0 + 15, 60), 0.01, np.random.default_rng(3))
    start = osc.resolve_case(case, mu_k=0.12, K3=2.4)
    found = osc.calibrate(start, data, {"mu_k": (0.05, 0.15), "K3": (1, 4)})
    assert found.success and _inside(found, {"mu_k": 0.1, "K3": 2.0}).all(), found.table
    assert found.table.stderr.mu_k < 0.002 and found.uncertainty.scale == pytest.approx(0.01, rel=0.25)
    assert found.runs == found.evaluations  # one run of the model per evaluation, derivatives included
    assert list(found.residuals.columns[:2]) == ["t", "variable"]


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        (lambda d: d.iloc[[0, 3, 1, 2]], "t", "data row 3 (t = 2.0): the times are not in order (row 2 is at t = 2.5"),
        (lambda d: d.assign(t=[0.5, 1.5, 2.0, 2.5]), "t", "data row 1 (t = 0.5): the measurement is before the model"),
        (lambda d: d.assign(variable=["x1", "x3", "x1", "x2"]), "measure", "no response measure named 'x3'"),
        (lambda d: d.drop(columns="variable"), "data", "a time series needs the columns 't', 'variable'"),
    ],
)
def test_a_bad_time_series_is_refused_by_row_and_column(change, field, words):
    good = pd.DataFrame(
        {"t": [1.5, 2.0, 2.0, 2.5], "variable": ["x1", "x1", "x2", "x1"], "value": [3.0, 2.0, 1.0, 0.5]}
    )
    with pytest.raises(InputError) as refused:
        osc.calibrate("instance-1", change(good).reset_index(drop=True), {"mu_k": (0.05, 0.2)})
    assert refused.value.field == field and words in str(refused.value), str(refused.value)


#: Each number's difference step on the rattler: where the truncation error and the runs'
#: rounding balance (mu_k and Omega move its slip and impact times most).
RATTLER_STEPS = {"floor.mu_k": 1e-4, "floor.mu_s": 1e-3, "stop.K": 1e-3, "Omega": 1e-4}


def test_a_declared_systems_trajectory_sensitivities_through_stick_slip_and_impact_are_richardsons():
    """The rattler (docs/systems/rattler.toml) sticks, slips and strikes its stop: its state's
    derivatives at fixed times against Richardson differences of its runs, to 1e-7 of each plus
    the differences' resolution (its runs' rounding, 1e-10 at its orbits' tolerances, over the
    step); times 0.02 s or more from any event."""
    from oscillator.calibrating.series import chain_trajectory_sensitivities
    from oscillator.hybrid.chain_run import simulate_chain

    chain = osc.load_system(ROOT / "docs" / "systems" / "rattler.toml")
    events = simulate_chain(chain, t_end=20).events
    assert {"sticks", "slips", "stop_closes", "stop_opens"} <= set(events.kind)
    grid = np.linspace(0.5, 19.5, 40)
    times = np.array([t for t in grid if np.abs(events.t.to_numpy() - t).min() > 0.02])
    names = tuple(RATTLER_STEPS)
    states, derivatives, _ = chain_trajectory_sensitivities(chain, names, times)
    for j, name in enumerate(names):
        value = chain.value(name)
        step = RATTLER_STEPS[name] * max(abs(value), 1.0)

        def at(v, name=name):
            return chain_trajectory_sensitivities(chain.with_values({name: v}), (), times)[0]

        exact, differenced = derivatives[:, :, j], _richardson(at, value, step)
        bound = 1e-7 * np.maximum(np.abs(exact), 1e-3 * np.abs(states)) + 1e-10 / step
        assert (np.abs(exact - differenced) <= bound).all(), (name, np.abs(exact - differenced).max())


def test_a_declared_systems_friction_and_stop_are_recovered_from_a_measured_time_series(capsys, monkeypatch):
    """docs/calibration.md's declared system's time series: its block prints the block under it,
    and the truth lies inside every interval."""
    found = _page_block(capsys, monkeypatch, "## From a measured time series", "Its floor's two coefficients")["found"]
    assert found.success and _inside(found, {"floor.mu_k": 0.1, "floor.mu_s": 0.15, "stop.K": 50.0}).all(), found.table
    assert found.runs == found.evaluations


def test_a_declared_systems_event_times_derivatives_are_richardsons_differences():
    """The rattler's switch times (sticking, slipping, passing the floor's speed, the stop closing
    and opening) and ``dt_s/dc`` from its tangent pass, against Richardson differences of its runs'
    switch times: 1e-7 of each plus the differences' resolution (1e-10 over the step)."""
    from oscillator.calibrating.events import chain_event_sensitivities

    chain = osc.load_system(ROOT / "docs" / "systems" / "rattler.toml")
    names = tuple(RATTLER_STEPS)
    events = chain_event_sensitivities(chain, names, 20.0)
    assert {"sticks", "slips", "passable", "stop_closes", "stop_opens"} <= set(events.kind)
    for name in names:
        value = chain.value(name)
        step = RATTLER_STEPS[name] * max(abs(value), 1.0)

        def times(v, name=name):
            moved = chain_event_sensitivities(chain.with_values({name: v}), (), 20.0)
            assert moved.kind.tolist() == events.kind.tolist()  # the same sequence either side
            return moved.t.to_numpy()

        exact = events[f"dt/d{name}"].to_numpy()
        differenced = _richardson(times, value, step)
        assert (np.abs(exact - differenced) <= 1e-7 * np.abs(exact) + 1e-10 / step).all(), (
            name, np.abs(exact - differenced).max()
        )  # fmt: skip


def test_a_declared_systems_friction_and_stop_are_recovered_from_measured_stick_slip_and_impact_times(
    capsys, monkeypatch
):
    """docs/calibration.md's declared system's event times: its block prints the block under it,
    and the truth lies inside every interval."""
    namespace = _page_block(capsys, monkeypatch, "## From measured event times", "element` (a")
    found, picked = namespace["found"], namespace["picked"]
    assert found.success and _inside(found, {"floor.mu_k": 0.1, "floor.mu_s": 0.15, "stop.K": 50.0}).all(), found.table
    assert found.runs == found.evaluations and list(found.residuals.element) == list(picked.element)


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        (lambda d: d.assign(element=["floor", "wall", "floor"]), "element", "data row 2: element is 'wall'; give one"),
        (lambda d: d.assign(kind=["sticks", "grazing", "slips"]), "measure", "'grazing'"),
        (lambda d: d.rename(columns={"element": "mass"}), "data", "the fit does not read 'mass'"),
    ],
)
def test_a_declared_systems_bad_event_times_are_refused_by_row_and_column(change, field, words):
    chain = osc.load_system(ROOT / "docs" / "systems" / "rattler.toml")
    good = pd.DataFrame({"kind": ["sticks", "stop_closes", "slips"], "element": ["floor", "stop", "floor"],
                         "t": [1.0, 2.0, 3.0]})  # fmt: skip
    with pytest.raises(InputError) as refused:
        osc.calibrate(chain, change(good), {"floor.mu_k": (0.05, 0.12)})
    assert refused.value.field == field and words in str(refused.value), str(refused.value)


def test_the_worked_time_series_prints_what_the_page_shows(capsys, monkeypatch):
    """docs/calibration.md's second Python block prints the block under it."""
    _page_block(capsys, monkeypatch, "## From a measured time series")


# -- event times -------------------------------------------------------------------------------


def test_the_event_times_derivatives_are_richardsons_differences_of_the_runs_event_times():
    """``dt_s/dc`` at every switch of a run that strikes both stops, rests and slips again: 1e-7
    of the derivative plus the differences' resolution (the runs' rounding, 5e-12, over the step)."""
    from oscillator.calibrating.events import event_sensitivities

    case = osc.resolve_case("instance-1", **IMPACTING, **TIGHT)
    names = ("mu_k", "mu_s", "K3", "K6", "Omega")
    events = event_sensitivities(case, names, 10.0)
    assert {"left_contact_onset", "right_contact_onset", "sliding_onset", "sliding_vanish"} <= set(events.kind)
    for name in names:
        value = getattr(case.parameters, name)
        step = 1e-4 * max(abs(value), 1.0)

        def times(v, name=name):
            moved = event_sensitivities(osc.resolve_case(case, **{name: v}), (), 10.0)
            assert moved.kind.tolist() == events.kind.tolist()  # the same sequence either side
            return moved.t.to_numpy()

        exact = events[f"dt/d{name}"].to_numpy()
        differenced = _richardson(times, value, step)
        assert (np.abs(exact - differenced) <= 1e-7 * np.abs(exact) + 5e-12 / step).all(), name


def test_friction_and_a_stops_stiffness_are_recovered_from_measured_impact_and_rest_times():
    from oscillator.calibrating.events import event_sensitivities

    truth = osc.resolve_case("instance-1", **IMPACTING)
    events = event_sensitivities(truth, (), 16.0)
    kinds = ["left_contact_onset", "right_contact_onset", "sliding_onset"]
    picked = events[events.kind.isin(kinds) & (events.mass == 1)]
    noise = np.random.default_rng(5).normal(0, 1e-3, len(picked))
    data = pd.DataFrame({"kind": picked.kind, "mass": 1, "t": picked.t + noise, "sigma": 1e-3})
    found = osc.calibrate(osc.resolve_case(truth, mu_k=0.12, K3=2.4), data, {"mu_k": (0.05, 0.15), "K3": (1, 4)})
    assert found.success and _inside(found, {"mu_k": 0.1, "K3": 2.0}).all(), found.table
    assert found.runs == found.evaluations and abs(found.residuals.residual).max() < 4e-3


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        (lambda d: d.assign(kind=["left_contact_onset", "grazing", "sliding_onset"]), "measure", "'grazing'"),
        (lambda d: d.assign(mass=[1, 3, 1]), "mass", "data row 2: mass is 3; give one of 1, 2"),
        (lambda d: d.assign(t=[4.6, 4.5, 5.0]), "t", "data row 2: t = 4.5 s comes before row 1's 4.6 s"),
        (lambda d: d.assign(t=[0.5, 4.5, 5.0]), "t", "data row 1: t = 0.5 s is before the model's start 1 s"),
        (lambda d: d.assign(t=[4.6, np.nan, 5.0]), "value", "data row 2"),
        (lambda d: d.assign(time=1.0), "data", "the fit does not read 'time'"),
    ],
)
def test_bad_event_times_are_refused_by_row_and_column(change, field, words):
    good = pd.DataFrame({"kind": ["left_contact_onset", "right_contact_onset", "sliding_onset"], "t": [4.6, 4.9, 5.5]})
    with pytest.raises(InputError) as refused:
        osc.calibrate("instance-1", change(good.assign(mass=1)), {"mu_k": (0.05, 0.2)})
    assert refused.value.field == field and words in str(refused.value), str(refused.value)


# -- the command -------------------------------------------------------------------------------


def _invoke(*args):
    from typer.testing import CliRunner

    from oscillator.cli.app import app

    return CliRunner().invoke(app, [str(a) for a in args])


def test_the_command_fits_a_measurement_file_and_writes_what_the_library_finds(tmp_path):
    from oscillator.calibrating.events import event_sensitivities

    events = event_sensitivities(osc.resolve_case("instance-1", **IMPACTING), (), 16.0)
    kinds = ["left_contact_onset", "right_contact_onset", "sliding_onset"]
    picked = events[events.kind.isin(kinds) & (events.mass == 1)]
    noise = np.random.default_rng(5).normal(0, 1e-3, len(picked))
    pd.DataFrame({"kind": picked.kind, "mass": picked.mass, "t": picked.t + noise, "sigma": 1e-3}).to_csv(
        tmp_path / "measured.csv", index=False
    )
    start = {"d": 1, "d1": 3.5, "mu_k": 0.12, "K3": 2.4}
    sets = [a for name, v in start.items() for a in ("--set", f"{name}={v}")]
    done = _invoke("calibrate", "instance-1", tmp_path / "measured.csv", "--vary", "mu_k=0.05,0.15", "--vary",
                   "K3=1,4", *sets, "--out", tmp_path / "fit", "--no-plots")  # fmt: skip
    assert done.exit_code == 0, done.output
    assert "mu_k = 0.1" in done.stdout and "written to" in done.stdout
    library = osc.calibrate(osc.resolve_case("instance-1", **start), pd.read_csv(tmp_path / "measured.csv"),
                            {"mu_k": (0.05, 0.15), "K3": (1, 4)})  # fmt: skip
    written = pd.read_csv(tmp_path / "fit" / "estimate.csv", index_col="parameter")
    assert np.allclose(written.estimate, library.estimate, rtol=1e-12) and np.allclose(
        written.stderr, library.table.stderr
    )
    fitted = osc.load_case(tmp_path / "fit" / "fitted.toml")
    assert fitted.parameters.mu_k == pytest.approx(library.estimate.mu_k, rel=1e-12)
    residuals = pd.read_parquet(tmp_path / "fit" / "residuals.parquet")
    report = (tmp_path / "fit" / "report.md").read_text(encoding="utf-8")
    assert len(residuals) == len(picked) and f"K3 fitted to {len(picked)} measurements of event times" in report


def test_the_command_resumes_its_folder_and_says_how_much_it_read_back(tmp_path):
    data = _noisy(_responses((1.4, 1.6), ("x_pp_m1",)), 0.02, np.random.default_rng(9))
    data.to_csv(tmp_path / "measured.csv", index=False)
    command = ["calibrate", "instance-1", tmp_path / "measured.csv", "--vary", "mu_k=0.05,0.2", "--starts", "2",
               "--set", "d=1", "--set", "d1=3.5", "--out", tmp_path / "fit", "--no-plots"]  # fmt: skip
    first = _invoke(*command)
    assert first.exit_code == 0 and "resumed" not in first.output, first.output
    estimate = pd.read_csv(tmp_path / "fit" / "estimate.csv")
    (tmp_path / "fit" / "parts" / "start-001.parquet").unlink()
    (tmp_path / "fit" / "estimate.csv").unlink()
    again = _invoke(*command, "--level", "0.9")  # the intervals' level is not the fits': it resumes
    assert again.exit_code == 0 and "resumed: 1 starts read from" in again.stdout, again.output
    rewritten = pd.read_csv(tmp_path / "fit" / "estimate.csv")
    assert np.array_equal(rewritten.estimate, estimate.estimate) and np.array_equal(rewritten.stderr, estimate.stderr)
    assert (rewritten.ci_high - rewritten.ci_low < estimate.ci_high - estimate.ci_low).all()
    kept = json.loads((tmp_path / "fit" / "calibration.json").read_text(encoding="utf-8"))
    assert kept["status"] == "computed" and kept["level"] == 0.9 and kept["estimate"]["mu_k"] == estimate.estimate[0]
    other = _invoke(*command[:-3], "--out", tmp_path / "fit", "--loss", "huber")
    assert other.exit_code == 2 and "holds another calibration computation" in other.stderr, other.output


@pytest.mark.slow
def test_ctrl_c_between_starts_keeps_the_finished_ones_and_the_same_command_resumes(tmp_path):
    import signal

    from conftest import start_reaching

    _noisy(_responses((1.4, 1.6), ("x_pp_m1",)), 0.02, np.random.default_rng(9)).to_csv(
        tmp_path / "measured.csv", index=False
    )
    command = ["calibrate", "instance-1", "measured.csv", "--vary", "mu_k=0.05,0.2", "--starts", "3",
               "--set", "d=1", "--set", "d1=3.5", "--out", "fit", "--no-plots"]  # fmt: skip
    process = start_reaching("oscillator.calibrating.fit._start", command, call=2, cwd=tmp_path)  # one start done
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=120)
    assert process.returncode == 130, (out, err)
    assert err.strip().endswith("interrupted; the starts finished so far are kept: run the same command to resume")
    assert sorted(p.name for p in (tmp_path / "fit" / "parts").iterdir()) == ["start-000.parquet"]
    assert json.loads((tmp_path / "fit" / "calibration.json").read_text(encoding="utf-8"))["status"] == "running"
    again = subprocess.run([str(Path(sys.executable).with_name("oscillator")), *command], cwd=tmp_path,
                           capture_output=True, text=True, timeout=300)  # fmt: skip
    assert again.returncode == 0 and "resumed: 1 starts read from fit" in again.stdout, again.stdout + again.stderr
    assert len(pd.read_parquet(tmp_path / "fit" / "starts.parquet")) == 3


@pytest.mark.parametrize(
    ("text", "words"),
    [
        (
            "Omega,measure,value\n1.4,x_pp_m1,7.7\n1.5,x_pp_m1,oops\n1.6,x_pp_m1,7.8\n",
            "data row 2 (Omega = 1.5): value",
        ),
        ("\x00\x01binary", "measurement file"),
        ("Omega,measure,value\n", "holds no measurement"),
        ('Omega,measure,value\n1.4,"x_pp_m1\n', "is not a CSV table"),
    ],
)
def test_the_command_refuses_a_bad_measurement_file_in_one_line_and_writes_nothing(tmp_path, text, words):
    (tmp_path / "bad.csv").write_text(text, encoding="utf-8")
    done = _invoke("calibrate", "instance-1", tmp_path / "bad.csv", "--vary", "mu_k=0.05,0.15", "--out", tmp_path / "x")
    assert done.exit_code == 2 and words in done.stderr, done.output
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.output
    assert not (tmp_path / "x").exists()
    missing = _invoke("calibrate", "instance-1", tmp_path / "none.csv", "--vary", "mu_k=0.05,0.15")
    assert missing.exit_code == 2 and "cannot read measurement file" in missing.stderr


def test_text_from_a_measurement_file_is_printed_escaped(tmp_path):
    """A column or measure name holding a terminal escape or markup is data: printed escaped."""
    (tmp_path / "bad.csv").write_text(
        "Omega,measure,value,\x1b[31m[bold]red\n1.4,x_pp_m1,7.7,1\n1.5,x_pp_m1,7.8,1\n", encoding="utf-8"
    )
    done = _invoke("calibrate", "instance-1", tmp_path / "bad.csv", "--vary", "mu_k=0.05,0.15")
    assert done.exit_code == 2 and "a column the fit does not read" in done.stderr, done.output
    assert "\x1b" not in done.output and "[bold]red" in done.stderr
    (tmp_path / "bad.csv").write_text("Omega,measure,value\n1.4,\x1b]0;x\x07m,7.7\n1.5,x_pp_m1,7.8\n", encoding="utf-8")
    done = _invoke("calibrate", "instance-1", tmp_path / "bad.csv", "--vary", "mu_k=0.05,0.15")
    assert (
        done.exit_code == 2 and "data row 1" in done.stderr and "\x1b" not in done.output and "\x07" not in done.output
    )
