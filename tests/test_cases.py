"""Loading cases: shipped names, user files, and one clear error per malformed input."""

import textwrap

import pytest

from oscillator import OscillatorError, load_case, simulate

INSTANCE_1 = load_case("instance-1")


def write(tmp_path, text, name="user.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def minimal_case_text(**changes):
    params = "\n".join(f"{k} = {v!r}" for k, v in {
        "m1": 1.0, "m2": 1.0, "C1": 0.05, "C2": 0.0, "C3": 1.0, "C4": 0.05, "C5": 0.0,
        "K1": 1.0, "K2": 0.0, "K3": 2.0, "K4": 1.0, "K5": 0.0, "K6": 1.0,
        "mu_k": 0.1, "mu_s": 0.2, "d": 5.0, "d1": 4.5, "Q1": 3.0, "Q2": 7.1, "Omega": 1.6,
        **changes,
    }.items())  # fmt: skip
    initial = "t0 = 0.0\nx1 = 1.0\nv1 = 0.0\nx2 = 0.5\nv2 = 0.0"
    return f"[parameters]\n{params}\n\n[initial]\n{initial}\n\n[run]\nt_end = 2.0\n"


def test_named_case_loads_with_its_expectations():
    assert INSTANCE_1.name == "instance-1"
    assert INSTANCE_1.initial.t0 == 1.0 and INSTANCE_1.t_end == 1.9
    assert len(INSTANCE_1.expected) == 2
    assert INSTANCE_1.expected[1].tolerance == 0.01 and "(*)" in INSTANCE_1.expected[1].note


def test_user_file_runs_with_documented_defaults(tmp_path):
    case = load_case(write(tmp_path, minimal_case_text()))
    assert (case.parameters.g, case.parameters.P1, case.parameters.phi2) == (9.8, 0.0, 0.0)
    assert simulate(case).stats.events >= 1


def test_unknown_case_name_suggests_the_closest():
    with pytest.raises(OscillatorError, match="did you mean 'instance-3'"):
        load_case("instanse-3")


def test_malformed_toml_gives_line_and_column(tmp_path):
    path = write(tmp_path, "[parameters]\nm1 = = 1\n")
    with pytest.raises(OscillatorError, match=r"malformed TOML.*line 2"):
        load_case(path)


def test_unknown_parameter_in_a_file_suggests_the_closest(tmp_path):
    path = write(tmp_path, minimal_case_text(mu_kk=0.1))
    with pytest.raises(OscillatorError, match="unknown parameters 'mu_kk'; did you mean 'mu_k'"):
        load_case(path)


def test_missing_parameter_is_named(tmp_path):
    text = minimal_case_text().replace("K6 = 1.0\n", "")
    with pytest.raises(OscillatorError, match="missing K6"):
        load_case(write(tmp_path, text))


def test_wrong_type_is_named(tmp_path):
    with pytest.raises(OscillatorError, match=r"parameters\.m2") as info:
        load_case(write(tmp_path, minimal_case_text(m2="heavy")))
    assert info.value.field == "parameters.m2"


def test_out_of_range_value_in_a_file_is_named(tmp_path):
    with pytest.raises(OscillatorError, match="mu_s must be >= mu_k"):
        load_case(write(tmp_path, minimal_case_text(mu_s=0.01)))


def test_end_before_start_in_a_file(tmp_path):
    text = minimal_case_text().replace("t_end = 2.0", "t_end = -1.0")
    with pytest.raises(OscillatorError, match="t_end"):
        load_case(write(tmp_path, text))


def test_unknown_run_setting_suggests(tmp_path):
    text = minimal_case_text() + "rtoll = 1e-9\n"
    with pytest.raises(OscillatorError, match="did you mean 'rtol'"):
        load_case(write(tmp_path, text))


def test_missing_file_is_a_clear_error(tmp_path):
    with pytest.raises(OscillatorError, match="cannot read case file"):
        load_case(tmp_path / "nowhere.toml")


@pytest.mark.parametrize("title", ["A short title", "", "T" * 300])
def test_a_case_with_many_overrides_is_written_as_a_file_that_reads_back(tmp_path, title):
    """Every parameter overridden (what the explorer's "Save as case file" writes after every
    slider moved, or a command with many --set): the title that lists the changes stays within a
    case file's 300 characters, counting those that do not fit, and the file loads."""
    import dataclasses

    from oscillator.io.cases import case_to_toml, resolve_case
    from oscillator.model.parameters import Parameters

    base = dataclasses.replace(INSTANCE_1, title=title)
    changes = {name: float(getattr(base.parameters, name)) * 1.01 + 0.001 for name in Parameters.names()}
    case = resolve_case(base, **changes)
    assert len(case.modified) == len(changes) > 20
    assert len(case.full_title) <= 300
    assert case.full_title.startswith(title[:200])
    listed = case.full_title.split("modified: ", 1)[1]
    assert listed.endswith(("more)", "more", "values)")), listed
    path = tmp_path / "saved.toml"
    path.write_text(case_to_toml(case), encoding="utf-8")
    loaded = load_case(path)
    assert loaded.title == case.full_title
    assert loaded.parameters == case.parameters
