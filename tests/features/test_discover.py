"""Steps for features/discover.feature (``vidiscover discover`` through click's runner)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner
from pytest_bdd import given, parsers, scenarios, then, when

from vidiscover import Effects, preset, record, simulate
from vidiscover.cli import main
from vidiscover.io import write_recording
from vidiscover.restitution_laws import RestitutionLaw

scenarios("discover.feature")


@pytest.fixture()
def rig(tmp_path):
    return {"dir": tmp_path}


@given(parsers.parse('recordings simulated at 6, 7.5 and 9 mm with right wall "{right}" '
                     'and left wall "{left}"'))
def sweep(rig, right, left):
    fx = Effects.parse([f"velocity_dependent_restitution=right={right},left={left}"])
    rig["laws"] = {"right": RestitutionLaw.parse(right), "left": RestitutionLaw.parse(left)}
    rig["paths"] = []
    for k, b in enumerate((0.006, 0.0075, 0.009)):
        rec, truth = record(simulate(preset("paper", b=b), fx, settle=5.0, duration=3.0),
                            seed=k)
        path = rig["dir"] / f"b{k}.csv"
        write_recording(rec, path, truth=truth)
        rig["paths"].append(str(path))


def _run(rig, extra=()):
    rig["out"] = rig["dir"] / "out"
    rig["result"] = CliRunner().invoke(
        main, ["discover", *rig["paths"], *extra, "--out", str(rig["out"]), "--json",
               "--n-boot", "30", "--no-figures"])


@when("I run discover on them")
def run(rig):
    _run(rig)
    assert rig["result"].exit_code == 0, rig["result"].output
    rig["doc"] = json.loads(rig["result"].stdout)


@when("I run discover on them and a file that does not exist")
def run_missing(rig):
    rig["missing"] = str(rig["dir"] / "nowhere.csv")
    _run(rig, [rig["missing"]])


@then(parsers.parse('the {side} wall law has the form of "{spec}"'))
def form(rig, side, spec):
    law, truth = rig["doc"]["impact_law"][side]["law"], RestitutionLaw.parse(spec)
    assert law is not None and law["kind"] == truth.kind
    if truth.kind == "power":
        assert math.isclose(law["p"], truth.p)


@then("each fitted law is within 0.02 of the truth over the observed impact speeds")
def close(rig):
    for side, truth in rig["laws"].items():
        law = rig["doc"]["impact_law"][side]
        found = RestitutionLaw(**{k: law["law"][k] for k in ("kind", "r0", "a", "p")})
        grid = np.linspace(*law["speed_range"], 100)
        assert np.max(np.abs(found(grid) - truth(grid))) < 0.02


@then("the JSON names the flight law and both impact-law formulas")
def keys(rig):
    doc = rig["doc"]
    assert {"mu", "theta_deg", "terms"} <= set(doc["flight"])
    assert all(doc["impact_law"][s]["formula"].startswith("r = ") for s in ("right", "left"))


@then("I get one line that names the missing file")
def one_line(rig):
    res = rig["result"]
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "nowhere.csv" in lines[0]


@then("no output directory is written")
def nothing(rig):
    assert not rig["out"].exists()
