"""Steps for features/analyze.feature: ``vidiscover analyze`` run through click's CliRunner."""

import base64
import json
import re

import pandas as pd
import pytest
from click.testing import CliRunner
from pytest_bdd import given, parsers, scenarios, then, when

from vidiscover import preset
from vidiscover.cli import main
from vidiscover.io import write_recording
from vidiscover.report import FIGURES
from vidiscover.workflows import simulate_to_memory

scenarios("analyze.feature")


@pytest.fixture()
def rig(tmp_path):
    return {"dir": tmp_path, "recordings": [], "out": tmp_path / "report"}


def _simulate(rig, b_mm: float, r_right: float, r_left: float):
    stem = f"b{b_mm:g}mm"
    rec, truth, _ = simulate_to_memory(
        preset("paper", b=b_mm / 1000), [f"asymmetric_restitution={r_right},{r_left}"],
        seed=len(rig["recordings"]), settle=4.0, duration=3.0, name=stem)
    path = rig["dir"] / f"{stem}.csv"
    write_recording(rec, path, truth=truth)
    rig["recordings"].append(path)
    return path


@given(parsers.parse("a simulated recording of the paper rig at b = {b_mm:g} mm with "
                     "r = {r_right:g} on the right wall and {r_left:g} on the left"))
def simulated(rig, b_mm, r_right, r_left):
    _simulate(rig, b_mm, r_right, r_left)


@given(parsers.parse('a recording whose acceleration column is named "{name}"'))
def bad_column(rig, name):
    path = _simulate(rig, 9, 0.88, 0.2)
    pd.read_csv(path).rename(columns={"a": name}).to_csv(path, index=False)


def _run(rig, *extra):
    args = ["analyze", *map(str, rig["recordings"]), "--out", str(rig["out"]), *extra]
    rig["res"] = CliRunner().invoke(main, args)


@when("I analyze it")
def analyze_it(rig):
    _run(rig)


@when("I analyze them without figures")
def analyze_them(rig):
    _run(rig, "--no-figures")


def _summary(rig) -> dict:
    assert rig["res"].exit_code == 0, rig["res"].output + rig["res"].stderr
    return json.loads((rig["out"] / "summary.json").read_text())


@then("summary.json says there are impacts on both walls")
def both_walls(rig):
    s = _summary(rig)
    assert s["impacts"]["n"] == len(s["impacts"]["t"]) > 0
    assert set(s["impacts"]["side"]) == {"right", "left"}


@then(parsers.parse("summary.json gives the {side} wall an RMS restitution within "
                    "{tol:g} of {value:g}"))
def restitution(rig, side, tol, value):
    w = _summary(rig)["restitution"][side]
    assert w["n"] > 5
    assert abs(w["rms"] - value) < tol


@then("summary.json counts as many impacts as impacts.csv has rows")
def counts(rig):
    assert _summary(rig)["impacts"]["n"] == len(pd.read_csv(rig["out"] / "impacts.csv"))


@then("report.html shows every figure and needs no other file")
def report(rig):
    html = (rig["out"] / "report.html").read_text(encoding="utf-8")
    for name in FIGURES:
        png = (rig["out"] / "figures" / f"{name}.png").read_bytes()
        assert f'id="fig-{name}"' in html and base64.b64encode(png).decode() in html
    refs = re.findall(r"<[^>]*\b(?:src|href)\s*=\s*[\"']?([^\"'\s>]+)", html, flags=re.I)
    assert refs and all(r.startswith(("data:", "#")) for r in refs)


@then("there is one report per recording")
def one_per_recording(rig):
    assert rig["res"].exit_code == 0, rig["res"].stderr
    for path in rig["recordings"]:
        s = json.loads((rig["out"] / path.stem / "summary.json").read_text())
        assert s["recording"] == path.stem
        assert (rig["out"] / path.stem / "report.html").is_file()


@then("index.html links every report")
def index(rig):
    html = (rig["out"] / "index.html").read_text(encoding="utf-8")
    assert re.findall(r'<a href="([^"]+)"', html) == [f"{p.stem}/report.html"
                                                   for p in rig["recordings"]]


@then(parsers.parse("the command fails with status {code:d}"))
def fails(rig, code):
    assert rig["res"].exit_code == code


@then(parsers.parse('the error message says "{text}"'))
def says(rig, text):
    assert text in rig["res"].stderr
    assert rig["res"].stderr.count("\n") == 1


@then("no output directory is written")
def no_output(rig):
    assert not rig["out"].exists()
    assert not [p for p in rig["dir"].iterdir() if p.name.startswith(".report")]
