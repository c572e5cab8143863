"""Output folders that someone else prepared (issue 50): links inside them, and the commands'
answers when a resume meets one, by the rule of ``test_hostile.py`` (exit 0 with a result, 2 with
one line and nothing created, 1 with what was computed kept)."""

from __future__ import annotations

import pandas as pd
import pytest

from conftest import FRC_WINDOW
from oscillator.errors import InputError
from oscillator.io.files import inner_folder, refuse_link
from test_hostile import oscillator


def test_nothing_is_written_through_a_link_inside_an_output_folder(tmp_path):
    """A folder's ``figures/`` that is a link: the tables and the report are written, no figure
    goes where the link points, and the one problem says why (the tables are kept)."""
    from oscillator.report import markup as mk
    from oscillator.report.outputs import write_folder

    folder, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    folder.mkdir()
    elsewhere.mkdir()
    (folder / "figures").symlink_to(elsewhere)

    def never() -> object:
        raise AssertionError("a figure was drawn for a linked folder")

    frame = pd.DataFrame({"a": [1.0]})
    problems = write_folder(folder, {"table": frame}, [("f", never)], [mk.Figure("f", "a figure")], "title")
    assert len(problems) == 1 and "figures not drawn" in problems[0] and "is a link" in problems[0]
    assert list(elsewhere.iterdir()) == []
    assert (folder / "table.parquet").is_file() and "a figure" not in (folder / "report.md").read_text()
    with pytest.raises(InputError, match="is a link"):
        inner_folder(folder / "figures")
    (folder / "plain").write_text("x")
    with pytest.raises(InputError, match="is not a folder"):
        inner_folder(folder / "plain")
    assert inner_folder(folder / "new").is_dir()
    with pytest.raises(InputError, match="is a link; give the name of a folder of its own"):
        refuse_link(folder / "figures", option="--out")


@pytest.mark.slow
@pytest.mark.parametrize(
    "command",
    [
        [*FRC_WINDOW, "--seeds", "2", "--sweep", "3", "--out", "f"],  # its folder is small_frc's
        ["atlas", "instance-1", "--x", "Omega", "1.5", "1.7", "3", "--y", "Q2", "70", "71", "2", "--transient", "20",
         "--record", "4", "--out", "f"],
        ["design", "instance-1", "--vary", "d1=3,4", "--over", "Omega", "1.4", "1.6", "--objective", "x_max_m1",
         "--band", "2", "--starts", "1", "--candidates", "2", "--transient", "30", "--record", "4", "--out", "f"],
        ["run", "instance-3", "--out", "f"],
    ],
    ids=["frc", "atlas", "design", "run"],
)  # fmt: skip
def test_a_resume_or_a_report_into_a_folder_whose_figures_are_a_link_writes_nothing_there(tmp_path, command, request):
    """frc, the atlas (14 files), design and ``oscillator report RUN`` (8 files) wrote their
    figures into a linked ``figures/``'s target."""
    import shutil

    work, elsewhere = tmp_path / "work", tmp_path / "elsewhere"
    work.mkdir()
    elsewhere.mkdir()
    computes = command[0] != "run"
    command = [*command, "--workers", "1"] if computes else command
    if command[0] == "frc":  # the same command's folder, computed once for the tests (without figures)
        shutil.copytree(request.getfixturevalue("small_frc"), work / "f")
    else:
        assert oscillator(*command, "-q", cwd=work).returncode == 0
    figures = work / "f" / "figures"
    if figures.exists():
        shutil.rmtree(figures)
    figures.symlink_to(elsewhere)
    answers = [oscillator(*command, cwd=work)] if computes else []
    if command[0] in ("run", "atlas"):
        answers.append(oscillator("report", "f", cwd=work))
    for done in answers:
        assert done.returncode in (1, 2) and "f/figures is a link" in done.stderr, done.stderr
        assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
        assert done.returncode == 2 or "the tables are in f" in done.stderr
    assert list(elsewhere.iterdir()) == []


@pytest.mark.slow
def test_an_output_folder_that_is_a_link_is_refused_as_a_link(tmp_path):
    """``--out`` naming a link to an empty folder was refused for another reason (or, for a
    resumable command, replaced); it is refused as a link, and nothing is made."""
    work, empty = tmp_path / "work", tmp_path / "empty"
    work.mkdir()
    empty.mkdir()
    (work / "f").symlink_to(empty)
    for command in (["run", "instance-3"], ["frc", "instance-1", "--param", "Omega", "1.5", "1.7"]):
        done = oscillator(*command, "--out", "f", cwd=work)
        assert done.returncode == 2 and "--out f is a link; give the name of a folder of its own" in done.stderr, (
            done.stderr
        )
        assert (work / "f").is_symlink() and list(empty.iterdir()) == []


def test_commands_without_out_in_the_same_second_get_folders_of_their_own(tmp_path, monkeypatch):
    """Two atlases without --out started in the same second resumed one folder (the second refused
    it as another computation): the second default name gets ``-2``, the third ``-3``."""
    import time

    from oscillator.cli.resumable import new_folder
    from oscillator.io.cases import resolve_case

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(time, "strftime", lambda pattern: "20261127-120000")
    case = resolve_case("instance-1")
    names = []
    for _ in range(3):
        folder = new_folder(case, "atlas")
        folder.mkdir(parents=True)
        names.append(folder.name)
    assert names == ["instance-1-atlas-20261127-120000", "instance-1-atlas-20261127-120000-2",
                     "instance-1-atlas-20261127-120000-3"]  # fmt: skip
