"""Files <-> values: recordings, their metadata and ground truth on disk.

A recording file (CSV, Parquet or NPZ) holds the columns ``t, x, a, xe`` in SI units,
or raw sensor voltages ``x_mV, a_mV, xe_mV``; its metadata live in a sidecar JSON with
the same stem (``rec.csv`` + ``rec.json``) and a simulated recording's ground truth in
``rec.truth.json`` (the README's 'Recording format').

Reading checks everything a rig, a logger or a spreadsheet can get wrong and raises
:class:`~vidiscover.errors.InputError` with one line naming the file, the problem and
the fix (the rules: :mod:`vidiscover._io_checks`). Writing is atomic: a recording and
its sidecars appear together or not at all, and :func:`atomic_directory` does the same
for a stage's output directory.
"""

from __future__ import annotations

import csv
import io as _stdio
import json
import os
import re
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from . import _io_checks as checks
from ._atomic import (
    atomic_directory,
    check_output_dir,
    dump_json,
    to_jsonable,
    write_group,
    write_json,
)
from .errors import InputError
from .params import G_ACCEL
from .recording import Metadata, Recording
from .truth import GroundTruth

__all__ = ["FORMATS", "read_recording", "read_metadata", "read_truth", "truth_path",
           "write_recording", "write_json", "to_jsonable", "atomic_directory", "check_output_dir"]

#: Recording file formats, by suffix (the last three read only, by :mod:`.io_lab`).
FORMATS = (".csv", ".parquet", ".npz", ".tdms", ".uff", ".unv")
#: Formats of the lab software (TDMS, UFF 58): read with the optional extra ``formats``.
LAB_FORMATS = (".tdms", ".uff", ".unv")
_META_KEYS = ("b", "sample_rate", "m1", "m2", "c1", "k1", "excitation", "sensitivity")


# =============================================================================== reading
def _format_of(path: Path, compressed: bool = False) -> str:
    """The format of ``path`` by its suffix; ``compressed`` admits a gzipped CSV."""
    fmt = path.suffix.lower()
    if compressed and fmt == ".gz" and Path(path.stem).suffix.lower() == ".csv":
        return ".csv.gz"
    if fmt not in FORMATS:
        shown = "".join(path.suffixes[-2:]) if fmt == ".gz" else path.suffix
        also = ", .csv.gz" if compressed else ""
        raise InputError(f"{path}: unknown recording format '{shown}'; use one of "
                         f"{', '.join(FORMATS)}{also}")
    return fmt


def _gunzip(path: Path, data: bytes) -> bytes:
    import gzip
    import zlib

    try:
        return gzip.decompress(data)
    except (OSError, EOFError, zlib.error) as err:
        raise _corrupt(path, "gzip", err) from None


def _read_bytes(path: Path, what: str, fix: str) -> bytes:
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{path}: no such {what}; {fix}") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, not a {what}; give the file") from None
    except OSError as err:
        raise InputError(f"{path}: cannot read the {what} ({err.strerror or err}); check "
                         "its permissions") from None


def _blank(data: bytes) -> bool:
    """Whether ``data`` holds nothing but whitespace and a BOM (scanned, not copied)."""
    return re.search(rb"[^\s\xef\xbb\xbf]", data) is None


def _first_sentences(text: str, limit: int = 160) -> str:
    """The whole sentences of ``text``'s first line that fit in ``limit`` characters.

    A reader's message is quoted in one line without being cut mid-sentence: whole
    sentences while they fit, else the first sentence cut at a word and marked "...".

    Examples
    --------
    >>> _first_sentences("Magic bytes not found. Either the file is corrupted or this "
    ...                  "is not a parquet file.", limit=40)
    'Magic bytes not found.'
    >>> _first_sentences("a b c d e f", limit=8)
    'a b...'
    """
    line = (text.strip().splitlines() or [""])[0].strip()
    if len(line) <= limit:
        return line
    kept = ""
    for sentence in re.split(r"(?<=[.!?])\s+", line):
        if len(kept) + len(sentence) + 1 > limit:
            break
        kept = f"{kept} {sentence}".strip()
    if kept:
        return kept
    return line[:limit - 3].rsplit(" ", 1)[0].rstrip(" ,;:") + "..."


def _corrupt(path: Path, kind: str, err: Exception) -> InputError:
    detail = _first_sentences(str(err))
    return InputError(f"{path}: not a readable {kind} file, truncated or corrupted "
                      f"({type(err).__name__}: {detail}); copy/export it again")


def _is_blank(row: list[str]) -> bool:
    return not row or (len(row) == 1 and not row[0].strip())


def _decode(path: Path, data: bytes) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise InputError(f"{path}: not UTF-8 text (bad byte at offset {err.start}); save the "
                         "CSV as UTF-8 text, or name a binary file .parquet or .npz") from None


def _first_line(data: bytes) -> bytes:
    """The first non-blank line of ``data`` (without a BOM), found without copying it all."""
    start = 3 if data.startswith(b"\xef\xbb\xbf") else 0
    while start < len(data):
        end = data.find(b"\n", start)
        end = len(data) if end < 0 else end
        line = data[start:end]
        if line.strip():
            return line
        start = end + 1
    return b""


def _read_csv(path: Path, data: bytes, reread: Callable[[], bytes] | None = None
              ) -> checks.RawTable:
    # The text is decoded as a whole only where a row must be diagnosed: a 200 MB file is
    # parsed by pyarrow from the bytes (a decoded copy and a StringIO of it cost ~5x the
    # file). ASCII is UTF-8, so only other files are checked by decoding them.
    if not data.isascii():
        _decode(path, data)
    first = _decode(path, _first_line(data))
    unterminated = not data.endswith((b"\n", b"\r"))
    held = [data]       # released once pyarrow parsed the file; re-read for a diagnosis
    del data

    def text() -> str:
        if held[0] is not None:
            return _decode(path, held[0])
        return _decode(path, reread() if reread is not None
                       else _read_bytes(path, "recording file", "check the path"))
    delim = next((d for d in (",", ";", "\t") if d in first), ",")

    def reader(text: str) -> Any:
        return csv.reader(_stdio.StringIO(text, newline=""), delimiter=delim)

    def parse() -> tuple[list[list[str]], list[int]]:
        rows: list[list[str]] = []
        lines: list[int] = []
        it = reader(text())
        seen_header = False
        try:
            for row in it:
                if _is_blank(row):
                    continue
                if seen_header:
                    rows.append(row)
                    lines.append(it.line_num)
                seen_header = True
        except csv.Error as err:
            raise InputError(f"{path}: unreadable CSV at line {it.line_num} ({err}); fix or "
                             "delete that line") from None
        return rows, lines

    header: list[str] = []
    try:
        header = next(([c.strip() for c in row] for row in reader(first)
                       if not _is_blank(row)), [])
    except csv.Error as err:
        raise InputError(f"{path}: unreadable CSV header ({err}); fix the first line") from None

    def fetch(raw: checks.RawTable, names: list[str]) -> dict[str, np.ndarray]:
        fast = _csv_fast(held, delim, names)
        if fast is not None:
            return fast
        rows = raw.rows or []
        checks.check_row_lengths(raw)
        cols = {}
        for name in names:
            j = raw.names.index(name)
            cells = [r[j] for r in rows]
            try:
                cols[name] = np.array(cells, dtype=float)
            except ValueError:
                cols[name] = checks.cells_to_float(raw, name, cells)
        return cols

    return checks.RawTable(path, header, fetch, parse=parse, unterminated=unterminated)


#: Bytes per block of the streaming CSV parse (pyarrow's own default is 1 MiB): whole-file
#: parsing holds ~3x the columns in flight; blocks keep a 200 MB file near 2x its size.
_CSV_BLOCK = 8 << 20


def _csv_fast(held: list, delim: str, names: list[str]) -> dict[str, np.ndarray] | None:
    """Strict C parse (pyarrow, streamed in blocks); None when anything is off.

    ``held`` is a one-item list holding the file's bytes; they are released (the item
    set to None) once parsed, before the columns are joined, so that the bytes, the
    parsed blocks and the joined columns are never all held at once.
    """
    import pyarrow as pa
    import pyarrow.csv as pacsv

    # The blocks are read in a Python loop, which the command line's Ctrl-C handler
    # interrupts between blocks; pyarrow's own handler (it would replace ours for the
    # duration of a read and turn Ctrl-C into its ArrowCancelled) stays off.
    pa.enable_signal_handlers(False)
    pieces: dict[str, list[np.ndarray]] = {c: [] for c in names}
    try:
        batches = pacsv.open_csv(
            pa.BufferReader(held[0]), read_options=pacsv.ReadOptions(block_size=_CSV_BLOCK),
            parse_options=pacsv.ParseOptions(delimiter=delim),
            convert_options=pacsv.ConvertOptions(
                column_types={c: pa.float64() for c in names}, include_columns=names))
        for batch in batches:
            for c in names:
                pieces[c].append(batch.column(c).to_numpy(zero_copy_only=False))
    except Exception:  # noqa: BLE001 - any doubt: the csv-module path diagnoses it
        return None
    good = sum(p.size for p in pieces[names[0]]) > 0 and all(
        np.isfinite(p).all() for parts in pieces.values() for p in parts)
    if not good:
        return None
    held[0] = None
    del batches
    cols = {}
    for c in names:
        parts = pieces.pop(c)
        cols[c] = np.concatenate(parts) if parts else np.empty(0)
        del parts
    pa.default_memory_pool().release_unused()     # the blocks' memory back to the system
    return cols


def _read_parquet(path: Path, data: bytes) -> checks.RawTable:
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(pa.BufferReader(data))
    except Exception as err:  # noqa: BLE001 - any reader failure means a damaged file
        raise _corrupt(path, "Parquet", err) from None

    def fetch(raw: checks.RawTable, names: list[str]) -> dict[str, np.ndarray]:
        cols = {}
        for name in names:
            col = table.column(name)
            typ = col.type
            if pa.types.is_floating(typ) or pa.types.is_integer(typ) or \
                    pa.types.is_decimal(typ):
                cols[name] = np.asarray(col.cast(pa.float64()).to_numpy(), dtype=float)
            elif pa.types.is_string(typ) or pa.types.is_large_string(typ):
                cols[name] = checks.cells_to_float(raw, name, col.to_pylist())
            else:
                raise InputError(f"{path}: column '{name}' holds {typ} values, not numbers; "
                                 "store it as floating point")
        return cols

    return checks.RawTable(path, [str(c) for c in table.column_names], fetch)


def _read_npz(path: Path, data: bytes) -> checks.RawTable:
    try:
        z = np.load(_stdio.BytesIO(data), allow_pickle=False)
    except Exception as err:  # noqa: BLE001 - any reader failure means a damaged file
        raise _corrupt(path, "NPZ", err) from None
    if not isinstance(z, np.lib.npyio.NpzFile):
        raise InputError(f"{path}: holds a single array, not named columns; save it with "
                         "numpy.savez(path, t=..., x=..., a=..., xe=...)")
    try:
        arrays = {k: z[k] for k in z.files}
    except Exception as err:  # noqa: BLE001 - a damaged member
        raise _corrupt(path, "NPZ", err) from None
    finally:
        z.close()

    def fetch(raw: checks.RawTable, names: list[str]) -> dict[str, np.ndarray]:
        cols = {}
        for name in names:
            arr = arrays[name]
            if arr.ndim != 1:
                raise InputError(f"{path}: array '{name}' has shape {arr.shape}; every "
                                 "column must be one-dimensional")
            if arr.dtype.kind in "fiu":
                cols[name] = arr.astype(float)
            elif arr.dtype.kind in "US":
                cells = [c.decode("utf-8", "replace") if isinstance(c, bytes) else c
                         for c in arr.tolist()]
                cols[name] = checks.cells_to_float(raw, name, cells)
            else:
                raise InputError(f"{path}: array '{name}' has dtype {arr.dtype}, not "
                                 "numbers; store it as floating point")
        return cols

    return checks.RawTable(path, list(arrays), fetch)


_READERS = {".csv": _read_csv, ".parquet": _read_parquet, ".npz": _read_npz}


def read_recording(path: str | os.PathLike, meta: Any = None,
                   channels: Mapping[str, str] | None = None) -> Recording:
    """Read a recording (CSV, Parquet, NPZ, TDMS or UFF 58) and its metadata, checked.

    Parameters
    ----------
    path : str or path-like
        The data file; the format follows the suffix (``.csv``, ``.parquet``, ``.npz``).
        Columns ``t, x, a, xe`` in SI units, or raw voltages ``x_mV, a_mV, xe_mV``
        converted with the metadata's sensitivities (x = x_mV / x_mV_per_mm / 1000 m,
        a = a_mV / a_mV_per_g * 9.81 m/s^2); other columns are ignored. A CSV may use
        ``,``, ``;`` or tab between cells and ``.`` as decimal point. LabVIEW ``.tdms``
        and UFF dataset 58 (``.uff``, ``.unv``) files need the extra ``formats``; their
        time axis and units come from the file (:mod:`vidiscover.io_lab`).
    meta : path-like, dict or Metadata, optional
        The metadata (see :func:`read_metadata`); default: the sidecar JSON with the
        same stem (``rec.json`` beside ``rec.csv``).
    channels : mapping, optional
        Our names (``t, x, a, xe`` or ``x_mV, a_mV, xe_mV``) -> the names of the file's
        columns or channels, e.g. ``{"x": "Laser", "a": "Accel", "xe": "Base"}``;
        default: the columns/channels with our names (lab files: case-insensitive).

    Returns
    -------
    Recording
        SI signals named after the file stem; ``meta.sample_rate`` is filled in from
        ``t`` when not given and ``meta.extra["units"]`` is "mV" when the file held
        voltages, else "SI".

    Raises
    ------
    InputError
        One line naming the file, the problem and the fix: a missing, empty, truncated
        or corrupted file; missing or misspelled columns; non-numeric cells; NaN gaps;
        non-monotonic or non-uniform time; a record shorter than 1 s or 2 forcing
        periods; displacements above 0.1 m (mm in a metre column) or an acceleration
        inconsistent with the displacement (g instead of m/s^2); missing, malformed or
        impossible metadata; a ``sample_rate`` off the time column by more than 0.1 %.

    See Also
    --------
    write_recording : the inverse.
    """
    path = Path(path)
    if path.is_dir():               # before the suffix check: 'unknown format' would mislead
        raise InputError(f"{path}: is a directory, not a recording file; pass the recording "
                         "file (rec.csv, .parquet or .npz)")
    fmt = _format_of(path, compressed=True)
    data = _read_bytes(path, "recording file", "check the path")
    if fmt == ".csv.gz":
        data = _gunzip(path, data)
    if _blank(data):
        raise InputError(f"{path}: empty file; copy/export the recording again")
    metadata = read_metadata(meta, recording=path)
    if fmt in LAB_FORMATS:
        from .io_lab import read_lab

        raw = read_lab(path, data, channels)
    else:
        raw = (_read_csv(path, data, reread=lambda: _gunzip(
                   path, _read_bytes(path, "recording file", "check the path")))
               if fmt == ".csv.gz" else _READERS[fmt](path, data))
        if channels is not None:
            from .io_lab import map_columns

            raw = map_columns(raw, channels)
    del data            # the reader keeps what it needs (a CSV's bytes only until parsed)
    cols = checks.pick_columns(raw)
    by_name = raw.fetch(raw, list(cols.values()))
    values = {sig: by_name[col] for sig, col in cols.items()}
    return checks.build_recording(raw, cols, values, metadata)


def _load_json(path: Path, what: str, fix_missing: str) -> Any:
    data = _read_bytes(path, what, fix_missing)
    if not data.strip():
        raise InputError(f"{path}: empty JSON file; write the {what} into it, e.g. "
                         '{"b": 0.009}')
    try:
        return json.loads(data.decode("utf-8-sig"))
    except UnicodeDecodeError as err:
        raise InputError(f"{path}: not UTF-8 text (bad byte at offset {err.start}); save it "
                         "as UTF-8 JSON") from None
    except json.JSONDecodeError as err:
        raise InputError(f"{path}: malformed JSON at line {err.lineno}, column {err.colno} "
                         f"({err.msg}); fix the syntax, e.g. " '{"b": 0.009}') from None
    except (ValueError, RecursionError) as err:
        raise InputError(f"{path}: malformed JSON ({type(err).__name__}: {str(err)[:80]}); "
                         "fix the file") from None


def _metadata_from_dict(d: Any, source: str) -> Metadata:
    if not isinstance(d, Mapping):
        raise InputError(f"{source}: metadata must be a JSON object such as "
                         f'{{"b": 0.009}}, found {type(d).__name__}')
    if "b" not in d:
        near = [k for k in d if str(k).strip().lower() in ("b", "b_m", "b_mm")
                or "clearance" in str(k).lower()]
        hint = f" (found {near[0]!r}: keys are case-sensitive, b is in m)" if near else ""
        raise InputError(f"{source}: missing required key 'b' (half-clearance in m){hint}; "
                         'add e.g. "b": 0.009')
    for key in ("b", "sample_rate", "m1", "m2", "c1", "k1"):
        if isinstance(d.get(key), (bool, list, dict)):
            raise InputError(f"{source}: '{key}' must be a number, was {d[key]!r}")
    for key, example in (("excitation", '{"amplitude": 0.0005, "frequency": 8.0}'),
                         ("sensitivity", '{"x_mV_per_mm": 10000, "a_mV_per_g": 50.34}')):
        value = d.get(key)
        if value is not None and not isinstance(value, Mapping):
            raise InputError(f"{source}: '{key}' must be an object like {example}, was "
                             f"{value!r}")
        for k, v in (value or {}).items():
            if v is None or isinstance(v, (bool, list, dict)):
                raise InputError(f"{source}: '{key}.{k}' must be a number, was {v!r}")
    kwargs = {k: d[k] for k in _META_KEYS if k in d}
    extra = {k: v for k, v in d.items() if k not in _META_KEYS}
    try:
        return Metadata(**kwargs, extra=extra, source=source)
    except InputError:
        raise
    except (TypeError, ValueError, OverflowError) as err:
        raise InputError(f"{source}: impossible metadata ({err}); fix the values") from None


def read_metadata(meta: Any = None, recording: str | os.PathLike | None = None) -> Metadata:
    """Metadata of a recording from a JSON file, a dict or a :class:`Metadata`.

    Parameters
    ----------
    meta : path-like, dict, Metadata or None
        A JSON file (``--meta``), its content as a dict, or a ready value (returned
        as is). None: the sidecar of ``recording`` (same stem, ``.json``).
    recording : path-like, optional
        The recording file, for the sidecar and for messages.

    Returns
    -------
    Metadata
        Only ``b`` is required, the rest defaults to the paper's values; unknown keys
        are kept in ``extra``; ``source`` names the JSON file so errors point at it.

    Raises
    ------
    InputError
        Missing or malformed file, missing ``b``, impossible values (b <= 0, a
        negative mass, a sensitivity that is not a number, ...).
    """
    rec = Path(recording) if recording is not None else None
    if isinstance(meta, Metadata):
        return meta
    if isinstance(meta, Mapping):
        return _metadata_from_dict(meta, f"metadata of {rec}" if rec else "metadata")
    if meta is None:
        if rec is None:
            raise InputError("no metadata given; pass a JSON file, a dict or a Metadata")
        path = rec.with_name(f"{checks.stem_of(rec)}.json")
        if not path.exists():
            raise InputError(f"{rec}: missing metadata: {path} not found; create "
                             f'{path.name} with {{"b": 0.009}} (half-clearance in m) or '
                             "pass --meta")
    elif isinstance(meta, (str, os.PathLike)):
        path = Path(meta)
    else:
        raise InputError(f"metadata must be a JSON file, a dict or a Metadata, was "
                         f"{type(meta).__name__}")
    content = _load_json(path, "metadata file", "check the --meta path")
    return _metadata_from_dict(content, str(path))


def truth_path(path: str | os.PathLike) -> Path:
    """The ground-truth file of recording ``path`` (``rec.csv[.gz]`` -> ``rec.truth.json``).

    A truth file's own path is returned as it is.
    """
    path = Path(path)
    if path.name.endswith(".truth.json"):
        return path
    return path.with_name(f"{checks.stem_of(path)}.truth.json")


def read_truth(path: str | os.PathLike) -> GroundTruth:
    """Ground truth of a simulated recording.

    Parameters
    ----------
    path : str or path-like
        The recording (``rec.csv``) or its truth file (``rec.truth.json``).

    Returns
    -------
    GroundTruth
        The content of ``<stem>.truth.json``.

    Raises
    ------
    InputError
        No truth file (only simulated recordings have one), malformed JSON or
        content that is not a ground truth.
    """
    tp = truth_path(Path(path))
    truth = _load_json(tp, "ground-truth file",
                       "only simulated recordings (vidiscover simulate) have one")
    try:
        return GroundTruth.from_dict(truth)
    except InputError as err:
        raise InputError(f"{tp}: {err}") from None


# =============================================================================== writing
def _write_csv(tmp: Path, columns: dict[str, np.ndarray], units: str) -> None:
    fmt = ["%.12g"] + ["%.12g" if units == "SI" else "%.10g"] * (len(columns) - 1)
    with open(tmp, "x", encoding="utf-8", newline="") as fh:
        np.savetxt(fh, np.column_stack(list(columns.values())), fmt=fmt, delimiter=",",
                   header=",".join(columns), comments="")


def _write_parquet(tmp: Path, columns: dict[str, np.ndarray], units: str) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    with open(tmp, "xb") as fh:
        pq.write_table(pa.table(columns), fh)


def _write_npz(tmp: Path, columns: dict[str, np.ndarray], units: str) -> None:
    with open(tmp, "xb") as fh:
        np.savez(fh, **columns)


def _write_data(fmt: str, tmp: Path, columns: dict[str, np.ndarray], units: str) -> None:
    writer = {".csv": _write_csv, ".parquet": _write_parquet, ".npz": _write_npz}[fmt]
    writer(tmp, columns, units)


def _columns_for(rec: Recording, units: str) -> dict[str, np.ndarray]:
    if units == "SI":
        return {"t": rec.t, "x": rec.x, "a": rec.a, "xe": rec.xe}
    s = rec.meta.sensitivity
    missing = [k for k in ("x_mV_per_mm", "xe_mV_per_mm", "a_mV_per_g") if k not in s]
    if missing:
        raise InputError(f"{rec.name}: cannot write mV columns without the sensitivities "
                         f"{', '.join(missing)}; set them in the recording's metadata")
    return {"t": rec.t, "x_mV": rec.x * 1000.0 * s["x_mV_per_mm"],
            "a_mV": rec.a / G_ACCEL * s["a_mV_per_g"],
            "xe_mV": rec.xe * 1000.0 * s["xe_mV_per_mm"]}


def write_recording(rec: Recording, path: str | os.PathLike,
                    truth: GroundTruth | None = None, units: str | None = None) -> list[Path]:
    """Write a recording, its metadata sidecar and optionally its ground truth.

    The files appear together or not at all: each is written to a temporary file in
    the same directory and renamed into place only when all were written; on any
    error the directory is left as it was.

    Parameters
    ----------
    rec : Recording
        The recording (SI values).
    path : str or path-like
        Data file; the format follows the suffix (``.csv``, ``.parquet``, ``.npz``).
        The metadata go to ``<stem>.json``, the truth to ``<stem>.truth.json``.
    truth : GroundTruth, optional
        Ground truth of a simulation, written as ``truth.to_dict()``. Without it, a
        stale ``<stem>.truth.json`` left by an earlier recording at this path is
        removed, so it cannot pass for this recording's truth.
    units : {"SI", "mV"}, optional
        Columns ``t, x, a, xe`` or ``t, x_mV, a_mV, xe_mV`` (converted with
        ``rec.meta.sensitivity``); default ``rec.meta.extra.get("units", "SI")``. The
        sidecar's ``"units"`` says which.

    Returns
    -------
    list of Path
        The files written: data, metadata and, with ``truth``, the truth file.

    Raises
    ------
    InputError
        Unknown format or units, or a directory that does not exist.

    Notes
    -----
    CSV keeps 12 significant digits in SI (10 for mV columns); Parquet and NPZ keep
    the float64 values exactly.
    """
    path = Path(path)
    fmt = _format_of(path)
    if fmt in LAB_FORMATS:
        raise InputError(f"{path}: vidiscover reads {fmt} files but does not write them; "
                         "write .csv, .parquet or .npz")
    units = rec.meta.extra.get("units", "SI") if units is None else units
    if units not in ("SI", "mV"):
        raise InputError(f"{path}: units must be 'SI' or 'mV', was {units!r}")
    if not path.parent.is_dir():
        raise InputError(f"{path}: directory '{path.parent}' does not exist; create it "
                         "first")
    columns = _columns_for(rec, units)
    meta = rec.meta.to_dict()
    meta["units"] = units
    tpath = truth_path(path)
    jobs: list[tuple[Path, Callable[[Path], None]]] = [
        (path, lambda tmp: _write_data(fmt, tmp, columns, units)),
        (path.with_suffix(".json"), lambda tmp: dump_json(tmp, meta, 2)),
    ]
    if truth is not None:
        if not isinstance(truth, GroundTruth):
            raise TypeError(f"truth must be a GroundTruth, was {type(truth).__name__}")
        content = truth.to_dict()
        jobs.append((tpath, lambda tmp: dump_json(tmp, content, None)))
    return write_group(jobs, remove=() if truth is not None else (tpath,))
