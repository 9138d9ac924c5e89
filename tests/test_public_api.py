"""The public surface is small, explicit and free of private names."""

import importlib
import subprocess
import sys

import vidiscover


def test_every_public_name_imports():
    for name in vidiscover.__all__:
        assert getattr(vidiscover, name) is not None, name


def test_no_private_names_are_public():
    assert all(not n.startswith("_") for n in vidiscover.__all__)
    for mod in ("effects", "params", "recording", "truth", "sensors", "simulation", "io",
                "restitution_laws", "regimes", "analysis", "discovery", "report"):
        m = importlib.import_module(f"vidiscover.{mod}")
        assert all(not n.startswith("_") for n in m.__all__), mod
        for n in m.__all__:
            assert hasattr(m, n), f"vidiscover.{mod}.{n} listed but missing"


def test_cli_import_stays_light():
    """`vidiscover --help` must not pay for numpy/scipy/matplotlib/pysindy/sklearn."""
    code = ("import sys, vidiscover.cli; heavy = {'numpy', 'scipy', 'matplotlib', "
            "'pysindy', 'sklearn', 'pandas'} & set(sys.modules); print(sorted(heavy))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
