
import numpy as np
import pytest
from click.testing import CliRunner
from pytest_bdd import given, parsers, scenarios, then, when

from vidiscover import Effects, preset
from vidiscover.cli import main
from vidiscover.workflows import simulate_to_memory

scenarios("simulate.feature")


@pytest.fixture()
def ctx():
    return {}


@given(parsers.parse("the paper preset with a half-clearance of {b_mm:g} mm"))
def given_preset(ctx, b_mm):
    ctx["params"] = preset("paper", b=b_mm * 1e-3)


def _run(ctx, effects, seed):
    rec, truth, result = simulate_to_memory(ctx["params"], Effects.parse(effects), seed=seed,
                                            settle=5.0, duration=2.0)
    ctx.update(rec=rec, truth=truth, result=result)


@when(parsers.parse("I simulate it with seed {seed:d}"))
def simulate_plain(ctx, seed):
    _run(ctx, [], seed)


@when(parsers.parse('I simulate it with the effect "{effect}" and seed {seed:d}'))
def simulate_effect(ctx, effect, seed):
    _run(ctx, [effect], seed)


@when(parsers.parse('I simulate it with the effects "{e1}" and "{e2}"'))
def simulate_two(ctx, e1, e2):
    _run(ctx, [e1, e2], 0)


@then("I get a recording with columns t, x, a and xe sampled at 6400 Hz")
def recording_columns(ctx):
    rec = ctx["rec"]
    assert list(rec.to_frame().columns) == ["t", "x", "a", "xe"]
    assert rec.sample_rate == 6400.0
    assert np.allclose(np.diff(rec.t), 1 / 6400.0)


@then("its ground truth lists impacts on both walls")
def both_walls(ctx):
    assert set(ctx["truth"].impacts.side) == {"right", "left"}


@then("the ground truth names a regime label")
def regime_label(ctx):
    from vidiscover.regimes import LABELS

    assert ctx["truth"].label in LABELS


@then(parsers.parse('the ground truth records the effect "{name}"'))
def records_effect(ctx, name):
    assert name in ctx["truth"].effects


@then("momentum is conserved at every impact")
def momentum(ctx):
    p = ctx["result"].params
    imp = ctx["result"].impacts
    before = p.m1 * imp.v_minus + p.m2 * imp.w_minus
    after = p.m1 * imp.v_plus + p.m2 * imp.w_plus
    assert imp.n > 0
    np.testing.assert_allclose(after, before, rtol=1e-12, atol=1e-15)


@then("the simulation completes")
def completes(ctx):
    assert ctx["result"].status == 0


@then("the ground truth reports sticking phases")
def sticking(ctx):
    assert len(ctx["truth"].sticking) > 0


@when(parsers.parse('I run "vidiscover {args}"'), target_fixture="cli")
def run_cli(args, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, args.split())
    return {"res": res, "dir": tmp_path}


@then(parsers.parse("the command fails with status {code:d}"))
def fails(cli, code):
    assert cli["res"].exit_code == code


@then(parsers.parse('the error message says "{text}"'))
def says(cli, text):
    assert text in cli["res"].stderr
    assert cli["res"].stderr.count("\n") == 1


@then("no file is written")
def no_file(cli):
    assert list(cli["dir"].iterdir()) == []
