"""Every notebook is executed in the test run (at reduced size), and its jupytext
`# %%` source and the committed .ipynb say the same thing.

Where the documentation tools are installed (the ``dev`` extra, CI), the docs build of
``tests/test_docs.py`` executes every notebook (a failing cell fails the build) and
checks its figures; the notebooks are then not executed a second time here (about
two minutes of CI). ``VIDISCOVER_TEST_NOTEBOOKS=1`` executes them here as well.
"""

import importlib.util
import os
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).parents[1] / "notebooks").glob("*.ipynb"))
DOCS_TOOLS = ("sphinx", "myst_nb", "numpydoc", "sphinx_click", "furo")
EXECUTED_BY_DOCS = (all(importlib.util.find_spec(m) for m in DOCS_TOOLS)
                    and os.environ.get("VIDISCOVER_TEST_NOTEBOOKS") != "1")


@pytest.mark.skipif(EXECUTED_BY_DOCS, reason="executed by the docs build (tests/test_docs.py); "
                    "VIDISCOVER_TEST_NOTEBOOKS=1 runs them here too")
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs(path, tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv("VIDISCOVER_NOTEBOOK_FAST", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("output_type") == "error"]
    assert not errors


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_matches_its_jupytext_source(path):
    jupytext = pytest.importorskip("jupytext")
    source = path.with_suffix(".py")
    assert source.exists(), f"{source.name} (jupytext percent format) is the source of {path.name}"
    py_cells = [c.source for c in jupytext.read(source).cells if c.cell_type == "code"]
    nb_cells = [c.source for c in jupytext.read(path).cells if c.cell_type == "code"]
    assert py_cells == nb_cells, f"run: jupytext --to ipynb {source}"
