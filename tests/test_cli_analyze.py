"""``vidiscover analyze``: files, JSON, human output, several recordings, bad input."""

import json
import re
import shutil

import pandas as pd
import pytest
from click.testing import CliRunner

from vidiscover import preset
from vidiscover.cli import main
from vidiscover.io import write_recording
from vidiscover.report import FIGURES
from vidiscover.workflows import simulate_to_memory

R_RIGHT, R_LEFT = 0.8782, 0.2018
ASYM = (f"asymmetric_restitution={R_RIGHT},{R_LEFT}",)
R_TOL = 0.02


@pytest.fixture(scope="module")
def recs(tmp_path_factory):
    """Two simulated recordings (b = 9 and 15 mm) with metadata and ground truth."""
    d = tmp_path_factory.mktemp("recs")
    for k, b_mm in enumerate((9, 15)):
        rec, truth, _ = simulate_to_memory(preset("paper", b=b_mm / 1000), ASYM, seed=k,
                                           settle=4.0, duration=3.0, name=f"b{b_mm}")
        write_recording(rec, d / f"b{b_mm}.csv", truth=truth)
    return d


@pytest.fixture()
def runner():
    return CliRunner()


def _ok(res):
    assert res.exit_code == 0, res.output + (res.stderr or "")
    return res


def test_one_recording_json_files_and_truth(runner, recs, tmp_path):
    out = tmp_path / "out"
    res = _ok(runner.invoke(main, ["analyze", str(recs / "b9.csv"), "--out", str(out),
                                   "--json"]))
    doc = json.loads(res.stdout)
    assert isinstance(doc, dict)
    assert doc["impacts"]["n"] == len(doc["impacts"]["t"]) == len(doc["impacts"]["side"])
    assert set(doc["impacts"]["side"]) == {"right", "left"}
    assert doc["regime"].keys() >= {"label"}
    assert abs(doc["restitution"]["right"]["rms"] - R_RIGHT) < R_TOL
    assert abs(doc["restitution"]["left"]["rms"] - R_LEFT) < R_TOL
    assert doc["restitution"]["right"]["n"] > 5 and doc["restitution"]["left"]["n"] > 5
    # the files
    assert doc["out"] == str(out)
    assert sorted(p.name for p in out.iterdir()) == [".vidiscover", "figures", "flights.csv",
                                                      "impacts.csv", "report.html",
                                                      "summary.json"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary == {k: v for k, v in doc.items() if k not in ("out", "files")}
    assert len(pd.read_csv(out / "impacts.csv")) == summary["impacts"]["n"]
    assert sorted(p.stem for p in (out / "figures").iterdir()) == sorted(FIGURES)
    # truth beside the recording was found and compared
    assert summary["truth"]["regime"]["label"] is not None
    assert abs(summary["truth"]["restitution"]["right"]["rms"] - R_RIGHT) < 1e-9
    html = (out / "report.html").read_text(encoding="utf-8")
    assert all(f'id="fig-{n}"' in html for n in FIGURES)


def test_human_output(runner, recs, tmp_path):
    out = tmp_path / "o"
    res = _ok(runner.invoke(main, ["analyze", str(recs / "b9.csv"), "--out", str(out),
                                   "--no-figures"]))
    n = json.loads((out / "summary.json").read_text())["impacts"]["n"]
    assert re.search(rf"^b9: {n} impacts \(\d+ right, \d+ left\)", res.stdout, flags=re.M)
    # the interval printed with the decimals two digits of its half-width carry, the
    # value with as many (it printed "0.878 [0.878, 0.878]")
    m = re.search(r"r right RMS (0\.8\d+) \[(0\.\d+), (0\.\d+)\] \(n = \d+\)", res.stdout)
    assert m and len({len(g) for g in m.groups()}) == 1
    value, lo, hi = (float(g) for g in m.groups())
    assert lo < value < hi and 10 <= (hi - lo) / 2 * 10 ** (len(m.group(1)) - 2) < 100
    assert "regime:" in res.stdout and str(out) in res.stdout
    assert not (out / "figures").exists()


def test_several_recordings_subdirs_index_and_json_list(runner, recs, tmp_path):
    out = tmp_path / "many"
    res = _ok(runner.invoke(main, ["analyze", str(recs / "b9.csv"), str(recs / "b15.csv"),
                                   "--out", str(out), "--json", "--no-figures"]))
    docs = json.loads(res.stdout)
    assert isinstance(docs, list) and [d["recording"] for d in docs] == ["b9", "b15"]
    assert sorted(p.name for p in out.iterdir()) == [".vidiscover", "b15", "b9", "index.html"]
    for d in docs:
        sub = out / d["recording"]
        assert d["out"] == str(sub)
        assert json.loads((sub / "summary.json").read_text())["impacts"] == d["impacts"]
        assert len(pd.read_csv(sub / "impacts.csv")) == d["impacts"]["n"]
    index = (out / "index.html").read_text(encoding="utf-8")
    assert re.findall(r'<a href="([^"]+)"', index) == ["b9/report.html", "b15/report.html"]


def test_same_stem_twice_gets_two_subdirs(runner, recs, tmp_path):
    other = tmp_path / "copy"
    other.mkdir()
    for suffix in (".csv", ".json"):
        shutil.copy(recs / f"b9{suffix}", other / f"b9{suffix}")
    out = tmp_path / "dup"
    _ok(runner.invoke(main, ["analyze", str(recs / "b9.csv"), str(other / "b9.csv"),
                             "--out", str(out), "--no-figures", "--json"]))
    assert sorted(p.name for p in out.iterdir()) == [".vidiscover", "b9", "b9-2", "index.html"]
    # the copy has no truth file: its summary has no truth
    assert "truth" in json.loads((out / "b9" / "summary.json").read_text())
    assert "truth" not in json.loads((out / "b9-2" / "summary.json").read_text())


def test_mu_and_seed_are_used(runner, recs, tmp_path):
    res = _ok(runner.invoke(main, ["analyze", str(recs / "b9.csv"), "--out",
                                   str(tmp_path / "m"), "--mu", "0.1", "--seed", "5",
                                   "--no-figures", "--json"]))
    doc = json.loads(res.stdout)
    assert doc["mu"] == 0.1 and doc["restitution"]["mu"] == 0.1


def test_meta_option(runner, recs, tmp_path):
    d = tmp_path / "data"
    d.mkdir()
    shutil.copy(recs / "b9.csv", d / "rec.csv")
    meta = tmp_path / "meta.json"
    shutil.copy(recs / "b9.json", meta)
    res = _ok(runner.invoke(main, ["analyze", str(d / "rec.csv"), "--meta", str(meta),
                                   "--out", str(tmp_path / "o"), "--no-figures", "--json"]))
    assert json.loads(res.stdout)["b"] == pytest.approx(0.009)


def _bad_column(recs, d):
    frame = pd.read_csv(recs / "b9.csv").rename(columns={"a": "acc"})
    frame.to_csv(d / "bad.csv", index=False)
    shutil.copy(recs / "b9.json", d / "bad.json")
    return [str(d / "bad.csv")]


@pytest.mark.parametrize("case,match", [
    ("missing", "no such recording file"),
    ("bad_column", "missing column 'a'"),
    ("mu", "--mu must be in [0, 2]"),
    ("meta", "no such metadata file"),
    ("second_bad", "missing column 'a'"),
    ("out_is_file", "is not a directory"),
    ("directory", "is a directory, not a recording"),
])
def test_bad_input_exit_2_one_line_no_output(runner, recs, tmp_path, case, match):
    d = tmp_path / "in"
    d.mkdir()
    out = tmp_path / "out"
    args = {"missing": lambda: [str(d / "nope.csv")],
            "bad_column": lambda: _bad_column(recs, d),
            "mu": lambda: [str(recs / "b9.csv"), "--mu", "-1"],
            "meta": lambda: [str(recs / "b9.csv"), "--meta", str(d / "none.json")],
            "second_bad": lambda: [str(recs / "b9.csv"), *_bad_column(recs, d)],
            "out_is_file": lambda: [str(recs / "b9.csv")],
            "directory": lambda: [str(d)]}[case]()
    if case == "out_is_file":
        out.write_text("x")
    res = runner.invoke(main, ["analyze", *args, "--out", str(out)])
    assert res.exit_code == 2, res.output
    assert match in res.stderr
    assert res.stderr.count("\n") == 1 and "Traceback" not in res.stderr
    if case == "out_is_file":
        assert out.read_text() == "x"
    else:
        assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["in", *(["out"] if case == "out_is_file" else [])])


def test_no_recording_is_a_usage_error(runner, tmp_path):
    res = runner.invoke(main, ["analyze", "--out", str(tmp_path / "o")])
    assert res.exit_code == 2 and "RECORDINGS" in res.stderr
    assert list(tmp_path.iterdir()) == []


class _FakeModel:
    """Stands in for a trained regime model: labels from the detected impacts per cycle."""

    def classify_analysis(self, result):
        from types import SimpleNamespace

        label = "multi_ipc" if result.features["impacts_per_cycle"] > 2.5 else "2ipc_asym"
        return SimpleNamespace(label=label, proba={label: 0.9, "chaotic": 0.1},
                               warnings=("b = 0.009 outside the training range",))


def test_regime_label_comes_from_the_model(recs, tmp_path):
    from vidiscover.commands.analyze import human_lines, run_analyze

    (doc,) = run_analyze([recs / "b9.csv"], tmp_path / "o", figures=False,
                         model=_FakeModel())
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    expected = "multi_ipc" if s["features"]["impacts_per_cycle"] > 2.5 else "2ipc_asym"
    assert s["regime"]["label"] == doc["regime"]["label"] == expected
    assert s["regime"]["proba"][expected] == 0.9
    assert any("outside the training domain" in w for w in s["warnings"])
    assert f"regime: {expected} (p = 0.90)" in "\n".join(human_lines(doc))
    html = (tmp_path / "o" / "report.html").read_text(encoding="utf-8")
    assert "Regime (classifier)" in html and f"<b>{expected}</b>" in html


def test_bad_model_path_is_refused(runner, recs, tmp_path):
    res = runner.invoke(main, ["analyze", str(recs / "b9.csv"), "--model",
                               str(tmp_path / "none.skops"), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2 and "no such model file" in res.stderr
    assert res.stderr.count("\n") == 1 and not (tmp_path / "o").exists()
