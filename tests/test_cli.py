"""The ``oscillator`` command, driven through typer's CliRunner: every command, every bad input."""

import json
import os
import re
import textwrap

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from oscillator import Event, SolverOptions, load_case, simulate
from oscillator.cli.app import app
from oscillator.report.runs import read_events_csv

runner = CliRunner()


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def instance_3_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("runs") / "i3"
    result = invoke("run", "instance-3", "--out", folder)
    assert result.exit_code == 0, result.stderr
    return folder, result


def assert_refused(result, *fragments, folder=None):
    """Exit 2, one line on stderr naming the field, no traceback, nothing written."""
    assert result.exit_code == 2, (result.stdout, result.stderr)
    message = result.stderr.strip()
    assert message.startswith("error:") and "\n" not in message, message
    assert "Traceback" not in result.stdout + result.stderr
    for fragment in fragments:
        assert fragment in message, message
    if folder is not None:
        assert not folder.exists()
        assert not [p for p in folder.parent.iterdir() if p.name.startswith(f".{folder.name}")]


# ----------------------------------------------------------------------------- commands


def test_list_names_every_case_with_its_title():
    result = invoke("list")
    assert result.exit_code == 0
    for i in range(1, 6):
        assert f"instance-{i}" in result.stdout
    assert "grazes" in result.stdout


def test_show_prints_parameters_start_and_expected_events():
    result = invoke("show", "instance-2")
    assert result.exit_code == 0
    assert "mu_k" in result.stdout and "0.15" in result.stdout
    assert "t0 = 3.0 s" in result.stdout and "expected events" in result.stdout and "3.813" in result.stdout


def test_run_writes_every_file(instance_3_run):
    folder, result = instance_3_run
    names = {p.name for p in folder.iterdir()}
    assert {"events.csv", "events.parquet", "trajectory.parquet", "case.toml", "run.json", "figures",
            "report.md", "report.html"} <= names  # fmt: skip
    figures = {p.name for p in (folder / "figures").iterdir()}
    for panel in ("a-displacement", "b-velocity", "c-phase", "d-forces"):
        assert {f"fig-{panel}.png", f"fig-{panel}.svg"} <= figures
    assert "left_contact_onset" in result.stdout and "6/6" in result.stdout


def test_written_tables_read_back_equal_to_the_result(instance_3_run):
    folder, _ = instance_3_run
    expected = simulate("instance-3").events
    from_parquet = pd.read_parquet(folder / "events.parquet")
    pd.testing.assert_frame_equal(from_parquet, expected)
    from_csv = read_events_csv(folder / "events.csv")
    assert list(from_csv.columns) == list(expected.columns)
    numeric = expected.select_dtypes("number").columns
    np.testing.assert_array_equal(from_csv[numeric].to_numpy(), expected[numeric].to_numpy())  # exact round trip
    for column in Event.text_columns():
        assert from_csv[column].tolist() == expected[column].tolist(), column
    trajectory = pd.read_parquet(folder / "trajectory.parquet")
    pd.testing.assert_frame_equal(trajectory, simulate("instance-3").trajectory)


def test_case_toml_repeats_the_run_exactly(instance_3_run, tmp_path):
    folder, _ = instance_3_run
    again = simulate(folder / "case.toml")
    pd.testing.assert_frame_equal(again.events, pd.read_parquet(folder / "events.parquet"))
    assert load_case(folder / "case.toml").expected == load_case("instance-3").expected


def test_run_json_records_versions_settings_and_audit(instance_3_run):
    folder, _ = instance_3_run
    info = json.loads((folder / "run.json").read_text())
    assert info["status"] == "complete" and info["case"] == "instance-3"
    assert info["versions"]["scikit-sundae"] and info["versions"]["oscillator"]
    assert info["solver"]["rtol"] == SolverOptions().rtol and info["counts"]["events"] == 8
    assert abs(info["energy"]["residual"]) < 1e-6 and info["wall_time"] > 0
    assert info["check"] == {"expected": 6, "within_tolerance": 6}


def test_report_tells_the_run_as_a_transition_log(instance_3_run):
    folder, _ = instance_3_run
    text = (folder / "report.md").read_text()
    assert "t = 3.0214 s — left contact starts on ∂Ω15(1)" in text and "(Theorem 5.8, Eq. 5.50)" in text
    assert "## Time in each domain" in text and "## Energy audit" in text and "## Comparison with the article" in text
    html = (folder / "report.html").read_text()
    assert html.count("data:image/png;base64,") == 4 and "<table>" in html and "figures/" not in html


def test_run_options(tmp_path):
    folder = tmp_path / "quiet"
    result = invoke("run", "instance-1", "--out", folder, "--format", "csv", "--no-plots", "--no-report", "--quiet",
                    "--t-end", "1.5", "--set", "Omega=1.7", "--set", "P1=pi/8")  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert result.stdout.strip() == str(folder)
    assert {p.name for p in folder.iterdir()} == {"events.csv", "trajectory.parquet", "case.toml", "run.json"}
    case = load_case(folder / "case.toml")
    assert case.parameters.Omega == 1.7 and case.t_end == 1.5


def test_default_output_folder_is_under_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = invoke("run", "instance-1", "--no-plots", "--no-report", "--quiet")
    assert result.exit_code == 0
    (folder,) = (tmp_path / "runs").iterdir()
    assert folder.name.startswith("instance-1-") and (folder / "events.parquet").exists()


@pytest.mark.parametrize("name", [f"instance-{i}" for i in range(1, 6)])
def test_check_passes_for_the_instances(name):
    result = invoke("check", name)
    assert result.exit_code == 0, result.stdout + result.stderr
    assert "within tolerance" in result.stdout


def test_check_fails_when_a_time_is_out_of_tolerance(tmp_path):
    path = tmp_path / "moved.toml"  # Instance 3 started 0.1 m off, its expectations kept
    path.write_text(load_case("instance-3").source.read_text().replace("x1 = 3.5", "x1 = 3.6"))
    result = invoke("check", path)
    assert result.exit_code == 1
    assert "out of tolerance" in result.stderr


def test_check_refuses_a_changed_case_but_takes_solver_options():
    refused = invoke("check", "instance-3", "--set", "x1=3.6")
    assert refused.exit_code == 2 and "--set changes the case (x1 3.5 → 3.6)" in refused.stderr
    assert invoke("check", "instance-3", "--set", "rtol=1e-11").exit_code == 0


def test_a_changed_case_is_not_scored_against_the_article(tmp_path):
    folder = tmp_path / "changed"
    result = invoke("run", "instance-1", "--t-end", "3", "--set", "Omega=1.7", "--no-plots", "--out", folder)
    assert result.exit_code == 0, result.stderr
    assert "modified case (Omega 1.6 → 1.7): the expected times of the case as written are not compared" in (
        result.stdout
    )
    assert "within tolerance" not in result.stdout
    saved = load_case(folder / "case.toml")
    assert saved.expected == () and saved.title.endswith("(modified: Omega 1.6 → 1.7)")
    report = (folder / "report.md").read_text()
    assert "**Modified case:** Omega 1.6 → 1.7" in report and "Comparison with the article" not in report
    assert "(modified: Omega 1.6 → 1.7)" in report.splitlines()[0]


def test_report_rebuilds_from_the_folder(instance_3_run):
    folder, _ = instance_3_run
    before = (folder / "report.md").read_text()
    (folder / "report.md").unlink()
    (folder / "report.html").unlink()
    result = invoke("report", folder)
    assert result.exit_code == 0, result.stderr
    assert (folder / "report.md").read_text() == before and (folder / "report.html").exists()


def test_report_of_a_csv_only_run_without_figures(tmp_path):
    folder = tmp_path / "csv"
    assert invoke("run", "instance-2", "--out", folder, "--format", "csv", "--no-plots", "--quiet").exit_code == 0
    result = invoke("report", folder)
    assert result.exit_code == 0, result.stderr
    assert "m2 grazes ∂Ω12(2) in Ω1(2)" in (folder / "report.md").read_text()
    assert (folder / "figures").is_dir()  # missing figures are drawn from the trajectory


def test_help_has_examples():
    result = invoke("run", "--help")
    assert result.exit_code == 0 and "oscillator run instance-3" in result.stdout


# ----------------------------------------------------------------------------- bad input


def test_unknown_case_suggests_the_closest(tmp_path):
    assert_refused(invoke("run", "instanse-3", "--out", tmp_path / "x"), "did you mean 'instance-3'",
                   folder=tmp_path / "x")  # fmt: skip


def test_unknown_parameter_in_set_suggests(tmp_path):
    assert_refused(invoke("run", "instance-1", "--set", "Omgea=1.7", "--out", tmp_path / "x"),
                   "'Omgea'", "did you mean 'Omega'", folder=tmp_path / "x")  # fmt: skip


def test_unknown_parameter_in_a_file_suggests(tmp_path):
    text = (load_case("instance-1").source).read_text().replace("mu_k = 0.1", "mu_kk = 0.1")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert_refused(invoke("run", path, "--out", tmp_path / "x"), "mu_kk", "did you mean 'mu_k'", folder=tmp_path / "x")


@pytest.mark.parametrize(
    ("assignment", "fragments"),
    [
        ("m1=abc", ["m1", "not a number"]),  # wrong type
        ("m1=inf", ["m1", "not a number"]),  # non-finite
        ("K1=1e999", ["K1", "finite"]),  # overflows to inf
        ("m1=0", ["m1 must be > 0"]),  # out of range
        ("mu_s=0.01", ["mu_s must be >= mu_k"]),
        ("max_events=2.5", ["max_events", "whole number"]),
        ("Omega", ["NAME=VALUE"]),
    ],
)
def test_bad_values_are_refused(tmp_path, assignment, fragments):
    folder = tmp_path / "x"
    assert_refused(invoke("run", "instance-1", "--set", assignment, "--out", folder), *fragments, folder=folder)


def test_end_before_start_is_refused(tmp_path):
    assert_refused(invoke("run", "instance-1", "--t-end", "0.5", "--out", tmp_path / "x"), "t_end",
                   folder=tmp_path / "x")  # fmt: skip


def test_malformed_toml_gives_line_and_column(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text(
        textwrap.dedent("""\
        [parameters]
        m1 = 1.0
        m2 = = 2
    """)
    )
    assert_refused(invoke("run", path, "--out", tmp_path / "x"), "malformed TOML", "line 3", "column",
                   folder=tmp_path / "x")  # fmt: skip


def test_unwritable_output_folder_is_refused_before_running(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    os.chmod(locked, 0o500)
    try:
        if os.access(locked, os.W_OK):  # root ignores permissions: use a path under a file instead
            target = tmp_path / "a-file" / "x"
            (tmp_path / "a-file").write_text("")
        else:
            target = locked / "x"
        assert_refused(invoke("run", "instance-1", "--out", target), "--out", "choose a writable folder")
        assert not target.exists()
    finally:
        os.chmod(locked, 0o700)


def test_existing_output_folder_is_never_overwritten(tmp_path):
    (tmp_path / "x").mkdir()
    (tmp_path / "x" / "keep.txt").write_text("precious")
    result = invoke("run", "instance-1", "--out", tmp_path / "x")
    assert result.exit_code == 2 and "exists already" in result.stderr
    assert (tmp_path / "x" / "keep.txt").read_text() == "precious"


def test_bad_format_is_refused(tmp_path):
    assert_refused(invoke("run", "instance-1", "--format", "xlsx", "--out", tmp_path / "x"), "--format",
                   folder=tmp_path / "x")  # fmt: skip


def test_a_failure_while_writing_leaves_no_half_written_folder(tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("oscillator.report.runs.case_to_toml", broken)
    folder = tmp_path / "x"
    result = runner.invoke(app, ["run", "instance-1", "--out", str(folder), "--no-plots"], catch_exceptions=False)
    assert result.exit_code == 1 and "Traceback" not in result.stderr
    assert result.stderr.startswith(f"error: cannot write the run to {folder}: No space left on device")
    assert not folder.exists() and list(tmp_path.iterdir()) == []


def test_report_of_a_folder_that_is_no_run(tmp_path):
    assert_refused(invoke("report", tmp_path), "not a run folder")


def test_check_without_expected_events(tmp_path):
    path = tmp_path / "plain.toml"
    text = load_case("instance-1").source.read_text()
    path.write_text(text[: text.index("[[expected]]")])
    assert_refused(invoke("check", path), "no [[expected]] events")


# ----------------------------------------------------------------------------- sweeps


def test_sweep_writes_tables_and_diagrams_and_resumes(tmp_path):
    folder = tmp_path / "sweep"
    args = ["sweep", "bifurcation-omega", "--steps", "3", "--from", "1.58", "--to", "1.62", "--transient", "3",
            "--record", "2", "--workers", "1", "--out", folder]  # fmt: skip
    result = invoke(*args)
    assert result.exit_code == 0, result.stderr
    assert "3 computed, 0 resumed, 0 failed" in result.stdout and "m2 slides" in result.stdout
    for name in ("switches", "poincare", "summary"):
        assert pd.read_parquet(folder / f"{name}.parquet").columns[0] == "Omega"
    assert {"fig-14-bifurcation.png", "fig-14-bifurcation.svg", "fig-14-poincare.png"} <= {
        p.name for p in (folder / "figures").iterdir()
    }
    again = invoke(*args)
    assert again.exit_code == 0 and "0 computed, 3 resumed" in again.stdout


def test_sweep_of_a_case_without_a_sweep_table_needs_a_parameter(tmp_path):
    assert_refused(invoke("sweep", "instance-1", "--out", tmp_path / "x"), "no [sweep] table", "--param")


def test_sweep_refuses_bad_settings(tmp_path):
    assert_refused(invoke("sweep", "bifurcation-q2", "--workers", "0", "--out", tmp_path / "x"), "--workers")
    assert_refused(invoke("sweep", "instance-1", "--param", "Omgea", "--from", "1", "--to", "2",
                          "--out", tmp_path / "y"), "did you mean 'Omega'")  # fmt: skip
    assert_refused(invoke("sweep", "bifurcation-q2", "--steps", "0", "--out", tmp_path / "z"), "steps")


def test_locate_prints_the_bracket_and_the_evidence():
    result = invoke("locate", "bifurcation-omega", "--between", "1.3", "1.6", "--what", "sliding",
                    "--transient", "3", "--record", "2", "--tolerance", "0.05")  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert "sliding changes at Omega = " in result.stdout
    assert "below" in result.stdout and "above" in result.stdout and "sliding_onset" in result.stdout


def test_locate_refuses_an_unknown_indicator():
    assert_refused(invoke("locate", "bifurcation-omega", "--between", "1.3", "1.6", "--what", "chaos"), "--what")


def test_sample_records_the_trajectory_on_a_grid_with_the_same_events(tmp_path):
    folder = tmp_path / "sampled"
    result = invoke("run", "instance-1", "--t-end", "3", "--sample", "0.25", "--no-report", "--quiet", "--out", folder)
    assert result.exit_code == 0, result.stderr
    trajectory = pd.read_parquet(folder / "trajectory.parquet")
    np.testing.assert_allclose(trajectory.t, 1.0 + 0.25 * np.arange(9), rtol=0, atol=1e-12)
    events = pd.read_parquet(folder / "events.parquet")
    np.testing.assert_allclose(events.t, simulate("instance-1", t_end=3.0).events.t, rtol=0, atol=1e-8)
    assert (folder / "figures" / "fig-a-displacement.png").is_file()


@pytest.mark.parametrize(
    ("value", "fragment"), [("0", "positive time step"), ("1e-12", "more than max_trajectory_rows")]
)
def test_bad_sample_steps_are_refused(tmp_path, value, fragment):
    folder = tmp_path / "x"
    assert_refused(invoke("run", "instance-1", "--sample", value, "--out", folder), "--sample", fragment, folder=folder)


def test_a_run_without_events_writes_typed_tables_and_reports(tmp_path):
    """mu_s = 10: no force reaches a flow barrier (mu_s g = 98 N/kg; the forces stay below 70 N/kg)."""
    folder = tmp_path / "still"
    result = invoke("run", "instance-1", "--set", "mu_s=10", "--no-plots", "--out", folder)
    assert result.exit_code == 0, result.stderr
    assert "no switching events" in result.stdout
    events = pd.read_parquet(folder / "events.parquet")
    assert events.empty and events.t.dtype == float and events.mass.dtype == "int64"
    rebuilt = invoke("report", folder)
    assert rebuilt.exit_code == 0, rebuilt.stderr
    assert "No switching event: each mass stays in its domain." in (folder / "report.md").read_text()


def test_figures_of_a_window_and_refused_windows(tmp_path):
    folder = tmp_path / "long"
    result = invoke("run", "instance-1", "--t-end", "60", "--sample", "0.05", "--window", "40", "50", "--out", folder)
    assert result.exit_code == 0, result.stderr
    info = json.loads((folder / "run.json").read_text())
    assert info["figures"] == {"window": [40.0, 50.0], "label": "t in [40, 50] s"}
    assert "The figures show t in \\[40, 50\\] s." in (folder / "report.md").read_text()  # escaped
    assert "<p>The figures show t in [40, 50] s.</p>" in (folder / "report.html").read_text()
    redrawn = invoke("report", folder, "--window", "10", "20")
    assert redrawn.exit_code == 0, redrawn.stderr
    assert json.loads((folder / "run.json").read_text())["figures"]["window"] == [10.0, 20.0]
    assert_refused(invoke("report", folder, "--window", "50", "70"), "--window 50 70 must be two times T0 < T1")
    for window in (("5", "4"), ("0", "2")):
        assert_refused(invoke("run", "instance-1", "--window", *window, "--out", tmp_path / "x"), "--window",
                       folder=tmp_path / "x")  # fmt: skip
    assert_refused(invoke("run", "instance-1", "--window", "1", "1.5", "--no-plots", "--out", tmp_path / "y"),
                   "no use with --no-plots", folder=tmp_path / "y")  # fmt: skip


def test_the_event_table_fits_a_narrow_terminal_without_cutting_a_time(tmp_path, monkeypatch):
    from oscillator.cli import console

    expected = [f"{t:.6f}" for t in simulate("instance-3").events.t]
    for width in (120, 80, 60, 40):
        monkeypatch.setattr(console.out, "width", width)  # as COLUMNS sets it for the command
        done = invoke("run", "instance-3", "--no-plots", "--no-report", "--out", tmp_path / str(width))
        assert done.exit_code == 0, done.stderr
        lines = done.stdout.splitlines()
        table = lines[lines.index("switching events") : lines.index(next(x for x in lines if x.startswith("energy")))]
        assert max(len(line) for line in table) <= width, (width, table)
        title = lines[: lines.index("switching events")]  # the case's name and title, wrapped
        assert max(len(line) for line in title) <= width and " ".join(title).split() == (
            "instance-3: " + load_case("instance-3").title).split()  # fmt: skip
        assert re.findall(r"\d\.\d{6}", "\n".join(table)) == expected, width


def test_a_branch_traced_down_says_so_and_names_bifurcations_as_the_parameter_increases(tmp_path):
    """Down in Q2 across 71.1577: the rest interval appears going down, so it vanishes as Q2
    increases: ``sliding_vanish``, with the rests on the lower side."""
    folder = tmp_path / "down"
    result = invoke("continue", "instance-1", "--param", "Q2", "--from", "71.3", "--to", "71.0", "--step", "0.5",
                    "--out", folder)  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert "from Q2 = 71.3 down to 71" in result.stdout and "named as Q2 increases" in result.stdout
    report = (folder / "report.md").read_text(encoding="utf-8")
    assert "traced from Q2 = 71.3 down to 71 N" in report
    row = next(line for line in report.splitlines() if "sliding\\_vanish" in line and line.startswith("| 71.15"))
    lower, higher = [cell.strip() for cell in row.strip("|").split("|")][-2:]
    assert "sliding\\_onset" in lower and "sliding\\_onset" not in higher  # m2 rests below 71.1577 only
    assert "| events at lower Q2 | events at higher Q2 |" in report
    fixed = report.split("## Fixed parameters", 1)[1]
    assert "| Omega | 1.6 | rad/s |" in fixed and "| Q1 | 30 | N |" in fixed and "| Q2 |" not in fixed
    assert json.loads((folder / "run.json").read_text())["coordinate"] == "x2"


def test_check_of_a_user_case_heads_its_times_expected_not_article(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text(load_case("instance-3").source.read_text(), encoding="utf-8")
    mine, shipped = invoke("check", path), invoke("check", "instance-3")
    assert mine.exit_code == shipped.exit_code == 0
    header = next(line for line in mine.stdout.splitlines() if "event" in line and "ours" in line)
    assert "expected" in header and "article" not in header
    assert "article" in next(line for line in shipped.stdout.splitlines() if "event" in line and "ours" in line)


def test_a_sweep_summary_names_grid_values_and_how_to_locate_the_ends(tmp_path):
    result = invoke("sweep", "bifurcation-omega", "--from", "1.595", "--to", "1.615", "--steps", "5", "--transient",
                    "5", "--record", "3", "--workers", "1", "--no-plots", "--out", tmp_path / "s")  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert "m2 slides (rests on its velocity boundary) at the grid values Omega = 1.6 to 1.605" in result.stdout
    assert ("where it begins (between two grid values): oscillator locate bifurcation-omega --param Omega "
            "--between 1.595 1.6 --what sliding") in result.stdout  # fmt: skip
    assert "where it ends (between two grid values): oscillator locate bifurcation-omega" in result.stdout
    assert "--between 1.605 1.61 --what sliding" in result.stdout


def test_show_prints_expressions_as_written_with_units():
    result = invoke("show", "instance-1")
    assert result.exit_code == 0
    lines = result.stdout.splitlines()
    assert any("P1" in line and "pi/8 = 0.3926990817" in line and line.rstrip(" │").endswith("N") for line in lines)
    assert (
        any("C2" in line and "N s^3/m^3" in line for line in lines) and "the run ends at t_end = 1.9 s" in result.stdout
    )


def test_check_fits_80_columns_without_wrapping_the_numbers(monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    result = invoke("check", "instance-3")
    assert result.exit_code == 0
    rows = [line for line in result.stdout.splitlines() if "✓" in line]
    assert len(rows) == 6 and all(len(line) <= 80 for line in result.stdout.splitlines())
    assert all(
        re.search(r"\d\.\d{4}\s+\d\.\d{4}\s+\d\.\d{6}\s+[-+]\d\.\de-\d\d\s+[-+]\d\.\de-\d\d\s+✓", row) for row in rows
    )


def test_a_both_ways_sweep_says_where_the_two_ways_differ(tmp_path):
    result = invoke("sweep", "bifurcation-q2", "--from", "71.15", "--to", "71.18", "--steps", "7", "--transient", "20",
                    "--record", "4", "--both-ways", "--out", tmp_path / "both")  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert "Q2 from 71.15 to 71.18 and back (7 values" in result.stdout
    assert "going up: m2 slides at the grid values Q2 = 71.15 to 71.17" in result.stdout
    assert "going down: m2 slides at the grid values Q2 = 71.15 to 71.155" in result.stdout
    assert "hysteresis: at Q2 = 71.16, 71.165, 71.17 the two ways end on different motions" in result.stdout
    assert {p.name for p in (tmp_path / "both" / "figures").iterdir()} >= {"fig-14-poincare.png"}
    refused = invoke("sweep", "bifurcation-q2", "--both-ways", "--workers", "2", "--out", tmp_path / "no")
    assert_refused(refused, "--workers", "one after another", folder=tmp_path / "no")


def test_an_error_says_its_arguments_as_the_command_lines_flags():
    """The library names its arguments; the command line says them as its flags, from one table."""
    from oscillator.cli.console import FLAGS, message
    from oscillator.errors import InputError

    error = InputError("start must be below stop; give a `guess` or a longer `transient`", field="start")
    assert message(error) == "--from must be below stop; give a --guess or a longer --transient"
    assert error.said_as({}) == "start must be below stop; give a guess or a longer transient"  # the names unquoted
    assert FLAGS["stop"] == "--to" and "`" not in message(InputError("`nothing` here", field="x"))
