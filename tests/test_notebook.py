"""docs/python-api.ipynb runs as shown, in a Jupyter kernel: every cell, in order, without an
error; its figures and rich displays come out (the notebook's own cells assert what they read
back)."""

from __future__ import annotations

from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

NOTEBOOK = Path(__file__).parent.parent / "docs" / "python-api.ipynb"


def test_the_notebook_runs_and_shows_its_figures_and_tables(tmp_path):
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    assert all(not cell.get("outputs") for cell in notebook.cells if cell.cell_type == "code")  # kept clean in git
    nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()  # fmt: skip
    outputs = [out for cell in notebook.cells if cell.cell_type == "code" for out in cell.outputs]
    assert not [out for out in outputs if out.output_type == "error"]
    images = [out for out in outputs if "image/png" in out.get("data", {})]
    assert len(images) == sum(".plot" in cell.source for cell in notebook.cells if cell.cell_type == "code") == 6
    shown = "".join(out.get("data", {}).get("text/html", "") for out in outputs)
    for words in ("energy audit residual", "period-1 orbit", "branch in Q2", "sliding_vanish"):
        assert words in shown, words
