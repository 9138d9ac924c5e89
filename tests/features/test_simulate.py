
import json

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


@then("the command succeeds")
def succeeds(cli):
    assert cli["res"].exit_code == 0, cli["res"].output


@then(parsers.parse("the files {a}, {b} and {c} are written"))
def files_written(cli, a, b, c):
    for name in (a, b, c):
        assert (cli["dir"] / name).is_file(), name


@then(parsers.parse("every impact in {name} has t_in < t_out"))
def contact_episodes(cli, name):
    truth = json.loads((cli["dir"] / name).read_text())
    imps = truth["impacts"]
    assert len(imps) > 0
    assert all(i["t_in"] < i["t_out"] for i in imps)
    assert all(i["t"] == i["t_in"] for i in imps)


@then(parsers.parse("{name} has the columns {c1}, {c2}, {c3} and {c4}"))
def has_columns(cli, name, c1, c2, c3, c4):
    header = (cli["dir"] / name).read_text().splitlines()[0]
    assert header.split(",") == [c1, c2, c3, c4]


@then(parsers.parse('"vidiscover {args}" finds impacts in it'))
def analyze_reads_back(cli, args):
    res = CliRunner().invoke(main, [*args.split(), "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["impacts"]["n"] > 0


@then(parsers.parse("{name} records m1 {m1:g}, k1 {k1:g}, m2 {m2:g} and a sample rate "
                    "of {fs:g} Hz"))
def rig_metadata(cli, name, m1, k1, m2, fs):
    meta = json.loads((cli["dir"] / name).read_text())
    assert (meta["m1"], meta["k1"], meta["m2"], meta["sample_rate"]) == (m1, k1, m2, fs)
