"""Steps of features/classify.feature."""

import json
import shlex

import pytest
from click.testing import CliRunner
from pytest_bdd import given, parsers, scenarios, then, when
from threadpoolctl import threadpool_limits

from vidiscover import Effects, preset
from vidiscover.cli import main
from vidiscover.io import write_recording
from vidiscover.regimes import LABELS
from vidiscover.workflows import simulate_to_memory

scenarios("classify.feature")

PAPER_WALLS = ("asymmetric_restitution=0.8782,0.2018",)


@pytest.fixture()
def ctx(tmp_path):
    with threadpool_limits(1):
        yield {"dir": tmp_path}


def _write(ctx, b_mm, settle=20.0, **kw):
    rec, truth, _ = simulate_to_memory(preset("paper", b=b_mm * 1e-3, **kw),
                                       Effects.parse(list(PAPER_WALLS)), seed=2,
                                       settle=settle)
    path = ctx["dir"] / f"rec_{b_mm:g}mm.csv"
    write_recording(rec, path, truth=truth)
    ctx.setdefault("files", []).append(path)
    ctx.setdefault("truth", {})[str(path)] = truth.label


def _invoke(ctx, args):
    res = CliRunner().invoke(main, args)
    ctx["result"] = res
    return res


@given("recordings of the paper's rig simulated at 9 and 17.5 mm")
def two_recordings(ctx):
    _write(ctx, 9.0)
    _write(ctx, 17.5)


@given(parsers.parse("a recording simulated with a half-clearance of {b_mm:g} mm"))
def one_recording(ctx, b_mm):
    _write(ctx, b_mm, settle=5.0)


@when(parsers.parse('I run "vidiscover classify" on {what} with --json'))
def run_classify(ctx, what):
    _invoke(ctx, ["classify", *map(str, ctx["files"]), "--json"])


@when('I run "vidiscover classify" on a file that does not exist')
def classify_missing(ctx):
    _invoke(ctx, ["classify", str(ctx["dir"] / "nope.csv")])


@when(parsers.parse('I run "vidiscover {command}" with --json'))
def run_train(ctx, command):
    ctx["model"] = ctx["dir"] / "model.skops"
    _invoke(ctx, [*shlex.split(command), "--out", str(ctx["model"]), "--json"])


@when(parsers.parse('I run "vidiscover train --out {name}"'))
def train_bad_out(ctx, name):
    _invoke(ctx, ["train", "--out", str(ctx["dir"] / name), "--n", "5"])


@then("the command succeeds")
def succeeds(ctx):
    res = ctx["result"]
    assert res.exit_code == 0, (res.output, res.stderr)
    ctx["json"] = json.loads(res.stdout)


@then("I get one entry per file with a label and the probability of every label")
def entries(ctx):
    out = ctx["json"]
    assert [e["file"] for e in out] == [str(p) for p in ctx["files"]]
    for e in out:
        assert e["label"] in LABELS and set(e["proba"]) == set(LABELS)
        assert sum(e["proba"].values()) == pytest.approx(1.0)
        assert e["proba"][e["label"]] == max(e["proba"].values())


@then("each label is the regime the simulation went through")
def labels_match(ctx):
    for e in ctx["json"]:
        assert e["label"] == ctx["truth"][e["file"]]


@then("a warning on stderr says the recording is outside the training domain")
def warns(ctx):
    assert "outside the training domain" in ctx["result"].stderr
    assert any("b = 0.06 outside the training range" in w for w in ctx["json"][0]["warnings"])


@then("the command fails with exit status 2 and one line on stderr")
def fails(ctx):
    res = ctx["result"]
    assert res.exit_code == 2
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr
    assert res.stdout == ""
    assert not list(ctx["dir"].glob("*.skops"))


@then("the JSON reports balanced_accuracy and confusion")
def train_json(ctx):
    out = ctx["json"]
    assert 0.0 <= out["balanced_accuracy"] <= 1.0
    m = out["confusion"]["matrix"]
    assert out["confusion"]["labels"] == list(LABELS) and sum(map(sum, m)) == out["n"]
    assert "balanced_accuracy" in out["baseline"]


@then("the model file and its training report are written")
def train_files(ctx):
    meta = json.loads(ctx["model"].with_suffix(".json").read_text())
    assert ctx["model"].is_file() and meta["seed"] == 3
    assert meta["command"].startswith("vidiscover train --seed 3 --n 16 --n-test 10")


@then("the model file loads with the trusted types only and labels a recording")
def train_loads(ctx):
    from vidiscover.regimes.classifier import load_model

    model = load_model(ctx["model"])
    rec, _, _ = simulate_to_memory(preset("paper", b=0.009), seed=4, settle=5.0,
                                   duration=2.0)
    assert model.classify(rec).label in LABELS
