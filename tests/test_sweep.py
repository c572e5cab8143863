"""Sweeps: the same rows on every backend, resuming after a kill, and locating a known change."""

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from conftest import assert_same_tables, make_case, start_reaching
from oscillator import OscillatorError, SweepSettings, load_case
from oscillator.analysis.locate import locate
from oscillator.analysis.periods import detect_period
from oscillator.analysis.sweep_points import TABLES, run_point, sliding_ranges
from oscillator.analysis.sweeps import read_sweep, run_sweep

SMALL = dict(param="Omega", start=1.55, stop=1.7, steps=4, transient=4, record=3)


@pytest.fixture(scope="module")
def case():
    return load_case("bifurcation-omega")


@pytest.fixture(scope="module")
def serial(case, tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweeps") / "serial"
    run_sweep(case, SweepSettings(**SMALL), folder, workers=1)
    return read_sweep(folder)


def test_tables_carry_the_swept_parameter_and_a_sliding_flag(serial):
    for name in TABLES:
        assert serial[name].columns[0] == "Omega"
    summary = serial["summary"]
    assert summary.sliding.dtype == bool and list(summary.index) == [0, 1, 2, 3]
    np.testing.assert_allclose(summary.Omega, [1.55, 1.6, 1.65, 1.7])
    # Instance 1's parameters at Omega = 1.6: m2 rests on its velocity boundary every period
    row = summary[np.isclose(summary.Omega, 1.6)].iloc[0]
    assert row.sliding and row.sliding_periods == 3 and row.rest_time_per_period > 0
    switches = serial["switches"]
    at = switches[np.isclose(switches.Omega, 1.6)]
    assert {"sliding_onset", "sliding_vanish"} <= set(at.kind)
    assert ((at.phase >= 0) & (at.phase < 2 * math.pi)).all()
    poincare = serial["poincare"]
    assert len(poincare) == 4 * 3 and set(poincare.n) == {4, 5, 6}  # one per recorded period


def test_process_pool_gives_the_same_rows(case, serial, tmp_path):
    run_sweep(case, SweepSettings(**SMALL), tmp_path / "pool", workers=2)
    assert_same_tables(serial, read_sweep(tmp_path / "pool"))


def test_dask_local_cluster_gives_the_same_rows(case, serial, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        run_sweep(case, SweepSettings(**SMALL), tmp_path / "dask", scheduler=cluster.scheduler_address)
    assert_same_tables(serial, read_sweep(tmp_path / "dask"))


def test_a_finished_sweep_is_not_run_again(case, tmp_path):
    settings = SweepSettings(**{**SMALL, "steps": 2})
    first = run_sweep(case, settings, tmp_path / "s", workers=1)
    again = run_sweep(case, settings, tmp_path / "s", workers=1)
    assert (first.computed, again.computed, again.resumed) == (2, 0, 2)


def test_a_killed_sweep_resumes_to_the_same_result(case, tmp_path):
    settings = dict(param="Omega", start=1.5, stop=1.7, steps=10, transient=6, record=3)
    reference = tmp_path / "reference"
    run_sweep(case, SweepSettings(**settings), reference, workers=1)
    folder = tmp_path / "killed"
    arguments = ["sweep", "bifurcation-omega", "--param", "Omega", "--from", "1.5", "--to", "1.7", "--steps", "10",
                 "--transient", "6", "--record", "3", "--workers", "1", "--quiet", "--no-plots",
                 "--out", folder]  # fmt: skip
    process = start_reaching("oscillator.analysis.sweep_points.run_point", arguments, call=4)  # 3 points done
    process.kill()
    process.communicate()
    finished_before = len(list(folder.glob("parts/*.summary.parquet")))
    assert finished_before == 3, finished_before
    outcome = run_sweep(case, SweepSettings(**settings), folder, workers=1)
    assert outcome.resumed == finished_before and outcome.computed == 10 - finished_before
    assert_same_tables(read_sweep(reference), read_sweep(folder))


def test_a_folder_of_another_sweep_is_refused(case, tmp_path):
    run_sweep(case, SweepSettings(**{**SMALL, "steps": 1}), tmp_path / "s", workers=1)
    with pytest.raises(OscillatorError, match="holds another sweep computation"):
        run_sweep(case, SweepSettings(**{**SMALL, "steps": 1, "record": 4}), tmp_path / "s", workers=1)


@pytest.mark.parametrize(
    ("damage", "said"),
    [
        ("another point's summary", "it holds another task's result"),
        ("the value x1000", "its rows are not point 1's"),
        ("a row twice", "it has 2 rows, where its task has 1"),
    ],
)
def test_a_part_that_is_not_its_points_is_refused_by_name(case, tmp_path, damage, said):
    """A point's part replaced by another point's, or its value changed, or its row twice: it was
    merged into the tables; it is refused naming the part, when the sweep resumes."""
    from conftest import rewritten

    settings = SweepSettings(**{**SMALL, "steps": 3})
    run_sweep(case, settings, tmp_path / "s", workers=1)
    part = tmp_path / "s" / "parts" / "000001.summary.parquet"
    if damage == "another point's summary":
        part.write_bytes(part.with_name("000002.summary.parquet").read_bytes())
    elif damage == "the value x1000":
        rewritten(part, lambda frame: frame.assign(Omega=1000 * frame.Omega))
    else:
        rewritten(part, lambda frame: pd.concat([frame, frame]))
    with pytest.raises(OscillatorError, match=r"000001\.summary\.parquet is damaged \(") as refused:
        run_sweep(case, settings, tmp_path / "s", workers=1)
    assert said in str(refused.value)


def test_a_refused_value_is_a_failed_row_not_a_crash(case):
    point = run_point(case, SweepSettings(param="mu_s", start=0.05, stop=0.2, steps=2), 0, 0.05)
    row = point.summary.iloc[0]
    assert row.status == "failed" and "mu_s must be >= mu_k" in row.message and point.switches.empty


def test_detect_period():
    cycle = np.array([[0.0, 1.0], [1.0, 0.0], [0.5, 0.5]])
    points = np.vstack([cycle] * 4)
    assert detect_period(points, 1e-9, 16) == 3
    assert detect_period(points + np.random.default_rng(0).normal(0, 1e-3, points.shape), 1e-9, 16) == 0
    assert detect_period(np.ones((5, 2)), 1e-9, 16) == 1


def test_sliding_ranges():
    summary = pd.DataFrame({"Q2": [1.0, 2.0, 3.0, 4.0, 5.0], "status": "ok",
                            "sliding": [False, True, True, False, True]})  # fmt: skip
    assert sliding_ranges(summary, "Q2") == [(2.0, 3.0), (5.0, 5.0)]


def test_locate_finds_a_closed_form_grazing_to_1e_8():
    """m1 linear (no friction, no feedback), damped and forced: its steady amplitude reaches the
    right stop d1 = 1 at Q1* = d1 sqrt((K1 - m1 Omega^2)^2 + (C1 Omega)^2) = sqrt(10); above it a
    pair of contact switches a period appears (a grazing bifurcation of the right stop)."""
    case = make_case(1.0, initial=(0.0, 0.0, 0.1, 0.0, 0.0), K1=4.0, C1=1.0, mu_k=0.0, mu_s=0.01, Omega=1.0,
                     d1=1.0, d=100.0)  # fmt: skip
    settings = SweepSettings(param="Q1", start=3.0, stop=3.3, steps=2, transient=8, record=2, mass=1)
    found = locate(case, settings, "grazing", (3.0, 3.3), tolerance=1e-8)
    assert found.width <= 1e-8
    assert found.value == pytest.approx(math.sqrt(10.0), abs=1e-8)
    assert "right_contact_onset" in set(found.evidence_above.kind)
    assert "right_contact_onset" not in set(found.evidence_below.kind)


def test_locate_refuses_a_bracket_without_a_change(case):
    settings = dataclasses.replace(case.sweep, transient=3, record=2)
    with pytest.raises(OscillatorError, match="is the same at"):
        locate(case, settings, "sliding", (1.3, 1.31))


BOTH_WAYS = dict(param="Q2", start=71.15, stop=71.18, steps=7, transient=20, record=4, both_ways=True)


def test_a_both_ways_sweep_shows_the_hysteresis_of_the_sliding_bifurcation(tmp_path):
    """At Omega = 1.6 the orbit in which m2 rests lives up to Q2 = 71.17025 and the orbit without
    rest down to 71.1577416 (located by continuation): between them both are stable.  Going up
    from Instance 1's start, each value from the last one's end, m2 keeps resting to 71.17;
    coming back down it keeps sliding through, to rest again only below 71.1577."""
    case = load_case("bifurcation-q2")
    settings = SweepSettings(**BOTH_WAYS)
    assert [d for d, _ in settings.points] == ["up"] * 7 + ["down"] * 7
    run_sweep(case, settings, tmp_path / "both", workers=1)
    summary = read_sweep(tmp_path / "both")["summary"]
    assert sliding_ranges(summary, "Q2", "up") == [(71.15, 71.17)]
    assert sliding_ranges(summary, "Q2", "down") == [(71.15, 71.155)]
    # each value started where the one before it ended: the state at the turn is handed on
    turn = summary.set_index("index").loc[[6, 7]]
    assert turn.Q2.tolist() == [71.18, 71.18] and np.allclose(
        turn[["end_x1", "end_v1", "end_x2", "end_v2"]].diff().iloc[1], 0, atol=1e-6
    )


def test_a_both_ways_sweep_resumes_from_the_state_it_stopped_in(tmp_path):
    case = load_case("bifurcation-q2")
    settings = SweepSettings(**BOTH_WAYS)
    run_sweep(case, settings, tmp_path / "whole", workers=1)

    def stop_after_nine(done, total):
        if done == 9:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(case, settings, tmp_path / "resumed", workers=1, progress=stop_after_nine)
    run_sweep(case, settings, tmp_path / "resumed", workers=1)
    whole, resumed = read_sweep(tmp_path / "whole"), read_sweep(tmp_path / "resumed")
    for name in TABLES:
        columns = [c for c in whole[name].columns if c != "wall_time"]
        pd.testing.assert_frame_equal(whole[name][columns], resumed[name][columns])


def test_both_ways_must_be_a_flag():
    with pytest.raises(OscillatorError, match=r"sweep\.both_ways must be true or false"):
        SweepSettings(**{**BOTH_WAYS, "both_ways": "yes"})
