"""docs/python-api.ipynb runs as shown, in a Jupyter kernel: every cell, in order, without an
error; its figures and rich displays come out (the notebook's own cells assert what they read
back).  It is stored with its outputs, so that it shows its figures where it is browsed: the
test runs a copy with them cleared, and checks that the stored one shows as many."""

from __future__ import annotations

from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

NOTEBOOK = Path(__file__).parent.parent / "docs" / "python-api.ipynb"


def _images(notebook) -> list:
    return [
        out
        for cell in notebook.cells
        if cell.cell_type == "code"
        for out in cell.outputs
        if "image/png" in out.get("data", {})
    ]


@pytest.mark.slow  # end to end: the page run in a Jupyter kernel (20 s)
def test_the_notebook_runs_and_shows_its_figures_and_tables(tmp_path):
    stored = nbformat.read(NOTEBOOK, as_version=4)
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    for cell in notebook.cells:
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = [], None
    nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()  # fmt: skip
    outputs = [out for cell in notebook.cells if cell.cell_type == "code" for out in cell.outputs]
    assert not [out for out in outputs if out.output_type == "error"]
    figures = sum(".plot" in cell.source for cell in notebook.cells if cell.cell_type == "code")
    assert len(_images(notebook)) == len(_images(stored)) == figures == 11  # the stored copy shows them all
    assert not [out for cell in stored.cells if cell.cell_type == "code" for out in cell.outputs
                if out.output_type == "error"]  # fmt: skip
    shown = "".join(out.get("data", {}).get("text/html", "") for out in outputs)
    for words in ("energy audit residual", "period-1 orbit", "branch in Q2", "sliding_vanish", "A0: period-1, no rest"):
        assert words in shown, words
