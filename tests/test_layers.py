"""Layers follow the data: no stage imports a later one, not even inside a function.

io -> simulation -> analysis -> discovery -> regimes -> gap -> commands/cli. The
import-time check (``import vidiscover.analysis`` loads no later stage) is in
``test_pulse_learning.py``; this one reads every module's source, so a deferred
import inside a function (which the import-time check cannot see) fails too.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import vidiscover

ROOT = Path(vidiscover.__file__).parent
#: package -> the later stages it must not import
LATER = {
    "analysis": ("simulation", "discovery", "regimes", "gap", "orbits", "commands", "cli"),
    "discovery": ("regimes", "gap", "commands", "cli"),
    "regimes": ("gap", "commands", "cli"),
}


def _imported(path: Path, root: Path = ROOT) -> set[str]:
    """Top-level vidiscover modules imported anywhere in ``path`` (relative or absolute)."""
    pkg = path.relative_to(root).parts[:-1]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = list(pkg[: len(pkg) - node.level + 1])
                mod = (node.module or "").split(".") if node.module else []
                parts = base + mod
                if not parts:        # "from .. import x": x names modules of the root
                    parts = [a.name for a in node.names]
                    out.update(parts)
                    continue
                out.add(parts[0])
            elif node.module and node.module.startswith("vidiscover."):
                out.add(node.module.split(".")[1])
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("vidiscover."):
                    out.add(a.name.split(".")[1])
    return out


@pytest.mark.parametrize("package", sorted(LATER))
def test_no_stage_imports_a_later_one(package):
    bad = {}
    for path in sorted((ROOT / package).rglob("*.py")):
        hit = _imported(path) & set(LATER[package])
        if hit:
            bad[str(path.relative_to(ROOT))] = sorted(hit)
    assert not bad, bad


def test_the_check_sees_a_deferred_import(tmp_path):
    """A function-level ``from ..discovery import x`` in analysis is found, and so is
    ``from .. import discovery``; a sibling import is not a later stage."""
    (tmp_path / "analysis").mkdir()
    fake = tmp_path / "analysis" / "probe.py"
    fake.write_text("from . import signals\n\ndef f():\n"
                    "    from ..discovery.flight_law import FlightLawResult\n"
                    "    from .. import regimes\n")
    assert _imported(fake, tmp_path) == {"analysis", "discovery", "regimes"}
