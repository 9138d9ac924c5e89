"""Steps of features/sweep.feature."""

import json

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from pytest_bdd import given, parsers, scenarios, then, when

from vidiscover import preset
from vidiscover.cli import main
from vidiscover.regimes.labels import LABELS
from vidiscover.sweep import sweep

scenarios("sweep.feature")

SHORT = dict(settle=10.0, duration=2.0, seed=1, progress=False)


@pytest.fixture()
def ctx():
    return {}


@given("the paper preset")
def paper(ctx):
    ctx["base"] = preset("paper")


@given(parsers.parse("the paper preset with a half-clearance of {b_mm:g} mm"))
def paper_b(ctx, b_mm):
    ctx["base"] = preset("paper", b=b_mm * 1e-3)


@when(parsers.parse('I sweep "{param}" from {lo:g} mm to {hi:g} mm in {n:d} points'))
@when(parsers.parse('I sweep "{param}" from {lo:g} mm to {hi:g} mm in {n:d} points serially'))
def sweep_mm(ctx, param, lo, hi, n):
    ctx["args"] = (param, np.linspace(lo, hi, n) * 1e-3)
    ctx["df"] = sweep(*ctx["args"], base=ctx["base"], n_jobs=1, **SHORT)


@when(parsers.parse('I sweep "{param}" from {lo:g} to {hi:g} in {n:d} points'))
def sweep_plain(ctx, param, lo, hi, n):
    ctx["df"] = sweep(param, np.linspace(lo, hi, n), base=ctx["base"], n_jobs=1, **SHORT)


@when("I run the same sweep on a local Dask cluster")
def on_dask(ctx):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  protocol="tcp", host="127.0.0.1",
                                  dashboard_address=None) as lc:
        ctx["dask"] = sweep(*ctx["args"], base=ctx["base"], scheduler=lc.scheduler_address,
                            **SHORT)


@then("every point has a ground-truth regime label")
def labelled(ctx):
    assert ctx["df"]["label"].isin(LABELS).all()


@then(parsers.parse("at {b_mm:g} mm the ball hits both walls alternately, half a period apart"))
def symmetric(ctx, b_mm):
    df = ctx["df"]
    row = df[np.isclose(df["value"], b_mm * 1e-3)].iloc[0]
    assert row["label"] == "2ipc_sym"
    assert row["alternation"] == 1.0
    np.testing.assert_allclose(row["dt_T"], 0.5, atol=0.05)


@then("the number of detected impacts matches the truth at every point")
def detected(ctx):
    df = ctx["df"]
    assert (df["n_impacts"] - df["n_impacts_true"]).abs().max() <= 1


@then("the two tables are identical")
def identical(ctx):
    pd.testing.assert_frame_equal(ctx["dask"], ctx["df"], check_exact=True)


@then("the restitution estimated from the sensor data follows the swept value")
def restitution(ctx):
    df = ctx["df"]
    for side in ("right", "left"):
        np.testing.assert_allclose(df[f"r_rms_{side}"], df["value"], atol=0.03)


@when(parsers.parse('I run "vidiscover {args}"'), target_fixture="cli")
def run_cli(args, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, args.split())
    return {"res": res, "dir": tmp_path}


@then(parsers.parse("the JSON lists {n:d} rows and the outputs"))
def json_rows(cli, n):
    assert cli["res"].exit_code == 0, cli["res"].output
    doc = json.loads(cli["res"].stdout)
    assert len(doc["rows"]) == n and len(doc["outputs"]) == 4


@then(parsers.parse('"{out}" holds sweep.parquet, bifurcation.parquet, sweep.json and '
                    "bifurcation.png"))
def holds(cli, out):
    names = sorted(p.name for p in (cli["dir"] / out).iterdir())
    assert names == [".vidiscover", "bifurcation.parquet", "bifurcation.png", "sweep.json",
                     "sweep.parquet"]


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
