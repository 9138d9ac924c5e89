"""The CLI imports a command's module only when that command runs."""

import subprocess
import sys

from click.testing import CliRunner

from vidiscover import cli


def _python(code: str) -> str:
    """What ``code`` prints in a fresh interpreter (its imports start from nothing)."""
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout


def test_help_lists_every_installed_command_without_importing_them():
    code = ("import sys; from click.testing import CliRunner; from vidiscover.cli import main;"
            "r = CliRunner().invoke(main, ['--help']); print(r.output);"
            "heavy = [m for m in ('numpy', 'scipy', 'pandas', 'matplotlib', 'sklearn', 'pysindy',"
            " 'numba')"
            " if m in sys.modules]; print('HEAVY', heavy)")
    out = _python(code)
    assert "HEAVY []" in out
    for name in ("simulate", "demo", *cli.main.lazy_commands):
        assert f"  {name} " in out


def test_lazy_commands_resolve_to_click_commands():
    import click

    for name in cli.main.lazy_commands:
        cmd = cli.main.get_command(click.Context(cli.main), name)
        assert isinstance(cmd, click.Command), name


def test_unknown_command_is_a_usage_error():
    res = CliRunner().invoke(cli.main, ["no-such-command"])
    assert res.exit_code == 2
    assert "No such command" in res.output


def test_numba_loads_with_the_first_simulation_not_with_the_package():
    """The compiled event search costs a numba import (~0.4 s): only simulations pay it."""
    code = ("import sys; import vidiscover, vidiscover.simulation, vidiscover.analysis;"
            "print('BEFORE', 'numba' in sys.modules);"
            "from vidiscover import preset, simulate;"
            "simulate(preset('paper', b=0.009), settle=0.0, duration=0.2);"
            "print('AFTER', 'numba' in sys.modules)")
    out = _python(code)
    assert "BEFORE False" in out and "AFTER True" in out


def test_the_compliant_engine_loads_with_its_first_use():
    """scipy.integrate/optimize (~0.4 s) come with the compliant engine, not with simulate:
    a sweep worker running the exact engine and recording does without them."""
    code = ("import sys; from vidiscover import preset, record, simulate;"
            "import vidiscover.simulation as s;"
            "record(simulate(preset('paper', b=0.009), settle=0.0, duration=0.2), seed=0);"
            "print('EXACT', sorted({'scipy.integrate', 'scipy.optimize'} & set(sys.modules)));"
            "print('NAMES', s.simulate_reference.__module__, s.CompliantResult.__name__);"
            "print('AFTER', 'scipy.integrate' in sys.modules)")
    out = _python(code)
    assert "EXACT []" in out
    assert "NAMES vidiscover.simulation.compliant CompliantResult" in out
    assert "AFTER True" in out
