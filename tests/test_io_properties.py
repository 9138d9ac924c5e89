"""Property tests: malformed recordings and metadata always give a one-line InputError,
and an interrupted write never leaves a partial file behind.

The base recording is the smallest valid one: 200 samples at 200 Hz (exactly the 1 s
minimum) of an 8 Hz motion with a = x'', so every corruption below must be refused.
"""

import json
import math
import string
import tempfile
from contextlib import ExitStack
from pathlib import Path
from unittest import mock

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import vidiscover._atomic as vatomic
import vidiscover.io as vio
from vidiscover.effects import Effects
from vidiscover.errors import InputError
from vidiscover.io import read_recording, write_recording
from vidiscover.params import preset
from vidiscover.recording import PAPER_SENSITIVITY, Metadata, Recording
from vidiscover.truth import GroundTruth, TrueImpacts, TrueMotion

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

FS, N, F = 200.0, 200, 8.0
HEADER = ["t", "x", "a", "xe"]
KNOWN = {"t", "x", "a", "xe", "x_mV", "a_mV", "xe_mV"}
META = {"b": 0.009, "sample_rate": FS}


def _base_rows() -> list[list[str]]:
    t = np.arange(N) / FS
    x = 1e-3 * np.sin(2 * np.pi * F * t)
    a = -(2 * np.pi * F) ** 2 * x
    xe = 5e-4 * np.sin(2 * np.pi * F * t + 0.3)
    return [[f"{v:.12g}" for v in row] for row in zip(t, x, a, xe, strict=True)]


ROWS = _base_rows()


def render(header, rows, end="\n") -> str:
    return "\n".join([",".join(header)] + [",".join(r) for r in rows]) + end


BASE_TEXT = render(HEADER, ROWS)


def read_text(csv_text: str | bytes, meta_text: str | bytes | None = None):
    """Write rec.csv (+ rec.json) into a fresh directory and read it."""
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "rec.csv"
        data = csv_text.encode() if isinstance(csv_text, str) else csv_text
        path.write_bytes(data)
        meta = json.dumps(META) if meta_text is None else meta_text
        path.with_suffix(".json").write_bytes(meta.encode() if isinstance(meta, str) else meta)
        return read_recording(path)


def refused(csv_text, meta_text=None, name="rec.csv") -> str:
    with pytest.raises(InputError) as err:
        read_text(csv_text, meta_text)
    msg = str(err.value)
    assert "\n" not in msg and "\r" not in msg, msg
    assert name in msg, msg
    return msg


def test_base_recording_is_valid():
    rec = read_text(BASE_TEXT)
    assert rec.n == N and rec.sample_rate == FS and rec.duration == 1.0


def _not_a_finite_number(tok: str) -> bool:
    try:
        return not math.isfinite(float(tok))
    except ValueError:
        return True


# ============================================================================ CSV corruptions
@st.composite
def drop_column(draw):
    j = draw(st.integers(0, 3))
    return render([h for k, h in enumerate(HEADER) if k != j],
                  [[c for k, c in enumerate(r) if k != j] for r in ROWS])


@st.composite
def rename_column(draw):
    j = draw(st.integers(0, 3))
    new = draw(st.text(string.ascii_letters + string.digits + "_ ", max_size=8)
               .filter(lambda s: s.strip() not in KNOWN))
    return render([new if k == j else h for k, h in enumerate(HEADER)], ROWS)


CELL_TEXT = st.text(st.characters(blacklist_characters='"\r\n', blacklist_categories=["Cs"]),
                    min_size=1, max_size=10).filter(_not_a_finite_number)


@st.composite
def non_numeric_cells(draw):
    rows = [list(r) for r in ROWS]
    for _ in range(draw(st.integers(1, 3))):
        i, j = draw(st.integers(0, N - 1)), draw(st.integers(0, 3))
        rows[i][j] = draw(CELL_TEXT)
    return render(HEADER, rows)


@st.composite
def nan_cells(draw):
    rows = [list(r) for r in ROWS]
    for _ in range(draw(st.integers(1, 5))):
        i, j = draw(st.integers(0, N - 1)), draw(st.integers(0, 3))
        rows[i][j] = draw(st.sampled_from(["", " ", "nan", "NaN", "NA", "null", "inf", "-inf"]))
    return render(HEADER, rows)


@st.composite
def shuffled_rows(draw):
    order = draw(st.permutations(range(N)).filter(lambda p: list(p) != sorted(p)))
    return render(HEADER, [ROWS[i] for i in order])


@st.composite
def swapped_rows(draw):
    i, j = draw(st.lists(st.integers(0, N - 1), min_size=2, max_size=2, unique=True))
    rows = list(ROWS)
    rows[i], rows[j] = rows[j], rows[i]
    return render(HEADER, rows)


@st.composite
def duplicated_rows(draw):
    i = draw(st.integers(0, N - 1))
    return render(HEADER, ROWS[:i + 1] + [ROWS[i]] + ROWS[i + 1:])


@st.composite
def dropped_rows(draw):
    i = draw(st.integers(1, N - 2))          # an inner row: the step doubles there
    return render(HEADER, ROWS[:i] + ROWS[i + 1:])


LAST_ROW_START = len(BASE_TEXT.rstrip("\n")) - len(",".join(ROWS[-1]))


@st.composite
def truncated_early(draw):
    """Cut anywhere before the last row: too short, ragged or header-only, never valid."""
    return BASE_TEXT[:draw(st.integers(0, LAST_ROW_START - 1))]


CORRUPTIONS = {
    "drop a column": drop_column(), "rename a column": rename_column(),
    "non-numeric cells": non_numeric_cells(), "NaN cells": nan_cells(),
    "shuffled rows": shuffled_rows(), "swapped rows": swapped_rows(),
    "duplicated row": duplicated_rows(), "dropped row": dropped_rows(),
    "truncated": truncated_early(),
}


@pytest.mark.parametrize("kind", list(CORRUPTIONS))
def test_corrupted_csv_is_refused_with_one_line(kind):
    @SETTINGS
    @given(CORRUPTIONS[kind])
    def check(text):
        refused(text)

    check()


@SETTINGS
@given(st.integers(LAST_ROW_START, len(BASE_TEXT) - 1))
def test_cut_in_the_last_row_is_refused_or_keeps_the_rest(k):
    """A cut inside the last row either is refused or, if the row still parses as four
    numbers (a shortened last digit), changes nothing before it."""
    try:
        rec = read_text(BASE_TEXT[:k])
    except InputError as err:
        assert "\n" not in str(err) and "rec.csv" in str(err)
        return
    ref = read_text(BASE_TEXT)
    assert rec.n == N
    for col in ("t", "x", "a", "xe"):
        np.testing.assert_array_equal(getattr(rec, col)[:-1], getattr(ref, col)[:-1])


@SETTINGS
@given(st.binary(max_size=300))
def test_random_bytes_are_refused(data):
    refused(data)


# ============================================================================ metadata
JSON_SCALARS = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6),
                         st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=6))


def json_values(scalars):
    return st.recursive(scalars, lambda inner: st.one_of(
        st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=5), inner, max_size=3)),
        max_leaves=6)


JSON_VALUES = json_values(JSON_SCALARS)
#: Values that compare equal after a JSON round trip (no NaN).
PLAIN_JSON_VALUES = json_values(st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6),
                                          st.floats(allow_nan=False, allow_infinity=False),
                                          st.text(max_size=6)))


def _is_valid_b(v) -> bool:
    if isinstance(v, bool) or not isinstance(v, (int, float, str)):
        return False
    try:
        return 0 < float(v) <= 1
    except (ValueError, OverflowError):
        return False


def _json_or_none(text):
    try:
        return json.loads(text)
    except ValueError:
        return None


@SETTINGS
@given(st.text(max_size=60))
def test_json_garbage_is_refused(text):
    content = _json_or_none(text)
    assume(not (isinstance(content, dict) and _is_valid_b(content.get("b"))))
    refused(BASE_TEXT, text, name="rec.json")


@SETTINGS
@given(st.binary(min_size=1, max_size=60))
def test_binary_metadata_is_refused(data):
    try:
        content = json.loads(data.decode("utf-8-sig"))
    except ValueError:
        content = None
    assume(not (isinstance(content, dict) and _is_valid_b(content.get("b"))))
    refused(BASE_TEXT, data, name="rec.json")


@SETTINGS
@given(st.dictionaries(st.text(max_size=6).filter(lambda k: k != "b"), JSON_VALUES,
                       max_size=4))
def test_metadata_without_b_is_refused(content):
    msg = refused(BASE_TEXT, json.dumps(content), name="rec.json")
    assert "missing required key 'b'" in msg


BAD_B = st.one_of(st.floats(max_value=0.0), st.floats(min_value=1.0, exclude_min=True),
                  st.just(float("nan")), st.integers(max_value=0), st.integers(min_value=2),
                  st.none(), st.booleans(), st.lists(st.floats(), max_size=2),
                  st.text(max_size=6).filter(lambda s: not _is_valid_b(s)))


@SETTINGS
@given(BAD_B)
def test_impossible_b_is_refused(b):
    refused(BASE_TEXT, json.dumps({"b": b}), name="rec.json")


@SETTINGS
@given(st.sampled_from(["m1", "m2", "k1", "c1"]),
       st.one_of(st.floats(max_value=0.0), st.integers(max_value=0), st.just(float("-inf"))))
def test_negative_masses_and_stiffness_are_refused(key, value):
    assume(not (key == "c1" and value == 0))          # no damping is allowed
    msg = refused(BASE_TEXT, json.dumps({"b": 0.009, key: value}), name="rec.json")
    assert f"'{key}'" in msg


NESTED_KEYS = {"excitation": ["amplitude", "frequency"],
               "sensitivity": ["x_mV_per_mm", "xe_mV_per_mm", "a_mV_per_g"]}
NOT_POSITIVE = st.one_of(st.floats(max_value=0.0), st.integers(max_value=0),
                         st.sampled_from([float("nan"), float("inf"), None, True, [], {}]),
                         st.text(max_size=6).filter(_not_a_finite_number))


@SETTINGS
@given(st.sampled_from(sorted(NESTED_KEYS)), st.data())
def test_bad_nested_metadata_is_refused(key, data):
    kind = data.draw(st.sampled_from(["not an object", "unknown key", "bad value"]))
    if kind == "not an object":
        value = data.draw(st.one_of(st.booleans(), st.integers(), st.floats(),
                                    st.text(max_size=5), st.lists(JSON_SCALARS, max_size=2)))
    elif kind == "unknown key":
        value = {data.draw(st.text(max_size=12).filter(lambda k: k not in NESTED_KEYS[key])):
                 1.0}
    else:
        value = {data.draw(st.sampled_from(NESTED_KEYS[key])): data.draw(NOT_POSITIVE)}
    msg = refused(BASE_TEXT, json.dumps({"b": 0.009, key: value}), name="rec.json")
    assert key in msg


@SETTINGS
@given(st.dictionaries(st.text(min_size=1, max_size=6).filter(
    lambda k: k not in {"b", "sample_rate", "m1", "m2", "c1", "k1", "excitation",
                        "sensitivity", "units"}), PLAIN_JSON_VALUES, max_size=4))
def test_unknown_keys_are_kept(extra):
    rec = read_text(BASE_TEXT, json.dumps({**META, **extra}))
    assert dict(rec.meta.extra) == {**extra, "units": "SI"}


# ============================================================================ atomic writes
def _tiny_recording() -> Recording:
    cols = np.array(ROWS, dtype=float).T
    return Recording(*cols, meta=Metadata(**META, sensitivity=PAPER_SENSITIVITY), name="rec")


TINY = _tiny_recording()
TRUTH = GroundTruth(params=preset("paper", b=0.009), effects=Effects(), b_true=0.009,
                    settle=1.0, duration=0.5, seed=0, sensors={},
                    impacts=TrueImpacts.from_columns(t=[0.1], side=["right"],
                                                     r=[np.float64(0.88)]),
                    motion=TrueMotion(t0=0.0, dt=0.1, x=np.zeros(5), xd=np.zeros(5),
                                      y=np.zeros(5), yd=np.zeros(5)))


def _snapshot(d: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


@SETTINGS
@given(fmt=st.sampled_from([".csv", ".parquet", ".npz"]), units=st.sampled_from(["SI", "mV"]),
       with_truth=st.booleans(), existing=st.booleans(),
       fail=st.one_of(st.tuples(st.just("data"), st.just(0)),
                      st.tuples(st.just("json"), st.integers(0, 1)),
                      st.tuples(st.just("replace"), st.integers(0, 6))))
def test_interrupted_write_leaves_no_partial_file(fmt, units, with_truth, existing, fail):
    where, k = fail
    calls = {"data": 0, "json": 0, "replace": 0}
    real = {"data": vio._write_data, "json": vio.dump_json, "replace": vatomic._replace}

    def failing(kind):
        def wrapper(*args):
            n = calls[kind]
            calls[kind] += 1
            if kind == where and n == k:
                if kind != "replace":             # half-written temp file, then the error
                    Path(args[1] if kind == "data" else args[0]).write_bytes(b"partial")
                raise OSError(28, "No space left on device")
            return real[kind](*args)
        return wrapper

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / f"rec{fmt}"
        if existing:
            write_recording(TINY, path, truth=TRUTH.with_regime({"label": "old"}), units="SI")
        before = _snapshot(Path(d))
        with ExitStack() as stack:
            stack.enter_context(mock.patch.object(vio, "_write_data", failing("data")))
            stack.enter_context(mock.patch.object(vio, "dump_json", failing("json")))
            stack.enter_context(mock.patch.object(vatomic, "_replace", failing("replace")))
            try:
                files = write_recording(TINY, path, truth=TRUTH if with_truth else None,
                                        units=units)
            except OSError as err:
                assert err.errno == 28
                assert _snapshot(Path(d)) == before       # nothing new, nothing lost
                return
        # the injected failure was not reached: the write must be complete
        assert calls[where] <= k
        assert sorted(p.name for p in Path(d).iterdir()) == sorted(f.name for f in files)
        back = read_recording(path)
        np.testing.assert_allclose(back.x, TINY.x, rtol=1e-9)
