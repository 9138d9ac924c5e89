"""Recording files: round trips, metadata, and one-line errors for every bad input.

Tolerances of the round trips: CSV keeps 12 significant digits for SI columns
(relative error <= 5e-12 per value, tested at 1e-11) and 10 for mV columns (tested at
1e-9 after converting back to SI); Parquet and NPZ keep float64 exactly (SI) or to a
few ulps of the mV conversion (tested at 1e-14).
"""

import json
from pathlib import Path

import numpy as np
import pytest

import vidiscover
from vidiscover import io as vio
from vidiscover.errors import InputError
from vidiscover.io import (
    atomic_directory,
    check_output_dir,
    read_metadata,
    read_recording,
    read_truth,
    to_jsonable,
    write_json,
    write_recording,
)
from vidiscover.recording import PAPER_SENSITIVITY, Metadata

RTOL = {(".csv", "SI"): 1e-11, (".csv", "mV"): 1e-9, (".parquet", "SI"): 0.0,
        (".parquet", "mV"): 1e-14, (".npz", "SI"): 0.0, (".npz", "mV"): 1e-14}


@pytest.fixture(scope="module")
def simulated():
    """A short simulated recording (1.5 s at 6400 Hz), in SI and mV, with its truth."""
    res = vidiscover.simulate(vidiscover.preset("paper", b=0.009), settle=1.0, duration=1.5)
    rec, truth = vidiscover.record(res, seed=0)
    rec_mv, _ = vidiscover.record(res, seed=0, units="mV")
    return rec, rec_mv, truth


@pytest.fixture()
def rec_csv(tmp_path, simulated):
    path = tmp_path / "rec.csv"
    write_recording(simulated[0], path)
    return path


def file_columns(path: Path) -> list[str]:
    if path.suffix == ".csv":
        return path.read_text().splitlines()[0].split(",")
    if path.suffix == ".parquet":
        import pyarrow.parquet as pq

        return pq.read_schema(path).names
    with np.load(path) as z:
        return list(z.files)


def assert_single_line_error(err: pytest.ExceptionInfo, name: str) -> None:
    msg = str(err.value)
    assert "\n" not in msg and "\r" not in msg, msg
    assert name in msg, msg


# ============================================================================ round trips
@pytest.mark.parametrize("units", ["SI", "mV"])
@pytest.mark.parametrize("suffix", [".csv", ".parquet", ".npz"])
def test_round_trip(tmp_path, simulated, suffix, units):
    rec = simulated[0] if units == "SI" else simulated[1]
    path = tmp_path / f"rec{suffix}"
    files = write_recording(rec, path)
    assert files == [path, tmp_path / "rec.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in files)
    expected = ["t", "x", "a", "xe"] if units == "SI" else ["t", "x_mV", "a_mV", "xe_mV"]
    assert file_columns(path) == expected
    back = read_recording(path)
    rtol = RTOL[suffix, units]
    for col in ("t", "x", "a", "xe"):
        np.testing.assert_allclose(getattr(back, col), getattr(rec, col), rtol=rtol, atol=0,
                                   err_msg=col)
    assert back.meta.to_dict() == rec.meta.to_dict()
    assert back.meta.extra["units"] == units
    assert back.name == "rec"
    assert back.meta.source == str(tmp_path / "rec.json")


def test_units_override_writes_voltages(tmp_path, simulated):
    rec = simulated[0]
    path = tmp_path / "rec.csv"
    write_recording(rec, path, units="mV")
    assert file_columns(path) == ["t", "x_mV", "a_mV", "xe_mV"]
    assert json.loads((tmp_path / "rec.json").read_text())["units"] == "mV"
    back = read_recording(path)
    np.testing.assert_allclose(back.a, rec.a, rtol=1e-9, atol=0)
    np.testing.assert_allclose(back.x, rec.x, rtol=1e-9, atol=0)
    # the voltages are the paper's sensitivities applied to the SI values
    first = [float(v) for v in path.read_text().splitlines()[1].split(",")]
    assert first[1] == pytest.approx(rec.x[0] * 1e3 * PAPER_SENSITIVITY["x_mV_per_mm"],
                                     rel=1e-9)
    assert first[2] == pytest.approx(rec.a[0] / 9.81 * PAPER_SENSITIVITY["a_mV_per_g"],
                                     rel=1e-9)


def test_truth_round_trip(tmp_path, simulated):
    rec, _, truth = simulated
    path = tmp_path / "rec.parquet"
    files = write_recording(rec, path, truth=truth)
    assert files[-1] == tmp_path / "rec.truth.json"
    assert json.loads((tmp_path / "rec.truth.json").read_text()) == json.loads(
        json.dumps(to_jsonable(truth.to_dict())))
    assert read_truth(path) == truth
    assert read_truth(tmp_path / "rec.truth.json") == truth
    assert read_truth(path).impacts.t[0] == truth.impacts.t[0]


def test_truth_file_without_the_contact_keys_still_reads(tmp_path, simulated):
    """Files written before ``contact``, ``t_in``, ``t_out``, ``v_in``, ``v_out``."""
    _, _, truth = simulated
    old = truth.to_dict()
    del old["contact"]
    for imp in old["impacts"]:
        for key in ("t_in", "t_out", "v_in", "v_out"):
            del imp[key]
    path = tmp_path / "old.truth.json"
    path.write_text(json.dumps(old))
    back = read_truth(path)
    assert back == truth and back.contact is None
    np.testing.assert_array_equal(back.impacts.t_out, back.impacts.t)
    np.testing.assert_array_equal(back.impacts.v_in, back.impacts.u_minus)


@pytest.mark.parametrize("content, words", [
    ('[1, 2]', "must be a JSON object"),
    ('{"impacts": []}', "lacks params"),
])
def test_malformed_truth_is_one_line(tmp_path, simulated, content, words):
    path = tmp_path / "rec.truth.json"
    path.write_text(content)
    with pytest.raises(InputError, match=words) as err:
        read_truth(path)
    assert_single_line_error(err, "rec.truth.json")


def test_truth_impact_missing_a_key_is_one_line(tmp_path, simulated):
    _, _, truth = simulated
    bad = truth.to_dict()
    del bad["impacts"][2]["r"]
    path = tmp_path / "rec.truth.json"
    path.write_text(json.dumps(bad))
    with pytest.raises(InputError, match="impact 2 lacks r") as err:
        read_truth(path)
    assert_single_line_error(err, "rec.truth.json")


def test_stale_truth_is_removed_when_rewriting_without_truth(tmp_path, simulated):
    rec, _, truth = simulated
    path = tmp_path / "rec.csv"
    write_recording(rec, path, truth=truth)
    write_recording(rec, path)
    assert not (tmp_path / "rec.truth.json").exists()
    with pytest.raises(InputError, match="only simulated recordings") as err:
        read_truth(path)
    assert_single_line_error(err, "rec.truth.json")


def test_csv_dialects_are_read(tmp_path, rec_csv):
    """Semicolons, CRLF line ends, a BOM, blank lines and extra columns are fine."""
    lines = rec_csv.read_text().splitlines()
    rows = [lines[0] + ",temp"] + [ln + ",21.5" for ln in lines[1:]]
    text = "\ufeff" + "\r\n".join(rows).replace(",", ";")
    other = tmp_path / "semi.csv"
    other.write_text(text + "\r\n\r\n", encoding="utf-8")
    (tmp_path / "semi.json").write_text('{"b": 0.009}')
    ref = read_recording(rec_csv)
    back = read_recording(other)
    np.testing.assert_array_equal(back.x, ref.x)
    np.testing.assert_array_equal(back.t, ref.t)


# ============================================================================ metadata
def test_metadata_defaults_and_extra_keys(rec_csv):
    rec_csv.with_suffix(".json").write_text('{"b": 0.009, "operator": "ana", "rig": 2}')
    rec = read_recording(rec_csv)
    m = rec.meta
    assert (m.b, m.m1, m.m2, m.c1, m.k1) == (0.009, 4.168, 0.032, 3.02, 11470.0)
    assert m.excitation == {"amplitude": 0.0005, "frequency": 8.0}
    assert m.sensitivity == {}          # none given: never assumed
    assert m.sample_rate == pytest.approx(6400.0, rel=1e-9)   # from t
    assert m.extra == {"operator": "ana", "rig": 2, "units": "SI"}


@pytest.mark.parametrize("kind", ["path", "dict", "Metadata"])
def test_metadata_given_explicitly(tmp_path, rec_csv, kind):
    rec_csv.with_suffix(".json").unlink()
    content = {"b": 0.0075, "m2": 0.05}
    if kind == "path":
        meta = tmp_path / "other-meta.json"
        meta.write_text(json.dumps(content))
    elif kind == "dict":
        meta = content
    else:
        meta = Metadata(**content)
    rec = read_recording(rec_csv, meta=meta)
    assert (rec.meta.b, rec.meta.m2) == (0.0075, 0.05)


@pytest.mark.parametrize("rate, ok", [(6400.0, True), (6404.0, True), (6395.0, True),
                                      (6410.0, False), (3200.0, False)])
def test_sample_rate_must_agree_with_time(rec_csv, rate, ok):
    rec_csv.with_suffix(".json").write_text(json.dumps({"b": 0.009, "sample_rate": rate}))
    if ok:
        assert read_recording(rec_csv).sample_rate == rate
        return
    with pytest.raises(InputError, match=rf"sample_rate = {rate:g} Hz disagrees with the time "
                                         r"column of rec\.csv \(6400 Hz") as err:
        read_recording(rec_csv)
    assert_single_line_error(err, "rec.json")


def test_metadata_source_names_the_json_file(tmp_path):
    path = tmp_path / "m.json"
    path.write_text('{"b": 0.009, "m1": -4}')
    with pytest.raises(InputError, match=r"m\.json: 'm1' must be > 0 \(kg\), was -4"):
        read_metadata(path)


# ============================================================================ bad inputs
def lines_of(path):
    return path.read_text().splitlines(keepends=True)


def rewrite(path, lines):
    path.write_text("".join(lines))


def with_cell(path, row, col, value):
    """Set data row ``row`` (1-based), column index ``col`` to ``value``."""
    lines = lines_of(path)
    cells = lines[row].rstrip("\n").split(",")
    cells[col] = value
    lines[row] = ",".join(cells) + "\n"
    rewrite(path, lines)


def scale_column(path, col, factor):
    lines = lines_of(path)
    out = [lines[0]]
    for ln in lines[1:]:
        cells = ln.rstrip("\n").split(",")
        cells[col] = repr(float(cells[col]) * factor)
        out.append(",".join(cells) + "\n")
    rewrite(path, out)


def write_meta(path, content):
    path.with_suffix(".json").write_text(content if isinstance(content, str)
                                         else json.dumps(content))


def c_empty(p):
    p.write_text("")


def c_blank(p):
    p.write_text("\n  \n")


def c_header_only(p):
    rewrite(p, lines_of(p)[:1])


def c_truncated_mid_row(p):
    text = p.read_text()
    start = text.rstrip("\n").rfind("\n") + 1
    p.write_text(text[:start + 6])


def c_truncated_number(p):
    lines = lines_of(p)
    cells = lines[-1].rstrip("\n").split(",")
    lines[-1] = ",".join(cells[:3] + ["-1.2"])          # xe cut from -1.2...e-05, no newline
    rewrite(p, lines)


def c_missing_cells(p):
    lines = lines_of(p)
    lines[100] = ",".join(lines[100].split(",")[:3]) + "\n"
    rewrite(p, lines)


def c_extra_cells(p):
    lines = lines_of(p)
    lines[100] = lines[100].rstrip("\n") + ",7\n"
    rewrite(p, lines)


def c_drop_xe(p):
    rewrite(p, [",".join(ln.rstrip("\n").split(",")[:3]) + "\n" for ln in lines_of(p)])


def header(new):
    def corrupt(p):
        lines = lines_of(p)
        lines[0] = new + "\n"
        rewrite(p, lines)
    return corrupt


def c_non_numeric(p):
    with_cell(p, 100, 1, "abc")


def c_nan_gap(p):
    for row in range(200, 205):
        with_cell(p, row, 2, "")


def c_nan_literal(p):
    with_cell(p, 50, 1, "NaN")


def c_inf(p):
    with_cell(p, 10, 2, "inf")


def c_swap_rows(p):
    lines = lines_of(p)
    lines[300], lines[301] = lines[301], lines[300]
    rewrite(p, lines)


def c_duplicate_row(p):
    lines = lines_of(p)
    rewrite(p, lines[:400] + [lines[399]] + lines[400:])


def c_skip_row(p):
    lines = lines_of(p)
    rewrite(p, lines[:500] + lines[501:])


def c_short(p):
    rewrite(p, lines_of(p)[:3201])


def c_x_mm(p):
    scale_column(p, 1, 1000.0)


def c_xe_mm(p):
    scale_column(p, 3, 1000.0)


def c_a_in_g(p):
    scale_column(p, 2, 1 / 9.81)


def c_t_in_ms(p):
    scale_column(p, 0, 1000.0)
    write_meta(p, {"b": 0.009})


def c_no_meta(p):
    p.with_suffix(".json").unlink()


def c_not_utf8(p):
    p.write_bytes(b"t,x,a,xe\n\xff\xfe,1,2,3\n")


def meta(content):
    return lambda p: write_meta(p, content)


BAD_INPUTS = {
    # id: (corruption, phrase the message must match, file it must name)
    "empty file": (c_empty, r"rec\.csv: empty file", "rec.csv"),
    "blank file": (c_blank, r"empty file", "rec.csv"),
    "header only": (c_header_only, r"no data rows \(empty or truncated file\)", "rec.csv"),
    "truncated mid row": (c_truncated_mid_row,
                          r"truncated file: the last row, row 9600 \(line 9601\), has 1 of "
                          r"4 cells", "rec.csv"),
    "truncated number": (c_truncated_number,
                         r"truncated file: the last row, row 9600 \(line 9601\), is "
                         r"incomplete \('xe' jumps to -1\.2 m\)", "rec.csv"),
    "missing cells": (c_missing_cells, r"row 100 \(line 101\) has 3 cells but the header has 4 "
                                       r"columns \(missing cells\)", "rec.csv"),
    "extra cells": (c_extra_cells, r"row 100 \(line 101\) has 5 cells .*\(extra cells\)",
                    "rec.csv"),
    "missing column": (c_drop_xe, r"missing column 'xe' \(base displacement in m, or 'xe_mV' "
                                  r"in mV\); the header has 't', 'x', 'a'", "rec.csv"),
    "misspelled column": (header("t,x,a,xee"), r"missing column 'xe' .*found 'xee': did you "
                                               r"mean 'xe'\?", "rec.csv"),
    "misspelled time": (header("tme,x,a,xe"), r"missing column 't' .*did you mean 't'\?",
                        "rec.csv"),
    "time alias": (header("Time,x,a,xe"), r"found 'Time': did you mean 't'\?", "rec.csv"),
    "case of mV": (header("t,x_mv,a,xe"), r"found 'x_mv': did you mean 'x_mV'\?", "rec.csv"),
    "both SI and mV": (header("t,x,a,x_mV"), r"has both 'x' and 'x_mV'", "rec.csv"),
    "duplicate column": (header("t,x,a,x"), r"column 'x' appears twice", "rec.csv"),
    "no header": (header("0,0.001,0.5,0"), r"the first line holds numbers, not column names",
                  "rec.csv"),
    "non-numeric cell": (c_non_numeric, r"non-numeric cell 'abc' in column 'x' at row 100 "
                                        r"\(line 101\)", "rec.csv"),
    "NaN gap": (c_nan_gap, r"column 'a' has 5 missing value\(s\) \(NaN or empty\) in 1 "
                           r"gap\(s\), the first at rows 200-204 \(lines 201-205\)", "rec.csv"),
    "NaN literal": (c_nan_literal, r"column 'x' has 1 missing value\(s\) .*row 50 \(line 51\)",
                    "rec.csv"),
    "infinite value": (c_inf, r"infinite value in column 'a' at row 10 \(line 11\)", "rec.csv"),
    "non-monotonic time": (c_swap_rows, r"time is not strictly increasing \(non-monotonic\) at "
                                        r"row 301 \(line 302\)", "rec.csv"),
    "duplicated row": (c_duplicate_row, r"non-monotonic\) at row 400 \(line 401\): t = (\S+) s "
                                                 r"after \1 s", "rec.csv"),
    "non-uniform time": (c_skip_row, r"non-uniform time step at row 500 \(line 501\)",
                         "rec.csv"),
    "too short": (c_short, r"record too short: 0\.5 s \(3200 samples\); the rule is at least "
                           r"1 s and 2 forcing periods", "rec.csv"),
    "too few periods": (meta({"b": 0.009, "excitation": {"frequency": 1.0}}),
                        r"too short: 1\.5 s .* 2 forcing periods \(2 s at 1 Hz\)", "rec.csv"),
    "mm in x": (c_x_mm, r"column 'x' reaches .* more than 0\.1 m: it looks like mm, not m",
                "rec.csv"),
    "mm in xe": (c_xe_mm, r"column 'xe' reaches .* it looks like mm", "rec.csv"),
    "a in g": (c_a_in_g, r"column 'a' is 0\.1\d* times what the displacement implies .*looks "
                         r"like g, not m/s\^2", "rec.csv"),
    "t in ms": (c_t_in_ms, r"fewer than 20 samples per forcing period .* is 't' in ms\?",
                "rec.csv"),
    "not UTF-8": (c_not_utf8, r"not UTF-8 text", "rec.csv"),
    "missing metadata": (c_no_meta, r"rec\.csv: missing metadata: .*rec\.json not found; "
                                    r'create rec\.json with \{"b": 0\.009\} .*or pass --meta',
                         "rec.csv"),
    "malformed JSON": (meta('{"b": 0.009,'), r"rec\.json: malformed JSON at line 1", "rec.json"),
    "empty JSON": (meta(""), r"empty JSON file", "rec.json"),
    "JSON not an object": (meta("[0.009]"), r"must be a JSON object .*found list", "rec.json"),
    "b missing": (meta({"m1": 4.0}), r"missing required key 'b' \(half-clearance in m\)",
                  "rec.json"),
    "b capitalised": (meta({"B": 0.009}), r"missing required key 'b' .*found 'B'", "rec.json"),
    "b zero": (meta({"b": 0}), r"'b' must be > 0", "rec.json"),
    "b negative": (meta({"b": -0.009}), r"'b' must be > 0", "rec.json"),
    "b in mm": (meta({"b": 9}), r"implausibly large; b is in metres", "rec.json"),
    "b not a number": (meta({"b": "nine"}), r"'b' must be a number", "rec.json"),
    "b boolean": (meta({"b": True}), r"'b' must be a number", "rec.json"),
    "negative mass": (meta({"b": 0.009, "m2": -0.032}), r"'m2' must be > 0", "rec.json"),
    "negative damping": (meta({"b": 0.009, "c1": -1}), r"'c1' must be >= 0", "rec.json"),
    "excitation not an object": (meta({"b": 0.009, "excitation": 8}),
                                 r"'excitation' must be an object", "rec.json"),
    "unknown sensitivity": (meta({"b": 0.009, "sensitivity": {"x_mv_per_mm": 1}}),
                            r"unknown sensitivity key", "rec.json"),
    "huge integer": (meta('{"b": 0.009, "m1": 1' + "0" * 400 + "}"), r"rec\.json", "rec.json"),
}


@pytest.mark.parametrize("case", list(BAD_INPUTS))
def test_bad_input_is_one_line_naming_the_file(rec_csv, case):
    corrupt, phrase, name = BAD_INPUTS[case]
    corrupt(rec_csv)
    with pytest.raises(InputError, match=phrase) as err:
        read_recording(rec_csv)
    assert_single_line_error(err, name)


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match=r"nope\.csv: no such recording file; check the path"):
        read_recording(tmp_path / "nope.csv")


def test_directory_instead_of_file(tmp_path):
    (tmp_path / "d.csv").mkdir()
    with pytest.raises(InputError, match=r"d\.csv: is a directory"):
        read_recording(tmp_path / "d.csv")
    # a directory without a suffix is named as a directory, not as an unknown format
    (tmp_path / "runs").mkdir()
    with pytest.raises(InputError, match=r"runs: is a directory, not a recording file"):
        read_recording(tmp_path / "runs")


def test_unknown_format(tmp_path):
    (tmp_path / "rec.txt").write_text("t,x,a,xe\n")
    with pytest.raises(InputError, match=r"rec\.txt: unknown recording format '\.txt'; use "
                                         r"one of \.csv, \.parquet, \.npz"):
        read_recording(tmp_path / "rec.txt")


def test_missing_meta_path(rec_csv, tmp_path):
    with pytest.raises(InputError, match=r"nope\.json: no such metadata file; check the "
                                         r"--meta path"):
        read_recording(rec_csv, meta=tmp_path / "nope.json")


def test_bad_metadata_dict_names_the_recording(rec_csv):
    with pytest.raises(InputError, match=r"metadata of .*rec\.csv: 'b' must be > 0"):
        read_recording(rec_csv, meta={"b": -1})


@pytest.mark.parametrize("suffix", [".parquet", ".npz"])
def test_truncated_binary_file(tmp_path, simulated, suffix):
    path = tmp_path / f"rec{suffix}"
    write_recording(simulated[0], path)
    data = path.read_bytes()
    path.write_bytes(data[:len(data) // 2])
    kind = "Parquet" if suffix == ".parquet" else "NPZ"
    with pytest.raises(InputError, match=rf"not a readable {kind} file, truncated or "
                                         r"corrupted") as err:
        read_recording(path)
    assert_single_line_error(err, f"rec{suffix}")
    # the reader's own message is quoted in whole sentences, never cut mid-sentence
    # (it was "... Either the file is corrupted or); copy/export it again")
    quoted = str(err.value).partition("(")[2].rpartition(")")[0]
    assert quoted.endswith((".", "...")) or ". " not in quoted, quoted


def test_reader_messages_are_quoted_in_whole_sentences():
    from vidiscover.io import _first_sentences

    msg = ("Could not open Parquet input source '<Buffer>': Parquet magic bytes not found "
           "in footer. Either the file is corrupted or this is not a parquet file. " * 2)
    short = _first_sentences(msg)
    assert len(short) <= 160 and short.endswith("not a parquet file.")
    assert _first_sentences("x" * 300).endswith("...")
    assert _first_sentences("one line\nsecond line") == "one line"


def test_npz_columns_of_different_lengths(tmp_path, simulated):
    rec = simulated[0]
    path = tmp_path / "rec.npz"
    np.savez(path, t=rec.t, x=rec.x, a=rec.a[:-1], xe=rec.xe)
    write_meta(path, {"b": 0.009})
    with pytest.raises(InputError, match=r"columns have different lengths \(t: 9600, x: 9600, "
                                         r"a: 9599, xe: 9600\); the file looks truncated"):
        read_recording(path)


def test_npz_text_column_names_the_row(tmp_path, simulated):
    rec = simulated[0]
    path = tmp_path / "rec.npz"
    x = rec.x.astype(str)
    x[2] = "abc"
    np.savez(path, t=rec.t, x=x, a=rec.a, xe=rec.xe)
    write_meta(path, {"b": 0.009})
    with pytest.raises(InputError, match=r"non-numeric cell 'abc' in column 'x' at row 3;"):
        read_recording(path)


def test_npz_single_array(tmp_path):
    path = tmp_path / "rec.npz"
    with open(path, "wb") as fh:
        np.save(fh, np.zeros((10, 4)))
    write_meta(path, {"b": 0.009})
    with pytest.raises(InputError, match=r"holds a single array, not named columns"):
        read_recording(path)


def test_parquet_gap_names_rows(tmp_path, simulated):
    rec = simulated[0]
    a = rec.a.copy()
    a[9:12] = np.nan
    bad = vidiscover.Recording(rec.t, rec.x, a, rec.xe, rec.meta)
    path = tmp_path / "rec.parquet"
    write_recording(bad, path)
    with pytest.raises(InputError, match=r"column 'a' has 3 missing value\(s\) .*the first at "
                                         r"rows 10-12; fill"):
        read_recording(path)


@pytest.mark.parametrize("key, value, phrase", [
    ("x_mV_per_mm", 10.0, r"column 'x_mV' converts to .* with x_mV_per_mm = 10; fix "
                          r"x_mV_per_mm in .*rec\.json"),
    ("a_mV_per_g", 5.034, r"column 'a_mV' is 10\.\d times what the displacement implies .*check "
                          r"a_mV_per_g in .*rec\.json"),
])
def test_wrong_sensitivity_in_mv_file(tmp_path, simulated, key, value, phrase):
    path = tmp_path / "rec.csv"
    write_recording(simulated[1], path)
    meta = json.loads(path.with_suffix(".json").read_text())
    meta["sensitivity"][key] = value
    write_meta(path, meta)
    with pytest.raises(InputError, match=phrase) as err:
        read_recording(path)
    assert_single_line_error(err, "rec.csv")


# ============================================================================ writing
def test_write_refuses_bad_arguments(tmp_path, simulated):
    rec = simulated[0]
    with pytest.raises(InputError, match=r"rec\.xlsx: unknown recording format"):
        write_recording(rec, tmp_path / "rec.xlsx")
    with pytest.raises(InputError, match=r"units must be 'SI' or 'mV', was 'V'"):
        write_recording(rec, tmp_path / "rec.csv", units="V")
    with pytest.raises(InputError, match=r"directory '.*nowhere' does not exist"):
        write_recording(rec, tmp_path / "nowhere" / "rec.csv")
    assert list(tmp_path.iterdir()) == []


def test_failed_write_keeps_the_previous_files(tmp_path, simulated, monkeypatch):
    rec, _, truth = simulated
    path = tmp_path / "rec.csv"
    write_recording(rec, path, truth=truth)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def broken(tmp, obj, indent):
        tmp.write_text('{"b": 0.0')
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(vio, "dump_json", broken)
    with pytest.raises(OSError, match="No space left"):
        write_recording(rec, path, units="mV")
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_write_json_converts_numpy_and_nan(tmp_path):
    path = write_json(tmp_path / "summary.json",
                      {"n": np.int64(3), "t": np.arange(3) / 2, "rms": np.float64("nan"),
                       "file": tmp_path / "rec.csv", "sides": ("right", "left")})
    assert json.loads(path.read_text()) == {"n": 3, "t": [0.0, 0.5, 1.0], "rms": None,
                                            "file": str(tmp_path / "rec.csv"),
                                            "sides": ["right", "left"]}
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]


def test_write_json_failure_leaves_old_file(tmp_path):
    path = write_json(tmp_path / "summary.json", {"ok": True})
    with pytest.raises(TypeError, match="not JSON serialisable: object"):
        write_json(path, {"bad": object()})
    assert json.loads(path.read_text()) == {"ok": True}
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]


def test_atomic_directory_creates_then_replaces_the_whole_folder(tmp_path):
    out = tmp_path / "a" / "out"
    with atomic_directory(out) as tmp:
        assert tmp.parent == out.parent and tmp != out
        (tmp / "summary.json").write_text("{}")
        (tmp / "figs").mkdir()
        (tmp / "figs" / "f.png").write_bytes(b"png")
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == [
        ".vidiscover", "figs", "figs/f.png", "summary.json"]
    with atomic_directory(out) as tmp:
        (tmp / "summary.json").write_text('{"v": 2}')
    # the second run replaces the first as a whole: its figures do not survive
    assert sorted(p.name for p in out.iterdir()) == [".vidiscover", "summary.json"]
    assert (out / "summary.json").read_text() == '{"v": 2}'
    assert sorted(p.name for p in out.parent.iterdir()) == ["out"]


def test_atomic_directory_failure_leaves_nothing(tmp_path):
    out = tmp_path / "a" / "b" / "out"
    with pytest.raises(RuntimeError, match="boom"):
        with atomic_directory(out) as tmp:
            (tmp / "half.json").write_text("{")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []


def test_atomic_directory_failure_or_interrupt_keeps_the_earlier_output(tmp_path):
    out = tmp_path / "out"
    with atomic_directory(out) as tmp:
        (tmp / "old.json").write_text("old")
    for exc in (InputError("bad"), KeyboardInterrupt()):
        with pytest.raises(type(exc)):
            with atomic_directory(out) as tmp:
                (tmp / "old.json").write_text("new")
                raise exc
        assert [p.name for p in tmp_path.iterdir()] == ["out"]
        assert (out / "old.json").read_text() == "old"


def test_atomic_directory_refuses_a_folder_it_did_not_write(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "thesis.tex").write_text("precious")
    with pytest.raises(InputError, match="holds files that vidiscover did not write"):
        with atomic_directory(out):
            pass
    assert [p.name for p in out.iterdir()] == ["thesis.tex"]
    (tmp_path / "empty").mkdir()
    with atomic_directory(tmp_path / "empty") as tmp:   # an empty folder is fine
        (tmp / "x.json").write_text("{}")
    assert (tmp_path / "empty" / "x.json").exists()


def test_unwritable_output_is_refused_before_any_work(tmp_path, monkeypatch):
    import errno
    import tempfile

    def read_only_fs(*args, **kwargs):
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(tempfile, "mkstemp", read_only_fs)
    with pytest.raises(InputError, match=r"cannot write in .* \(Read-only file system\); "
                                         "choose a writable --out"):
        check_output_dir(tmp_path / "out")
    assert list(tmp_path.iterdir()) == []


def test_atomic_directory_refuses_a_file(tmp_path):
    (tmp_path / "out").write_text("x")
    with pytest.raises(InputError, match=r"out: exists and is not a directory"):
        with atomic_directory(tmp_path / "out"):
            pass


def test_to_jsonable_returns_plain_python_types():
    out = to_jsonable({"f": np.float64(0.5), "i": np.int64(2), "b": np.bool_(True),
                       "inf": np.float32("inf"), "nested": [np.arange(2.0)]})
    assert out == {"f": 0.5, "i": 2, "b": True, "inf": None, "nested": [[0.0, 1.0]]}
    assert [type(out[k]) for k in ("f", "i", "b")] == [float, int, bool]
    with pytest.raises(TypeError, match="not JSON serialisable: object"):
        to_jsonable(object())


# ----------------------------------------------------------------- gzipped CSV (read only)
def test_gzipped_csv_reads_like_the_csv(tmp_path, rec_csv, simulated):
    """``rec.csv.gz`` (how the independent simulator's recordings ship) reads as the CSV
    it holds, with the sidecars of the stem ``rec``: ``rec.json`` and ``rec.truth.json``."""
    import gzip
    import shutil

    gz = tmp_path / "gz" / "rec.csv.gz"
    gz.parent.mkdir()
    gz.write_bytes(gzip.compress(rec_csv.read_bytes()))
    shutil.copy(rec_csv.with_suffix(".json"), gz.parent / "rec.json")
    plain, packed = read_recording(rec_csv), read_recording(gz)
    assert packed.name == "rec"
    for f in ("t", "x", "a", "xe"):
        np.testing.assert_array_equal(getattr(packed, f), getattr(plain, f))
    assert vio.truth_path(gz).name == "rec.truth.json"


def test_gzipped_csv_errors_name_the_file(tmp_path, rec_csv):
    import gzip
    import shutil

    shutil.copy(rec_csv.with_suffix(".json"), tmp_path / "bad.json")
    (tmp_path / "bad.csv.gz").write_bytes(b"not gzip at all")
    with pytest.raises(InputError, match=r"bad\.csv\.gz: not a readable gzip file, truncated "
                                         r"or corrupted \(.*\); copy/export it again"):
        read_recording(tmp_path / "bad.csv.gz")
    # a row problem inside the archive is diagnosed from the decompressed text
    text = rec_csv.read_text().splitlines()
    text[5] = text[5].replace(",", ",oops", 1)
    shutil.copy(rec_csv.with_suffix(".json"), tmp_path / "row.json")
    (tmp_path / "row.csv.gz").write_bytes(gzip.compress("\n".join(text).encode() + b"\n"))
    with pytest.raises(InputError, match=r"row\.csv\.gz: .*line 6"):
        read_recording(tmp_path / "row.csv.gz")
    (tmp_path / "rec.txt.gz").write_bytes(gzip.compress(b"t,x,a,xe\n"))
    with pytest.raises(InputError, match=r"rec\.txt\.gz: unknown recording format "
                                         r"'\.txt\.gz'; use one of .*, \.csv\.gz"):
        read_recording(tmp_path / "rec.txt.gz")
