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


def test_analysing_a_recording_does_not_load_pandas():
    """Sweep and gap workers analyse thousands of recordings and build no table: the
    analysis imports pandas only where it builds a DataFrame (worker start-up cost)."""
    code = ("import sys\n"
            "from vidiscover.analysis import PulseModel, analyze\n"
            "from vidiscover.params import preset\n"
            "from vidiscover.regimes.features import ALL_FEATURES\n"
            "from vidiscover.workflows import simulate_to_memory\n"
            "rec, _, _ = simulate_to_memory(preset('paper'), settle=1.0, duration=1.0)\n"
            "an = analyze(rec, n_boot=0, pulse=PulseModel(), features=ALL_FEATURES)\n"
            "print('pandas' in sys.modules, an.impact_table.shape[0] == an.detection.n, "
            "'pandas' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "False True True"        # loaded by the first table, not before
