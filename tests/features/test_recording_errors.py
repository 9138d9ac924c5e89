"""Steps for features/recording_errors.feature.

"When I analyze it" runs ``vidiscover analyze REC --out DIR`` through click's
CliRunner once the CLI has an ``analyze`` command; until then it reads the recording
with :func:`vidiscover.io.read_recording`, which is where every one of these errors
is raised.
"""

import functools
import json
from pathlib import Path

import pytest
from pytest_bdd import given, parsers, scenarios, then, when

from vidiscover.io import read_recording, write_recording

scenarios("recording_errors.feature")


@functools.lru_cache(maxsize=1)
def _simulated():
    import vidiscover

    res = vidiscover.simulate(vidiscover.preset("paper", b=0.009), settle=1.0, duration=1.5)
    return vidiscover.record(res, seed=0)[0]


@pytest.fixture()
def rig(tmp_path):
    return {"dir": tmp_path}


# ----------------------------------------------------------------------------- helpers
def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines(keepends=True)


def _rewrite(path: Path, lines: list[str]) -> None:
    path.write_text("".join(lines))


def _map_column(path: Path, col: str, fn) -> None:
    lines = _lines(path)
    j = lines[0].rstrip("\n").split(",").index(col)
    out = [lines[0]]
    for ln in lines[1:]:
        cells = ln.rstrip("\n").split(",")
        cells[j] = fn(cells[j])
        out.append(",".join(cells) + "\n")
    _rewrite(path, out)


def _edit_meta(rig, **changes) -> None:
    meta = json.loads(rig["meta"].read_text())
    meta.update(changes)
    rig["meta"].write_text(json.dumps(meta))


# ----------------------------------------------------------------------------- given
@given(parsers.parse('a valid recording "{name}" with its metadata "{meta}"'))
def valid_recording(rig, name, meta):
    path = rig["dir"] / name
    write_recording(_simulated(), path)
    assert (rig["dir"] / meta).exists()
    rig.update(path=path, meta=rig["dir"] / meta)


@given(parsers.parse('a recording whose column "{col}" is missing'))
def column_missing(rig, col):
    lines = _lines(rig["path"])
    j = lines[0].rstrip("\n").split(",").index(col)
    _rewrite(rig["path"], [",".join(c for k, c in enumerate(ln.rstrip("\n").split(","))
                                    if k != j) + "\n" for ln in lines])


@given(parsers.parse('a recording whose column "{col}" is spelled "{wrong}"'))
def column_misspelled(rig, col, wrong):
    lines = _lines(rig["path"])
    lines[0] = ",".join(wrong if c == col else c
                        for c in lines[0].rstrip("\n").split(",")) + "\n"
    _rewrite(rig["path"], lines)


@given(parsers.parse('a recording whose cell in column "{col}" at row {row:d} reads "{text}"'))
def bad_cell(rig, col, row, text):
    lines = _lines(rig["path"])
    names = lines[0].rstrip("\n").split(",")
    cells = lines[row].rstrip("\n").split(",")
    cells[names.index(col)] = text
    lines[row] = ",".join(cells) + "\n"
    _rewrite(rig["path"], lines)


@given(parsers.parse('a recording whose column "{col}" has a gap of {n:d} missing values'))
def nan_gap(rig, col, n):
    lines = _lines(rig["path"])
    j = lines[0].rstrip("\n").split(",").index(col)
    for row in range(1000, 1000 + n):
        cells = lines[row].rstrip("\n").split(",")
        cells[j] = ""
        lines[row] = ",".join(cells) + "\n"
    _rewrite(rig["path"], lines)


@given("a recording whose time column is not monotonic")
def not_monotonic(rig):
    lines = _lines(rig["path"])
    lines[300], lines[301] = lines[301], lines[300]
    _rewrite(rig["path"], lines)


@given("a recording whose time column skips a sample")
def skipped_sample(rig):
    lines = _lines(rig["path"])
    _rewrite(rig["path"], lines[:500] + lines[501:])


@given(parsers.parse("a recording whose length is only {seconds:g} s"))
def too_short(rig, seconds):
    n = int(round(seconds * _simulated().sample_rate))
    _rewrite(rig["path"], _lines(rig["path"])[:n + 1])


@given(parsers.parse('a recording whose column "{col}" is in mm instead of m'))
def in_mm(rig, col):
    _map_column(rig["path"], col, lambda v: repr(float(v) * 1000.0))


@given("a recording whose acceleration is in g instead of m/s^2")
def in_g(rig):
    _map_column(rig["path"], "a", lambda v: repr(float(v) / 9.81))


@given("a recording whose metadata file is missing")
def no_metadata(rig):
    rig["meta"].unlink()


@given(parsers.parse("a recording whose metadata says {key} = {value:g}"))
def metadata_value(rig, key, value):
    _edit_meta(rig, **{key: value})


@given("a recording whose metadata is not valid JSON")
def metadata_not_json(rig):
    rig["meta"].write_text(rig["meta"].read_text().replace(",", "", 1))


@given(parsers.parse('a recording whose column "{col}" reads 0 throughout'))
def dead_channel(rig, col):
    _map_column(rig["path"], col, lambda v: "0")


@given("a recording whose columns are in mV without sensitivities")
def mv_without_sensitivities(rig):
    lines = _lines(rig["path"])
    lines[0] = "t,x_mV,a_mV,xe_mV\n"
    _rewrite(rig["path"], lines)
    meta = json.loads(rig["meta"].read_text())
    meta.pop("sensitivity", None)
    rig["meta"].write_text(json.dumps(meta))


@given("a recording whose file is empty")
def empty_file(rig):
    rig["path"].write_text("")


@given("a recording whose file is truncated in its last row")
def truncated(rig):
    text = rig["path"].read_text()
    rig["path"].write_text(text[:text.rstrip("\n").rfind("\n") + 12])


# ----------------------------------------------------------------------------- when
@when("I analyze it", target_fixture="outcome")
def analyze(rig):
    from click.testing import CliRunner

    from vidiscover.cli import main

    out = rig["dir"] / "analysis"
    before = sorted(p.name for p in rig["dir"].iterdir())
    res = CliRunner().invoke(main, ["analyze", str(rig["path"]), "--out", str(out),
                                    "--no-figures", "--json"])
    return {"status": res.exit_code, "error": res.stderr, "stdout": res.stdout, "out": out,
            "before": before, "path": rig["path"]}


# ----------------------------------------------------------------------------- then
@then("it is accepted")
def accepted(outcome):
    assert outcome["status"] == 0, outcome["error"]
    summary = json.loads((outcome["out"] / "summary.json").read_text())
    assert summary["duration"] == pytest.approx(1.5)
    assert summary["sample_rate"] == 6400.0
    assert json.loads(outcome["stdout"])["impacts"] == summary["impacts"]
    assert read_recording(outcome["path"]).n == 9600


@then(parsers.parse('I get one line that names "{file}" and says "{says}"'))
def one_line(outcome, file, says):
    assert outcome["status"] == 2
    lines = outcome["error"].splitlines()
    assert len(lines) == 1, outcome["error"]
    assert file in lines[0], lines[0]
    assert says in lines[0], lines[0]
    assert "Traceback" not in outcome["error"]


@then("no output files are written")
def no_output(outcome, rig):
    out = outcome["out"]
    assert not out.exists() or not any(out.iterdir())
    after = sorted(p.name for p in rig["dir"].iterdir() if p != out)
    assert after == outcome["before"]
