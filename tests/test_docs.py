"""The documentation site in docs/ builds warning-free, with the notebooks executed and
their figures in the pages, and the pages the docstrings cite exist."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
DOCS = ROOT / "docs"
PACKAGE = ROOT / "vidiscover"
#: How a docstring or an error message cites a page of the site.
CITATION = re.compile(r"docs page '([^']+)'")


def _page_titles() -> dict[str, Path]:
    """Title (first heading) of every Markdown/reST page of the site."""
    titles = {}
    for path in sorted(DOCS.rglob("*.md")) + sorted(DOCS.rglob("*.rst")):
        lines = path.read_text(encoding="utf-8").splitlines()
        for i, line in enumerate(lines):
            if line.startswith("# "):
                titles[line[2:].strip()] = path
                break
            if i + 1 < len(lines) and lines[i + 1] and set(lines[i + 1]) == {"="}:
                titles[line.strip()] = path
                break
    return titles


def _sources():
    return sorted(PACKAGE.rglob("*.py"))


def test_no_source_cites_the_internal_design_file():
    offenders = [f"{p.relative_to(ROOT)}:{n}" for p in _sources()
                 for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
                 if "DESIGN.md" in line]
    assert not offenders, f"cite a docs page instead of DESIGN.md: {offenders}"


def test_cited_docs_pages_exist():
    titles = _page_titles()
    cited = {(m.group(1), p.relative_to(ROOT)) for p in _sources()
             for m in CITATION.finditer(p.read_text(encoding="utf-8"))}
    assert cited, "the orbits package cites its docs page"
    missing = sorted(f"{page!r} (cited in {where})" for page, where in cited
                     if page not in titles)
    assert not missing, f"no docs page titled {missing}; pages: {sorted(titles)}"


@pytest.mark.slow
def test_docs_build_warning_free_with_executed_notebooks(tmp_path):
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")
    pytest.importorskip("numpydoc")
    pytest.importorskip("sphinx_click")
    pytest.importorskip("furo")
    out = tmp_path / "html"
    env = {**os.environ, "VIDISCOVER_NOTEBOOK_FAST": "1"}
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         str(DOCS), str(out)],
        capture_output=True, text=True, timeout=900, env=env, cwd=ROOT)
    # the notebooks' kernels print a notice on stderr; Sphinx's own warnings say WARNING:
    problems = [line for line in proc.stderr.splitlines()
                if ("WARNING:" in line or "ERROR:" in line) and "IPKernelApp" not in line]
    assert proc.returncode == 0 and not problems, proc.stderr[-4000:]

    for page in ("index", "install", "guide", "recording-format", "effects", "regimes",
                 "realism", "orbits", "cli", "api/core", "api/orbits"):
        assert (out / f"{page}.html").is_file(), page
    # every notebook rendered executed: its figures are images in the page
    for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
        html = (out / "notebooks" / f"{nb.stem}.html").read_text(encoding="utf-8")
        assert "<img" in html, f"{nb.name}: no figure in the rendered page"
        assert "Traceback" not in html, nb.name
    # the CLI reference lists every command with its options
    import click

    from vidiscover.cli import main

    cli = (out / "cli.html").read_text(encoding="utf-8")
    commands = main.list_commands(click.Context(main))
    assert len(commands) >= 11
    for command in commands:
        assert f'id="vidiscover-{command}"' in cli, f"docs/cli.rst lacks {command}"
    assert 'id="cmdoption-vidiscover-analyze-flight-law"' in cli  # options are listed too
    # the API reference documents every public name of the package
    import vidiscover

    api = "".join(p.read_text(encoding="utf-8") for p in (out / "api").glob("*.html"))
    for name in vidiscover.__all__:
        assert re.search(rf'id="vidiscover\.(\w+\.)*{name}"', api), name
