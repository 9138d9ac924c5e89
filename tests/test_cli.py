import json
import re

import pytest
from click.testing import CliRunner

from vidiscover.cli import main

FAST = ["--settle", "2", "--duration", "1.5"]


@pytest.fixture()
def runner():
    return CliRunner()


def test_help_lists_the_commands(runner):
    res = runner.invoke(main, ["--help"])
    assert res.exit_code == 0
    for cmd in ("simulate", "demo"):
        assert cmd in res.output


def test_simulate_writes_recording_metadata_truth_and_json(runner, tmp_path):
    out = tmp_path / "rec.csv"
    res = runner.invoke(main, ["simulate", "--b", "0.009", "--effect", "coulomb_friction=0.1",
                               "--seed", "3", "--out", str(out), "--json", *FAST])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert {"impacts", "regime"} <= set(doc)
    assert doc["impacts"]["n"] == len(doc["impacts"]["t"]) > 0
    assert set(doc["impacts"]["side"]) <= {"right", "left"}
    assert doc["effects"] == {"coulomb_friction": {"mu": 0.1}}
    for f in ("rec.csv", "rec.json", "rec.truth.json"):
        assert (tmp_path / f).exists()
    truth = json.loads((tmp_path / "rec.truth.json").read_text())
    assert truth["regime"]["label"] == doc["regime"]["label"]
    assert len(truth["impacts"]) == doc["impacts"]["n"]


def test_simulate_is_deterministic(runner, tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    for out in (a, b):
        assert runner.invoke(main, ["simulate", "--seed", "7", "--out", str(out), *FAST]
                             ).exit_code == 0
    assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize("args,match", [
    (["--b", "-0.009"], "b must be > 0"),
    (["--b", "9"], "implausibly large"),
    (["--effect", "friction=0.3"], "unknown effect 'friction'"),
    (["--effect", "coulomb_friction=abc"], "mu must be in"),
    (["--param", "m2"], "expected NAME=VALUE"),
    (["--param", "mass=3"], "unknown parameter"),
    (["--noise", "-1"], "--noise must be >= 0"),
])
def test_simulate_bad_input_one_line_exit_2_no_files(runner, tmp_path, args, match):
    out = tmp_path / "rec.csv"
    res = runner.invoke(main, ["simulate", *args, "--out", str(out), *FAST])
    assert res.exit_code == 2
    assert match in res.stderr
    assert res.stderr.count("\n") == 1 and "Traceback" not in res.stderr
    assert list(tmp_path.iterdir()) == []


def test_simulate_unknown_format(runner, tmp_path):
    res = runner.invoke(main, ["simulate", "--out", str(tmp_path / "rec.xlsx"), *FAST])
    assert res.exit_code == 2 and "unknown format '.xlsx'" in res.stderr
    assert list(tmp_path.iterdir()) == []


def test_demo_writes_recordings_reports_and_an_index(tmp_path):
    from vidiscover.demo import run_demo

    out = tmp_path / "demo"
    doc = run_demo(out, seed=1, progress=False, clearances_mm=(9.0, 15.0), settle=4.0,
                   duration=2.0, figures=False)
    written = sorted(str(p.relative_to(out)) for p in out.rglob("*")
                     if p.is_file() and p.name != ".vidiscover")
    assert sorted(doc["outputs"]) == written
    for stem in ("paper_b9mm", "paper_b15mm"):
        for f in (f"{stem}.csv", f"{stem}.json", f"{stem}.truth.json", f"{stem}.png",
                  f"{stem}/summary.json", f"{stem}/impacts.csv", f"{stem}/report.html"):
            assert f in written
    index = (out / "index.html").read_text(encoding="utf-8")
    assert re.findall(r'<a href="([^"]+)"', index) == ["paper_b9mm/report.html",
                                                      "paper_b15mm/report.html"]
    for r in doc["recordings"]:
        assert abs(r["r_right_rms"] - 0.8782) < 0.02 and abs(r["r_left_rms"] - 0.2018) < 0.02
        s = json.loads((out / r["report"]).with_name("summary.json").read_text())
        assert s["impacts"]["n"] == r["detected"] > 0


@pytest.mark.slow
def test_demo_command_full_size(runner, tmp_path):
    res = runner.invoke(main, ["demo", "--out", str(tmp_path / "d"), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert "index.html" in doc["outputs"] and len(doc["recordings"]) == 5
    assert all((tmp_path / "d" / f).is_file() for f in doc["outputs"])


def test_demo_prints_one_line_per_clearance(runner, tmp_path, monkeypatch):
    """Human output: where the index is, then classified vs true regime and r per wall."""
    import vidiscover.demo as demo_mod

    real = demo_mod.run_demo

    def small(out, seed=0, progress=True):
        return real(out, seed=seed, progress=False, clearances_mm=(9.0,), settle=4.0,
                    duration=2.0, figures=False)

    monkeypatch.setattr(demo_mod, "run_demo", small)
    res = runner.invoke(main, ["demo", "--out", str(tmp_path / "d")])
    assert res.exit_code == 0, res.output
    lines = res.output.strip().splitlines()
    assert "index.html" in lines[0]
    assert len(lines) == 2 and lines[1].strip().startswith("paper_b9mm:")
    assert "(true " in lines[1] and "r right" in lines[1] and "r left" in lines[1]
