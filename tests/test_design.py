"""Robust design over an operating band (issue 39): the worked design of docs/design.md checked by
its constraint, a brute-force grid and the simulations it took; bad input refused with the field;
an infeasible problem reported, not refined."""

from __future__ import annotations

import numpy as np
import pytest

import oscillator as osc
from oscillator.attractors.mapping import AttractorSettings
from oscillator.designing.judging import Judged, survey
from oscillator.errors import InputError

#: docs/design.md's problem: the right stop's distance and stiffness that make Instance 1's largest
#: displacement of m1 over Omega in [1.4, 1.6] smallest, with impacts on the stop no faster than 5 m/s and m2
#: resting at most 1 % of the period.
VARY = {"d1": (2.5, 4.5), "K6": (1.0, 40.0)}
OVER = {"Omega": (1.4, 1.6)}
QUICK = AttractorSettings(transient=100, record=8)
SMALL = {"band": 3, "starts": 2, "candidates": 8, "settings": QUICK}


@pytest.fixture(scope="module")
def worked():
    return osc.design("instance-1", VARY, OVER, "x_max_m1", ["impact_max_right <= 5", "rest_m2 <= 0.01"], **SMALL)


def test_the_optimum_sits_on_its_constraint_and_its_bound(worked):
    """A closer stop limits m1 but is struck faster: the optimum puts the worst impact speed over
    the band exactly at its limit, with the stiffest stop allowed; the refinement lowered the
    global search's best, and the check from fresh starts agrees with the followed value."""
    assert worked.best.feasible and worked.values["K6"] == pytest.approx(40.0, abs=1e-9)
    assert 3.3 < worked.values["d1"] < 3.5
    impact = max(s.value("impact_max_right") for s in worked.best.seen)
    assert impact == pytest.approx(5.0, abs=1e-6)
    assert worked.best.objective < worked.start.objective - 0.01
    followed = worked.history[worked.history.how == "followed"].objective.min()
    assert worked.best.objective == pytest.approx(followed, rel=1e-7)
    assert worked.runs["global"] == worked.candidates.runs.sum() > 0 and worked.runs["refine"] > 0


def test_no_candidate_of_the_global_search_beats_the_optimum(worked):
    """Every feasible candidate surveyed is worse than the refined design."""
    feasible = worked.candidates[worked.candidates.violation == 0]
    assert len(feasible) and (feasible.objective >= worked.best.objective).all()


@pytest.mark.slow
def test_a_brute_force_grid_finds_its_best_within_one_step_of_the_optimum(worked):
    """An independent 6 x 6 grid over (d1, K6), each design judged from fresh starts: its best
    feasible design is within one grid step of the optimiser's and no better."""
    problem = worked.problem
    axes = [np.linspace(low, high, 6) for _, low, high in problem.vary]
    judged = [survey(problem, QUICK, np.array([a, b])) for a in axes[0] for b in axes[1]]
    best = min((j for j in judged if j.feasible), key=Judged.key)
    step = (problem.upper - problem.lower) / 5
    assert (np.abs(best.design - worked.best.design) <= step + 1e-12).all()
    assert best.objective >= worked.best.objective - 1e-9


def test_an_infeasible_problem_is_reported_with_the_fix_and_not_refined():
    found = osc.design("instance-1", VARY, OVER, "x_max_m1", ["x_max_m1 <= 1"], **SMALL)
    assert not found.best.feasible and found.best.violation > 2
    assert "no candidate of the global search meets the constraints" in found.message
    assert "relax `constraints`" in found.message and found.runs["refine"] == 0


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        ({"vary": {"d2": (1, 2)}}, "vary", "'d2' is not a parameter"),
        ({"vary": {"d1": (4, 3)}}, "vary", "is empty; give low < high"),
        ({"vary": {}}, "vary", "vary must map parameters"),
        ({"over": {"Omega": (1, 2), "Q2": (1, 2)}}, "over", "one parameter"),
        ({"over": {"d1": (3, 4)}}, "over", "d1 is varied too"),
        ({"objective": "impact"}, "objective", "is not a response measure"),
        ({"constraints": ["impact_max_right < 5"]}, "constraints", "write 'measure <= value'"),
        ({"constraints": ["rest_m3 <= 0"]}, "constraints", "is not a response measure"),
        ({"candidates": 0}, "candidates", "candidates"),
        ({"objective": ["x_max_m1", "x_pp_m1", "x_max_m2"]}, "objective", "two different ones"),
        ({"objective": ["x_max_m1", "x_max_m1"]}, "objective", "two different ones"),
    ],
)
def test_bad_input_is_refused_with_the_field_and_the_fix(change, field, words):
    arguments = {"vary": VARY, "over": OVER, "objective": "x_max_m1", "constraints": ["impact_max_right <= 5"]}
    arguments |= change
    options = dict(SMALL) | {key: value for key, value in change.items() if key == "candidates"}
    arguments.pop("candidates", None)
    with pytest.raises(InputError, match=words) as refused:
        osc.design("instance-1", **arguments, **options)
    assert refused.value.field == field


def test_an_interrupted_design_keeps_its_surveys_and_resumes_to_the_same_design(tmp_path, worked):
    """Ctrl-C during the global search: the surveys finished are kept; the same design into the
    same folder reads them back and ends where an uninterrupted run does."""
    from oscillator.designing.optimise import design_store
    from oscillator.designing.problem import Problem

    constraints = ["impact_max_right <= 5", "rest_m2 <= 0.01"]
    problem = Problem.of("instance-1", VARY, OVER, "x_max_m1", constraints, band=3, starts=2)

    def store():
        return design_store(tmp_path / "design", problem, QUICK, 8)

    def stop(done, total):
        if done == 10:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        osc.design("instance-1", VARY, OVER, "x_max_m1", constraints, **SMALL, store=store(), progress=stop)
    assert len(list((tmp_path / "design" / "parts").glob("survey-*.parquet"))) == 10  # kept before the report
    again = store()
    resumed = osc.design("instance-1", VARY, OVER, "x_max_m1", constraints, **SMALL, store=again)
    assert again.reused == 10 and resumed.runs == worked.runs
    assert np.array_equal(resumed.best.design, worked.best.design) and resumed.best.objective == worked.best.objective


def test_the_command_writes_its_folder_with_an_escaped_report_and_resumes(tmp_path, capsys):
    """`oscillator design` on a case file whose name is markup: tables, best.json as the library's
    design, figures, a report that shows the name as text; the same command again resumes."""
    import json
    from pathlib import Path

    from oscillator.cli.app import main

    hostile = tmp_path / "<img src=x onerror=alert(1)>.toml"
    hostile.write_text((Path(__file__).parents[1] / "cases" / "instance-1.toml").read_text(encoding="utf-8"))
    out = tmp_path / "out"
    args = [
        "design", str(hostile), "--vary", "d1=2.5,4.5", "--vary", "K6=1,40", "--over", "Omega", "1.4", "1.6",
        "--objective", "x_max_m1", "--constraint", "impact_max_right <= 5", "--band", "2", "--starts", "1",
        "--candidates", "4", "--transient", "100", "--record", "8", "--workers", "1", "--out", str(out),
    ]  # fmt: skip
    for extra in ([], ["--no-plots"]):  # the figures once
        with pytest.raises(SystemExit) as done:
            main([*args, *extra])
        assert done.value.code == 0
    printed = capsys.readouterr()
    assert "resumed: 8 surveys read" in printed.err + printed.out
    best = json.loads((out / "best.json").read_text(encoding="utf-8"))
    assert best["feasible"] and best["design"]["K6"] == pytest.approx(40.0)
    assert 3.40 < best["design"]["d1"] < 3.5 and best["runs"]["global"] > 0
    assert {p.name for p in (out / "figures").glob("*.png")} == {"design-search.png", "design-response.png"}
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "<img src=x" not in html and "&lt;img src=x onerror=alert(1)&gt;" in html
    # a survey part replaced by another candidate's gave another "best" design, exit 0; strings
    # in its numbers a traceback: each refused naming the part, before anything is computed
    from conftest import rewritten

    parts = out / "parts"
    original = (parts / "survey-0000-000.parquet").read_bytes()
    (parts / "survey-0000-000.parquet").write_bytes((parts / "survey-0001-000.parquet").read_bytes())
    rewritten(parts / "survey-0002-001.parquet", lambda frame: frame.assign(x_max_m1="big"))
    for name, said in (("survey-0000-000", "it holds another task's result"), ("survey-0002-001", "is not numbers")):
        with pytest.raises(SystemExit) as done:
            main([*args, "--no-plots"])
        error = capsys.readouterr().err
        assert done.value.code == 2 and f"{name}.parquet is damaged (" in error and said in error, error
        (parts / "survey-0000-000.parquet").write_bytes(original)


@pytest.mark.parametrize(
    ("flags", "words"),
    [
        (["--vary", "d1=2.5"], "--vary 'd1=2.5': write NAME=LOW,HIGH"),
        (["--vary", "d1=2.5,4.5", "--objective", "x_max"], "--objective: 'x_max' is not a response measure"),
        (["--vary", "d1=4,3"], "--vary: d1's range (4, 3) is empty"),
        (["--vary", "d1=2.5,4.5", "--constraint", "x_max_m1 < 3"], "--constraint: 'x_max_m1 < 3' is not a bound"),
        (["--vary", "d1=2.5,4.5", "--candidates", "0"], "--candidates"),
        # a bound that is not a number (a traceback); ranges the model refuses (a folder left
        # marked running, and a generated candidate named instead of the option)
        (["--vary", "d1=2.5,4.5", "--constraint", "x_max_m1 <= e"], "--constraint: 'x_max_m1 <= e': 'e' is not a"),
        (["--vary", "m1=-1,2"], "--vary: the model refuses m1 = -1"),
        (["--vary", "mu_k=0.1,0.3"], "--vary: the model refuses mu_k = 0.3 (parameters.mu_s must be >= mu_k"),
        (["--vary", "d1=2.5,4.5", "--over", "Omega", "0", "1"], "--over: the model refuses Omega = 0"),
    ],
)
def test_the_command_refuses_bad_input_with_the_flag(tmp_path, capsys, flags, words):
    from oscillator.cli.app import main

    base = ["design", "instance-1", "--out", str(tmp_path / "d")]
    if "--over" not in flags:
        flags = [*flags, "--over", "Omega", "1.4", "1.6"]
    if "--objective" not in flags:
        flags = [*flags, "--objective", "x_max_m1"]
    with pytest.raises(SystemExit) as done:
        main([*base, *flags])
    assert done.value.code == 2 and words in capsys.readouterr().err
    assert not (tmp_path / "d").exists()


def test_a_band_value_where_every_start_fails_is_the_worst_case():
    """It added nothing to the worst case (a design judged on the values it could run); now it is
    the worst, and a design where every start fails everywhere is an error naming the failures,
    not a design with no objective called feasible."""
    from oscillator.designing.judging import Seen, survey_task
    from oscillator.designing.problem import Problem
    from oscillator.errors import SimulationFailed

    problem = Problem.of(osc.resolve_case("instance-1", max_num_steps=5), VARY, OVER, "x_max_m1", band=2, starts=1)
    (failed,), runs = survey_task(problem, QUICK, (3.5, 20.0), 1.5)
    assert failed.period == 0 and "max_num_steps" in failed.failure and runs >= 1
    fine = Seen(1.4, 1, np.zeros(4), {"x_max_m1": 3.0})
    judged = Judged.of(problem, np.array([3.5, 20.0]), [fine, failed], 2, "survey")
    assert judged.objective == np.inf and judged.key() > Judged.of(problem, judged.design, [fine], 1, "survey").key()
    with pytest.raises(SimulationFailed, match=r"every start failed at every band value of all 2 candidates") as error:
        osc.design(problem.case, VARY, OVER, "x_max_m1", band=2, starts=1, candidates=2, settings=QUICK)
    assert "max_num_steps" in str(error.value)


def test_the_documented_example_finds_the_documented_design(worked):
    """docs/design.md's Python block, run as shown: the design the page reports."""
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "design.md").read_text(encoding="utf-8")
    scope: dict = {}
    exec(compile(page.split("```python\n", 1)[1].split("```", 1)[0], "docs/design.md", "exec"), scope)
    found = scope["found"]
    assert found.values == pytest.approx(worked.values, rel=1e-9)
    assert f"`d1 = {found.values['d1']:.8g}`" in page and f"{found.best.objective:.8g} m" in page
    assert f"| {found.runs['refine']} (" in page and f"| {found.runs['global']} |" in page


# 9.6 s, the default tier's longest call: in the slow tier, which CI runs, until the design's
# orbits run on the compiled path (issue 53).
@pytest.mark.slow
def test_two_objectives_give_a_pareto_front_whose_refined_points_meet_their_bounds():
    """Amplitude against impact speed: the front runs from the stop out of reach (no impact) to
    the closest, stiffest stop; no point beats another in both; each refined point's impact speed
    sits on the bound it was refined under, and the design minimising the amplitude alone ends it."""
    from oscillator.designing.front import non_dominated

    found = osc.design("instance-1", VARY, OVER, ["x_max_m1", "impact_max_right"], **SMALL, front=5)
    front = found.front
    assert len(front) >= 4 and non_dominated(front[["objective", "second"]].to_numpy()).all()
    assert front.second.is_monotonic_increasing and front.objective.is_monotonic_decreasing
    assert front.second.iloc[0] == 0 and front.objective.iloc[0] == pytest.approx(3.9, abs=0.01)
    bounded = front[front.eps.notna()]
    assert len(bounded) >= 2 and np.allclose(bounded.second, bounded.eps, rtol=1e-6)
    assert front.iloc[-1][["d1", "K6"]].tolist() == pytest.approx(list(found.values.values()))
    assert found.values == pytest.approx({"d1": 2.5, "K6": 40.0})  # the amplitude alone: the closest, stiffest stop


def test_the_pareto_front_keeps_what_no_other_design_beats():
    from oscillator.designing.front import non_dominated

    points = np.array([[1.0, 5.0], [2.0, 4.0], [2.0, 4.0], [3.0, 4.5], [4.0, 1.0], [1.0, 6.0]])
    assert non_dominated(points).tolist() == [True, True, False, False, True, False]


def test_a_design_saves_reads_back_and_rebuilds_its_report(tmp_path, worked, monkeypatch):
    """``save`` writes the command's folder; ``read_run`` gives back the same design (the problem,
    the design found and the global search's best with their attractors, the tables, the runs),
    computing nothing; ``oscillator report`` writes its tables, figures and report again; in
    Jupyter the case's name is text."""
    import dataclasses
    import json

    import pandas as pd

    import oscillator.designing.optimise as computing
    import oscillator.report.design as drawing
    from oscillator.report.kinds import rebuild

    monkeypatch.setattr(computing, "survey", None)  # reading computes nothing
    folder = worked.save(tmp_path / "design")
    back = osc.read_run(folder)
    assert dataclasses.replace(back.problem, case=worked.problem.case) == worked.problem
    assert back.problem.case.name == "instance-1" and back.settings == worked.settings
    assert back.values == worked.values and (back.runs, back.message) == (worked.runs, worked.message)
    for name in ("candidates", "history"):
        pd.testing.assert_frame_equal(getattr(back, name), getattr(worked, name), check_exact=True, check_dtype=False)
    for a, b in ((back.best, worked.best), (back.start, worked.start)):
        assert np.array_equal(a.design, b.design) and (a.objective, a.violation, a.runs, a.how) == (
            b.objective, b.violation, b.runs, b.how
        )  # fmt: skip
        assert a.worst == b.worst and len(a.seen) == len(b.seen) > 0
        for x, y in zip(a.seen, b.seen, strict=True):
            assert (x.band, x.period, x.failure) == (y.band, y.period, y.failure) and np.array_equal(x.state, y.state)
            assert np.array_equal(list(x.measures.values()), list(y.measures.values()), equal_nan=True)
    monkeypatch.setattr(drawing, "RESPONSE_VALUES", 2)  # the responses before and after at two values
    (folder / "report.md").unlink()
    what, problems = rebuild(folder)
    assert what == "the design" and problems == [] and (folder / "report.md").is_file()
    assert (folder / "figures" / "design-response.png").is_file()
    marker = folder / "design.json"
    stored = json.loads(marker.read_text())
    marker.write_text(json.dumps(stored | {"format": stored["format"] - 1}))  # an earlier version's folder
    with pytest.raises(InputError, match=r"written by another version of oscillator .* with a new --out"):
        osc.read_run(folder)
    marker.write_text(json.dumps(stored))
    (folder / "best.json").write_text('{"judged": {}}')
    with pytest.raises(InputError, match=r"best.json is damaged"):
        osc.read_run(folder)
    shown = dataclasses.replace(worked, problem=dataclasses.replace(worked.problem, case=dataclasses.replace(
        worked.problem.case, name="<script>")))  # fmt: skip
    assert "<script>" not in shown._repr_html_() and "&lt;script&gt;" in shown._repr_html_()


@pytest.mark.parametrize("store", ["frequency", "design"])
def test_a_resumable_folder_of_an_earlier_format_is_refused_as_another_versions(tmp_path, store):
    """A frequency response's or a design's folder written before its parts gained the impulses and
    force_rms is refused as another version's, not read part by part as damaged."""
    import json

    from oscillator.attractors.frequency_parts import FrequencyStore
    from oscillator.designing.optimise import DesignStore
    from oscillator.errors import InputError

    kind = FrequencyStore if store == "frequency" else DesignStore
    identity = {"case": "[parameters]\nOmega = 1.5\n", "settings": {"band": 3}}
    kind(tmp_path / "f", identity).open()
    marker = next(path for path in (tmp_path / "f").glob("*.json"))
    again = kind(tmp_path / "f", identity)
    again.check()  # this version's folder resumes
    assert again.resuming
    stored = json.loads(marker.read_text())
    marker.write_text(json.dumps(stored | {"format": kind.FORMAT - 1}))
    with pytest.raises(InputError, match="written by another version of oscillator"):
        kind(tmp_path / "f", identity).check()
