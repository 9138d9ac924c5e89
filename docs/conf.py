"""Sphinx configuration of the vidiscover documentation.

Build (warnings are errors, as in CI)::

    .venv/bin/sphinx-build -W --keep-going -b html docs build/docs

then open ``build/docs/index.html``. The notebooks in ``notebooks/`` are executed during
the build (myst-nb) at the reduced size the test suite uses; set
``VIDISCOVER_NOTEBOOK_FAST=0`` for the full-size figures (several minutes), or add
``-D nb_execution_mode=off`` to check the text only.
"""

from __future__ import annotations

import atexit
import os
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# The notebooks' kernels inherit this environment: reduced size unless asked otherwise,
# and the inline backend so that their figures end up in the pages (CI exports
# MPLBACKEND=Agg, which would swallow them).
os.environ.setdefault("VIDISCOVER_NOTEBOOK_FAST", "1")
os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"
# Figures made without pyplot (the plotting functions return ``Figure`` objects) are
# shown as images only once the inline backend is active: start every kernel with it
# (as ``%matplotlib inline`` would), through an IPython profile of this build's own.
_IPYTHONDIR = Path(tempfile.mkdtemp(prefix="vidiscover-docs-ipython-"))
atexit.register(shutil.rmtree, _IPYTHONDIR, ignore_errors=True)
(_IPYTHONDIR / "profile_default").mkdir()
(_IPYTHONDIR / "profile_default" / "ipython_kernel_config.py").write_text(
    'c.InteractiveShellApp.matplotlib = "inline"\n')
os.environ["IPYTHONDIR"] = str(_IPYTHONDIR)

import vidiscover  # noqa: E402

project = "vidiscover"
author = "vidiscover developers"
copyright = "vidiscover developers, BSD-3-Clause"  # noqa: A001
version = release = vidiscover.__version__

extensions = [
    "myst_nb",  # Markdown pages (MyST) and executed notebooks
    "numpydoc",  # the docstrings are numpy style
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_click",
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
# Some docstrings write absolute values as |theta| or |z'-|, which reST reads as
# substitutions: define them as themselves (API pages are reST for this reason).
rst_prolog = r"""
.. |theta| replace:: \|theta\|
.. |z'-| replace:: \|z'-\|
"""
exclude_patterns = ["_build", "notebooks/*.py", "**/.ipynb_checkpoints"]
myst_enable_extensions = ["colon_fence", "dollarmath", "deflist"]
myst_heading_anchors = 3

# Notebooks: executed on every build (their outputs depend on vidiscover's code, not
# only on the notebook, so a cache keyed on the notebook would go stale), one kernel at
# a time; a failing cell fails the build. ``-D nb_execution_mode=off`` skips them.
nb_execution_mode = "force"
nb_execution_in_temp = True  # files a notebook writes go to a temporary folder
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "none"  # numpydoc renders the documented types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()

html_theme = "furo"
html_title = f"vidiscover {release}"
html_static_path: list[str] = []
