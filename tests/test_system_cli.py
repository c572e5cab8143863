"""``oscillator run`` and ``oscillator show`` on a system file (issue 51): the folder a run writes,
its tables read back, a refused file that creates nothing, options that belong to cases refused,
and names that are hostile text shown as text."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from oscillator.cli.app import app

ROOT = Path(__file__).resolve().parents[1]
BLADE = ROOT / "docs" / "systems" / "blade-damper.toml"


def _invoke(*arguments: str):
    return CliRunner().invoke(app, list(arguments))


def test_run_writes_a_system_folder(tmp_path):
    done = _invoke("run", str(BLADE), "--out", str(tmp_path / "blade"), "--t-end", "12")
    assert done.exit_code == 0, done.stderr
    folder = tmp_path / "blade"
    names = {p.name for p in folder.iterdir()}
    assert {"events.csv", "events.parquet", "trajectory.parquet", "energy.csv", "system.toml", "run.json"} <= names
    assert {"report.md", "report.html", "figures"} <= names
    events = pd.read_csv(folder / "events.csv")
    assert list(events.columns[:6]) == ["t", "element", "type", "mass", "with", "kind"]
    assert set(events.element) == {"platform"} and events.t.between(0, 12).all()
    assert "slider_slips" in done.stdout and "platform" in done.stdout
    info = json.loads((folder / "run.json").read_text())
    assert info["status"] == "complete" and info["t_end"] == 12.0 and info["events"] == len(events)
    assert abs(info["energy_residual"]) < 1e-6
    trajectory = pd.read_parquet(folder / "trajectory.parquet")
    assert trajectory.t.iloc[-1] == 12.0 and {"x:blade", "v:damper", "z:platform", "mode:platform"} <= set(trajectory)
    from oscillator.io.chains import load_system

    assert load_system(folder / "system.toml").masses == load_system(BLADE).masses


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("[[mass]]\nname = 'a'\nm = 0\n", "m must be positive"),
        ("[[mass]]\nname = 'a'\nm = 1\n[[element]]\ntype = 'spring'\non = 'b'\nk = 1\n", "is no mass of the system"),
        (
            "[[mass]]\nname = 'a'\nm = 1\n[[element]]\ntype = 'friction'\non = 'a'\nmu_s = 0.1\nmu_k = 0.2\n",
            "mu_s (0.1) must be at least mu_k (0.2)",
        ),
        ("[system]\nOmega = 1.0\n", "has no mass"),
        ("[[mass]]\nname = 'a'\nm = 1\n[[element]]\ntype = 'sprung'\non = 'a'\n", "did you mean 'spring'"),
    ],
)
def test_a_bad_system_file_is_refused_and_nothing_is_created(tmp_path, text, said):
    path = tmp_path / "machine.toml"
    path.write_text(text, encoding="utf-8")
    done = _invoke("run", str(path), "--out", str(tmp_path / "out"))
    assert done.exit_code == 2 and said in done.stderr and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists() and sorted(p.name for p in tmp_path.iterdir()) == ["machine.toml"]


def test_options_of_the_articles_cases_are_refused_for_a_system(tmp_path):
    done = _invoke("run", str(BLADE), "--sample", "0.1", "--out", str(tmp_path / "out"))
    assert done.exit_code == 2 and "--sample applies to the article's cases" in done.stderr
    assert not (tmp_path / "out").exists()


def test_set_changes_a_systems_numbers_by_name(tmp_path):
    """--set element.field=VALUE and mass.m=VALUE change the system run (system.toml holds it as run);
    a name that is no number of the system is refused with the closest one, nothing created."""
    from oscillator.io.chains import load_system

    folder = tmp_path / "out"
    done = _invoke("run", str(BLADE), "--set", "platform.F=0.5", "--set", "damper.m=pi/20", "--out", str(folder))
    assert done.exit_code == 0, done.stderr
    ran = load_system(folder / "system.toml")
    assert ran.elements[2].values["F"] == 0.5 and ran.masses[1].m == pytest.approx(0.15707963267948966)
    refused = _invoke("run", str(BLADE), "--set", "platfrom.F=0.5", "--out", str(tmp_path / "no"))
    assert refused.exit_code == 2 and "did you mean 'platform.F'" in refused.stderr
    assert not (tmp_path / "no").exists()


def test_hostile_names_are_shown_as_text(tmp_path):
    """Names with markup in them reach the report escaped and the figures as plain text."""
    hostile = "<script>alert(1)</script> **bold** $x^2$"
    path = tmp_path / "hostile.toml"
    path.write_text(
        f'title = "{hostile}"\n[[mass]]\nname = "{hostile}"\nm = 1\nv = 1\n[[element]]\ntype = "spring"\n'
        f'on = "{hostile}"\nk = 1\n[[element]]\ntype = "friction"\nname = "[link](http://x)"\non = "{hostile}"\n'
        "mu_s = 0.3\nmu_k = 0.2\n",
        encoding="utf-8",
    )
    done = _invoke("run", str(path), "--out", str(tmp_path / "out"), "--t-end", "10")
    assert done.exit_code == 0, done.stderr
    page = (tmp_path / "out" / "report.html").read_text()
    assert "<script>" not in page and "&lt;script&gt;" in page
    markdown = (tmp_path / "out" / "report.md").read_text()
    assert "[link](http://x)" not in markdown and "<script>" not in markdown


def test_show_draws_the_schematic(tmp_path):
    target = tmp_path / "blade.png"
    done = _invoke("show", str(BLADE), "--figure", str(target))
    assert done.exit_code == 0, done.stderr
    assert target.read_bytes().startswith(b"\x89PNG") and "platform" in done.stdout and "jenkins" in done.stdout
    refused = _invoke("show", "instance-1", "--figure", str(tmp_path / "x.png"))
    assert refused.exit_code == 2 and not (tmp_path / "x.png").exists()


def test_report_rebuilds_a_system_folder_and_refuses_a_damaged_one(tmp_path):
    import shutil

    folder = tmp_path / "blade"
    assert _invoke("run", str(BLADE), "--out", str(folder), "--t-end", "8", "--no-plots", "--no-report").exit_code == 0
    assert not (folder / "report.md").exists() and not (folder / "figures").exists()
    done = _invoke("report", str(folder))
    assert done.exit_code == 0, done.stderr
    assert (folder / "figures" / "motion.png").is_file() and (folder / "figures" / "schematic.png").is_file()
    report = (folder / "report.md").read_text()
    assert "platform" in report and "Energy audit" in report
    damaged = tmp_path / "damaged"
    shutil.copytree(folder, damaged)
    (damaged / "energy.csv").write_text("element,type,work\nelsewhere,spring,1.0\n")
    refused = _invoke("report", str(damaged))
    assert refused.exit_code == 2 and "is damaged" in refused.stderr and "energy.csv" in refused.stderr


def test_check_compares_a_systems_expected_events(tmp_path):
    """The belt chain's expected times (from the independent implementation) are met; a time moved
    by 0.01 s is out of tolerance (exit 1); an expected event naming no element is refused."""
    done = _invoke("check", str(ROOT / "docs" / "systems" / "belt-chain.toml"))
    assert done.exit_code == 0 and "all 4 expected events within tolerance" in done.stdout, done.stderr
    text = (ROOT / "docs" / "systems" / "belt-chain.toml").read_text()
    moved = tmp_path / "moved.toml"
    moved.write_text(text.replace("t = 0.5420", "t = 0.5520"))
    out = _invoke("check", str(moved))
    assert out.exit_code == 1 and "1 expected event(s) out of tolerance" in out.stderr and "OUT" in out.stdout
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(text.replace('element = "belt under m3"', 'element = "belt under m4"'))
    refused = _invoke("check", str(wrong))
    assert refused.exit_code == 2 and "did you mean 'belt under m3'" in refused.stderr


def test_orbit_of_a_system_file_prints_the_orbit_find_orbit_finds():
    """``oscillator orbit FILE --set platform.F=0.5``: the state at the section, to the ten digits
    printed, is find_chain_orbit's; the multipliers' moduli too; what is neutral is said."""
    import numpy as np

    from oscillator.io.chains import load_system
    from oscillator.orbits.chain_orbits import find_chain_orbit

    done = _invoke("orbit", str(BLADE), "--set", "platform.F=0.5", "--transient", "60")
    assert done.exit_code == 0, done.stderr
    chain = load_system(BLADE).with_values({"platform.F": 0.5})
    orbit = find_chain_orbit(chain, transient=60)
    state = ", ".join(f"{n} = {v:.10g}" for n, v in zip(chain.system.state, orbit.state, strict=True))
    assert state in done.stdout and "period-1 orbit at t = 0 s" in done.stdout
    for mu in orbit.multipliers:
        assert f"{abs(mu):.6e}" in done.stdout
    assert "neutral in z:platform" in done.stdout and orbit.free == ("x:blade", "v:blade", "x:damper", "v:damper")
    assert np.all(np.abs(orbit.multipliers) < 1)


def test_orbit_of_a_system_file_prints_its_sensitivities_by_element_and_field():
    """``--sensitivities platform.F,Omega``: the tables hold the orbit's state and measures with
    their derivatives, to the six digits printed, as ``orbit.sensitivities`` gives them."""
    from oscillator.io.chains import load_system
    from oscillator.orbits.chain_orbits import find_chain_orbit

    done = _invoke("orbit", str(BLADE), "--transient", "60", "--sensitivities", "platform.F,Omega")
    assert done.exit_code == 0, done.stderr
    found = find_chain_orbit(load_system(BLADE), transient=60).sensitivities(["platform.F", "Omega"])
    lines = done.stdout.splitlines()
    for frame in (found.state, found.measures):
        for name, values in frame.iterrows():
            row = next(line.split() for line in lines if line.split()[:1] == [name] and "=" not in line)
            assert row[1:] == [f"{value:+.6g}" for value in values], name
    assert "Sensitivities of the measures" in done.stdout and "d/dplatform.F" in done.stdout


def test_orbit_of_a_system_file_refuses_a_guess_of_another_size_and_says_when_newton_fails():
    done = _invoke("orbit", str(BLADE), "--guess", "1,2")
    assert done.exit_code == 2 and "--guess must be 5 numbers, one for each of x:blade" in done.stderr
    done = _invoke("orbit", str(BLADE), "--sensitivities", "platform.G")
    assert done.exit_code == 2 and "platform.G is no number of the system; did you mean 'platform.F'" in done.stderr
    assert "Floquet" not in done.stdout  # refused before the orbit is sought
    conveyor = ROOT / "docs" / "systems" / "conveyor.toml"
    done = _invoke("orbit", str(conveyor), "--transient", "10", "--max-iterations", "3")
    assert done.exit_code == 1 and "did not converge in 3 steps" in done.stderr and "Traceback" not in done.stderr


def test_frc_of_a_system_file_sweeps_up_and_down_and_writes_its_folder(tmp_path):
    """``oscillator frc FILE --param Omega LOW HIGH --sweep N``: the folder holds both sweeps, each
    row the orbit frequency_sweep finds there (the same table), the system as swept, run.json and
    the figure; what it prints is the table's largest amplitude."""
    import numpy as np

    from oscillator.io.chains import load_system
    from oscillator.orbits.chain_response import frequency_sweep

    folder = tmp_path / "frc"
    done = _invoke("frc", str(BLADE), "--param", "Omega", "0.9", "1.1", "--sweep", "3", "--transient", "40",
                   "--out", str(folder))  # fmt: skip
    assert done.exit_code == 0, done.stderr
    table = pd.read_parquet(folder / "sweeps.parquet")
    assert list(table.direction) == ["up"] * 3 + ["down"] * 3 and list(table.Omega) == [0.9, 1.0, 1.1, 1.1, 1.0, 0.9]
    expected = frequency_sweep(load_system(BLADE), np.linspace(0.9, 1.1, 3), transient=40)
    np.testing.assert_allclose(table["x_max:blade"][:3], expected["x_max:blade"], rtol=0, atol=1e-12)
    info = json.loads((folder / "run.json").read_text())
    assert info["kind"] == "system-frc" and info["span"] == [0.9, 1.1] and info["failed"] == 0
    assert (folder / "figures" / "frequency.png").stat().st_size > 0 and (folder / "system.toml").is_file()
    worst = expected.loc[expected["x_max:blade"].idxmax()]
    assert f"sweep up: largest x_max of blade {worst['x_max:blade']:.6g} m at Omega = {worst.Omega:.6g}" in done.stdout


def test_frc_of_a_system_file_refuses_the_options_of_cases_and_bad_spans_creating_nothing(tmp_path):
    folder = tmp_path / "frc"
    for extra, said in ((["--max-points", "30"], "--max-points applies to the article's cases"),
                        (["--sweep", "1"], "--sweep must be 2 to 100000"),
                        (["--set", "platform.F=-1"], "F must not be negative"),
                        (["--starts", "3"], "--starts goes with --seeds")):  # fmt: skip
        done = _invoke("frc", str(BLADE), "--param", "Omega", "0.9", "1.1", *extra, "--out", str(folder))
        assert done.exit_code == 2 and said in done.stderr, (extra, done.stderr)
        assert not folder.exists()
    done = _invoke("frc", str(BLADE), "--param", "platform.kt", "-1", "2", "--out", str(folder))
    assert done.exit_code == 2 and "kt" in done.stderr and not folder.exists()


OSCILLATOR_FILE = """title = "A forced oscillator"

[system]
Omega = 1.0

[[mass]]
name = "m"
m = 1.0

[[element]]
type = "spring"
on = "m"
k = 1.0

[[element]]
type = "damper"
name = "dashpot"
on = "m"
c = 0.1

[[element]]
type = "force"
on = "m"
Q = 1.0
"""


@pytest.mark.slow
def test_design_of_a_system_file_writes_what_chain_design_finds(tmp_path):
    """``oscillator design FILE --vary dashpot.c=0.05,0.3 --over Omega 0.5 1.5 --objective x_max:m
    --band 7``: run.json's best value, worst and place are chain_design's (the same problem), the
    history is its table, system.toml the machine at the best value, the figure drawn."""
    import json

    import pandas as pd

    from oscillator.designing.chain_design import chain_design
    from oscillator.io.chains import load_system

    path = tmp_path / "oscillator.toml"
    path.write_text(OSCILLATOR_FILE, encoding="utf-8")
    arguments = ["--vary", "dashpot.c=0.05,0.3", "--over", "Omega", "0.5", "1.5", "--objective", "x_max:m"]
    done = _invoke("design", str(path), *arguments, "--band", "7", "--out", str(tmp_path / "d"))
    assert done.exit_code == 0, done.stderr
    found = chain_design(load_system(path), {"dashpot.c": (0.05, 0.3)}, {"Omega": (0.5, 1.5)}, "x_max:m", sweep=7)
    info = json.loads((tmp_path / "d" / "run.json").read_text())
    assert (info["kind"], info["vary"], info["objective"], info["over"]) == (
        "system-design", "dashpot.c", "x_max:m", ["Omega", 0.5, 1.5]
    )  # fmt: skip
    assert (info["best"], info["worst"], info["at"]) == (found.value, found.worst.value, found.worst.at)
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "d" / "history.parquet"), found.history)
    assert load_system(tmp_path / "d" / "system.toml").with_values({"t0": 0.0}) == found.chain
    assert (tmp_path / "d" / "figures" / "design.png").stat().st_size > 10_000
    assert found.summary in done.stdout.replace("\n", " ") or found.summary[:40] in done.stdout


def test_design_of_a_system_file_refuses_what_it_cannot_take_and_writes_nothing(tmp_path):
    path = tmp_path / "oscillator.toml"
    path.write_text(OSCILLATOR_FILE, encoding="utf-8")
    base = ["design", str(path), "--over", "Omega", "0.5", "1.5", "--objective", "x_max:m"]
    base += ["--out", str(tmp_path / "d")]
    for extra, said in (
        (["--vary", "dashpot.c=0.05,0.3", "--starts", "3"], "--starts applies to the article's cases"),
        (["--vary", "dashpot.k=0.05,0.3"], "dashpot.k is no number of the system; did you mean 'dashpot.c'"),
        (["--vary", "dashpot.c=0.05,0.3", "--vary", "spring-1.k=1,2"], "varies one number"),
        (["--vary", "dashpot.c=0.05,0.3", "--objective", "x_pp:m"], "one --objective"),
        (["--vary", "dashpot.c=-1,0.3"], "element 'dashpot': c must not be negative, got -1"),
    ):
        done = _invoke(*base, *extra)
        assert done.exit_code == 2 and said in done.stderr, (extra, done.stderr)
        assert "Traceback" not in done.stderr and not (tmp_path / "d").exists()


@pytest.mark.slow
def test_continue_of_a_system_file_writes_the_branch_continue_orbit_finds(tmp_path):
    """``oscillator continue FILE --param Omega --from 0.6 --to 0.8``: branch.parquet is
    continue_orbit's points, run.json says it reached the end, the figure is drawn; to 0.9 the
    branch ends where the slider starts to slip at the section: exit 1, said, the branch kept."""
    import json

    import pandas as pd

    import oscillator
    from oscillator.io.chains import load_system

    done = _invoke(
        "continue", str(BLADE), "--param", "Omega", "--from", "0.6", "--to", "0.8", "--out", str(tmp_path / "c")
    )
    assert done.exit_code == 0, done.stderr
    branch = oscillator.continue_orbit(load_system(BLADE), param="Omega", start=0.6, stop=0.8)
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "c" / "branch.parquet"), branch.points)
    info = json.loads((tmp_path / "c" / "run.json").read_text())
    assert info["ended"] == "the end of the span" and info["points"] == len(branch.points)
    assert (tmp_path / "c" / "figures" / "branch.png").stat().st_size > 10_000
    done = _invoke(
        "continue", str(BLADE), "--param", "Omega", "--from", "0.6", "--to", "0.9", "--out", str(tmp_path / "d")
    )
    assert done.exit_code == 1 and "the coordinates that move at the section change between 0.86" in done.stderr
    assert json.loads((tmp_path / "d" / "run.json").read_text())["points"] > 2


def test_continue_of_a_system_file_refuses_the_articles_options_and_writes_nothing(tmp_path):
    base = ["continue", str(BLADE), "--param", "Omega", "--from", "0.6", "--to", "0.8", "--out", str(tmp_path / "c")]
    for extra, said in (
        (["--period", "2"], "--period applies to the article's cases"),
        (["--coordinate", "x2"], "--coordinate applies to the article's cases"),
        (["--guess", "1,2"], "--guess must be 5 numbers"),
        (["--set", "platform.G=1"], "platform.G is no number of the system"),
    ):
        done = _invoke(*base, *extra)
        assert done.exit_code == 2 and said in done.stderr, (extra, done.stderr)
        assert not (tmp_path / "c").exists()
    done = _invoke("continue", str(BLADE), "--param", "platform.Q", "--from", "0.6", "--to", "0.8")
    assert done.exit_code == 2 and "did you mean" in done.stderr


HARDENING = ROOT / "docs" / "systems" / "hardening.toml"
SLICE = (
    "--x",
    "x:m",
    "-2",
    "2",
    "3",
    "--y",
    "v:m",
    "-2",
    "2",
    "2",
    "--transient",
    "200",
    "--record",
    "8",
    "--workers",
    "1",
)


def test_basins_of_a_system_file_writes_what_find_basins_finds_and_resumes(tmp_path):
    import oscillator
    from oscillator import AttractorSettings, Axis

    folder = tmp_path / "basins"
    done = _invoke("basins", str(HARDENING), *SLICE, "--out", str(folder))
    assert done.exit_code == 0, done.stderr
    assert {"basins.parquet", "attractors.parquet", "system.toml", "basins.json", "report.html"} <= {
        p.name for p in folder.iterdir()
    }
    assert (folder / "figures" / "basins.png").stat().st_size > 0
    found = oscillator.find_basins(
        oscillator.load_system(HARDENING),
        Axis("x:m", -2, 2, 3),
        Axis("v:m", -2, 2, 2),
        settings=AttractorSettings(transient=200, record=8),
    )
    cells = pd.read_parquet(folder / "basins.parquet")
    assert list(cells.columns[:3]) == ["x:m", "v:m", "attractor"]
    assert cells.attractor.to_numpy().reshape(2, 3).tolist() == found.grid.tolist()
    table = pd.read_parquet(folder / "attractors.parquet")
    assert table["x_pp:m"].tolist() == pytest.approx([a.measures["x_pp:m"] for a in found.found.attractors], rel=1e-9)
    assert table["stable"].tolist() == [True, True] and "A0: period-1" in done.stdout
    again = _invoke("basins", str(HARDENING), *SLICE, "--out", str(folder))
    assert again.exit_code == 0, again.stderr
    assert "resumed: 6 of the 6 starts read" in " ".join(again.stderr.split() + again.stdout.split())
    assert pd.read_parquet(folder / "basins.parquet").equals(cells)
    refused = _invoke("report", str(folder))
    assert refused.exit_code == 2 and "declared system's basins" in refused.stderr


def test_basins_and_lyapunov_of_a_system_file_refuse_what_they_cannot_take_creating_nothing(tmp_path):
    for arguments, said in (
        (("--x", "x1", "0", "1", "3", "--y", "v:m", "0", "1", "3"), "give one of x:m, v:m"),
        (("--x", "x:m", "0", "1", "3", "--y", "v:m", "0", "1", "3", "--engine", "cvode"), "--engine applies"),
        (("--x", "x:m", "0", "1", "3", "--y", "v:m", "0", "1", "3", "--set", "m.k=1"), "is no number of the system"),
    ):
        done = _invoke("basins", str(HARDENING), *arguments, "--out", str(tmp_path / "b"))
        assert done.exit_code == 2 and said in done.stderr, done.stderr
        assert not (tmp_path / "b").exists()
    done = _invoke("lyapunov", str(HARDENING), "--periods", "0", "--out", str(tmp_path / "l"))
    assert done.exit_code == 2 and "--periods" in done.stderr and not (tmp_path / "l").exists()


def test_lyapunov_of_a_system_file_prints_and_writes_the_spectrum(tmp_path):
    import oscillator

    done = _invoke("lyapunov", str(HARDENING), "--periods", "30", "--transient", "20", "--out", str(tmp_path / "l"))
    assert done.exit_code == 0, done.stderr
    spectrum = oscillator.lyapunov(oscillator.load_system(HARDENING), periods=30, transient=20)
    exponents = ", ".join(f"{value:.6g}" for value in spectrum.exponents)
    assert f"Hardening oscillator between its folds: Lyapunov exponents (1/s), 30 periods: {exponents}" in done.stdout
    back = oscillator.read_run(tmp_path / "l")
    assert list(back.exponents) == list(spectrum.exponents) and back.case == oscillator.load_system(HARDENING)


def test_basins_of_a_system_file_show_hostile_names_as_text(tmp_path):
    hostile = "<script>alert(1)</script> **bold** $x^2$"
    path = tmp_path / "hostile.toml"
    path.write_text(
        f'title = "{hostile}"\n[system]\nOmega = 0.6\n[[mass]]\nname = "{hostile}"\nm = 1\n[[element]]\n'
        f'type = "spring"\non = "{hostile}"\nk = 1\n[[element]]\ntype = "damper"\non = "{hostile}"\nc = 0.05\n'
        f'[[element]]\ntype = "friction"\nname = "[link](http://x)"\non = "{hostile}"\nmu_s = 0.4\nmu_k = 0.25\n'
        f'N = 1.0\nw = 0.3\n[[element]]\ntype = "force"\non = "{hostile}"\nQ = 0.4\n',
        encoding="utf-8",
    )
    axes = ("--x", f"x:{hostile}", "-1", "1", "2", "--y", f"v:{hostile}", "-1", "1", "2", "--transient", "100")
    done = _invoke("basins", str(path), *axes, "--record", "4", "--workers", "1", "--out", str(tmp_path / "out"))
    assert done.exit_code == 0, done.stderr
    page = (tmp_path / "out" / "report.html").read_text()
    assert "<script>" not in page and "&lt;script&gt;" in page
    assert "<a " not in page and "<td>[link](http://x): slips, sticks</td>" in page  # shown as text, no link
    markdown = (tmp_path / "out" / "report.md").read_text()
    assert "[link](http://x)" not in markdown and "<script>" not in markdown
    table = pd.read_parquet(tmp_path / "out" / "attractors.parquet")
    assert table.signature.iloc[0].startswith("[link](http://x): ") and f"rests:{hostile}" in table
