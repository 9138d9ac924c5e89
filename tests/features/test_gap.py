import json
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner
from pytest_bdd import given, parsers, scenarios, then, when

sys.path.insert(0, str(Path(__file__).parents[1]))
from gap_cases import quick_battery, recording  # noqa: E402

from vidiscover.cli import main  # noqa: E402
from vidiscover.io import write_recording  # noqa: E402

scenarios("gap.feature")


@pytest.fixture()
def ctx():
    return {}


@given(parsers.parse('a recording simulated at {b_mm:g} mm with the withheld effect "{effect}"'))
def given_recording(ctx, tmp_path, b_mm, effect):
    rec, truth = recording(b_mm * 1e-3, (effect,))
    path = tmp_path / "rec.csv"
    write_recording(rec, path, truth=truth)
    ctx["rec"] = path


@when("I run vidiscover gap on it with --json")
def run_gap(ctx, tmp_path):
    out = tmp_path / "gap"
    res = CliRunner().invoke(main, ["gap", str(ctx["rec"]), "--out", str(out), "--json",
                                    "--n-jobs", "1"])
    assert res.exit_code == 0, res.output
    ctx.update(doc=json.loads(res.output), out=out)


@then("the JSON document has the keys gap_before, effects, attributed and unexplained")
def has_keys(ctx):
    doc = ctx["doc"]
    assert {"gap_before", "effects", "attributed", "unexplained"} <= set(doc)
    assert all({"name", "params", "gap_after", "shrink"} <= set(e) for e in doc["effects"])


@then(parsers.parse('the attributed effect is "{name}"'))
def attributed(ctx, name):
    assert ctx["doc"]["attributed"][0]["name"] == name
    assert ctx["doc"]["verdict"] == name


@then(parsers.parse("the attributed effect removes at least {pct:d} % of the gap"))
def removes(ctx, pct):
    assert ctx["doc"]["attributed"][0]["share"] >= pct / 100


@then("the output directory holds summary.json, report.html and the waterfall figure")
def outputs(ctx):
    out = ctx["out"]
    assert json.loads((out / "summary.json").read_text())["gap_before"] == \
        ctx["doc"]["gap_before"]
    assert (out / "report.html").is_file()
    assert (out / "figures" / "waterfall.png").is_file()


@when("I run vidiscover gap on a file that does not exist")
def run_missing(ctx, tmp_path):
    out = tmp_path / "gap"
    ctx["out"] = out
    ctx["res"] = CliRunner().invoke(main, ["gap", str(tmp_path / "nope.csv"), "--out",
                                           str(out)])


@then("the command exits with status 2 and one line naming the file")
def exit_two(ctx):
    res = ctx["res"]
    assert res.exit_code == 2
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and "nope.csv" in lines[0]
    assert "Traceback" not in res.output


@then("no output directory is left behind")
def no_output(ctx):
    assert not ctx["out"].exists()


@when("I run the quick withheld-effect battery")
def run_battery(ctx):
    ctx["battery"] = quick_battery()


@then("every case has an expected and a predicted verdict")
def verdicts(ctx):
    b = ctx["battery"]
    assert {"accuracy", "confusion", "cases"} <= set(b)
    assert all(c["expected"] and c["predicted"] for c in b["cases"])


@then("the no-effect case is reported as no significant gap")
def none_case(ctx):
    c = next(c for c in ctx["battery"]["cases"] if c["effect"] == "none")
    assert c["predicted"] == "none"


@then("the out-of-catalogue case leaves at least half of the gap unexplained")
def outside(ctx):
    c = next(c for c in ctx["battery"]["cases"] if c["kind"] == "outside")
    assert c["unexplained"] >= 0.5
