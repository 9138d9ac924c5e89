"""Checks of a recording file's columns and values (used by :mod:`vidiscover.io`).

Every check raises :class:`~vidiscover.errors.InputError` with one line naming the
file, the problem (with its row, and its line for CSV) and the fix. The rules are the
module constants below; the README's 'Recording format' lists the bad inputs they cover.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .errors import InputError
from .params import G_ACCEL
from .recording import Metadata, Recording

#: Signals of a recording and what they hold.
SIGNALS = {"t": "time in s", "x": "LO displacement in m", "a": "LO acceleration in m/s^2",
           "xe": "base displacement in m"}
#: Column names a recording file may use.
KNOWN_COLUMNS = ("t", "x", "a", "xe", "x_mV", "a_mV", "xe_mV")
LAYOUT = "t, x, a, xe (SI) or t, x_mV, a_mV, xe_mV (raw mV)"
#: Common names that mean one of the known columns.
ALIASES = {"time": "t", "times": "t", "disp": "x", "displacement": "x", "acc": "a",
           "accel": "a", "acceleration": "a", "base": "xe", "x_base": "xe", "xbase": "xe"}
#: Cell texts read as a missing value (case-insensitive).
NAN_TOKENS = frozenset({"", "nan", "-nan", "na", "n/a", "null", "none"})
#: |x| and |xe| above this (m) mean "not in metres".
MAX_DISPLACEMENT = 0.1
#: Shortest record (s) and fewest forcing periods accepted.
MIN_DURATION, MIN_PERIODS = 1.0, 2
#: Fewest samples per forcing period (fewer: ``t`` is probably not in seconds).
MIN_SAMPLES_PER_PERIOD = 20
#: Relative agreement required between the metadata ``sample_rate`` and ``t``.
RATE_RTOL = 1e-3
#: Accepted relative deviation of a time step from the median step.
STEP_RTOL = 0.01
#: Accepted ratio |a| / ((2 pi f)^2 |x|) at the strongest line near the forcing.
ACCEL_RATIO_RANGE = (0.2, 5.0)
#: Displacement amplitude (m) below which that ratio is not checked.
MIN_LINE_FOR_ACCEL = 1e-5


@dataclass
class RawTable:
    """Columns of a data file before validation; values are parsed on demand.

    ``fetch(raw, names)`` returns the named columns as floats (NaN for a missing cell).
    For CSV, ``parse()`` gives every data row's cells and file line; it runs only when
    needed (a problem to diagnose, a line number for a message).
    """

    path: Path
    names: list[str]
    fetch: Callable[[RawTable, list[str]], dict[str, np.ndarray]]
    parse: Callable[[], tuple[list[list[str]], list[int]]] | None = None
    unterminated: bool = False      # CSV text that does not end with a newline
    _parsed: tuple[list[list[str]], list[int]] | None = field(default=None, repr=False)

    def _table(self) -> tuple[list[list[str]], list[int]] | None:
        if self.parse is None:
            return None
        if self._parsed is None:
            self._parsed = self.parse()
        return self._parsed

    @property
    def rows(self) -> list[list[str]] | None:
        """CSV: the cells of each data row (None for other formats)."""
        table = self._table()
        return None if table is None else table[0]

    @property
    def lines(self) -> list[int] | None:
        """CSV: the file line of each data row (None for other formats)."""
        table = self._table()
        return None if table is None else table[1]

    def where(self, i: int, j: int | None = None) -> str:
        """Human location of data rows i..j (0-based in, 1-based out)."""
        j = i if j is None else j
        rows = f"row {i + 1}" if i == j else f"rows {i + 1}-{j + 1}"
        lines = self.lines
        if lines is None or j >= len(lines):
            return rows
        return f"{rows} (line {lines[i]})" if i == j else f"{rows} (lines {lines[i]}-{lines[j]})"

    def truncated(self, i: int, problem: str) -> InputError:
        """Error for an incomplete last row ``i``."""
        return InputError(f"{self.path}: truncated file: the last row, {self.where(i)}, is "
                          f"incomplete ({problem}); delete that row or copy/export the file "
                          "again")

    def row_error(self, i: int, n: int, problem: str, fix: str) -> InputError:
        """Error about row ``i`` of ``n`` (a truncation if it is an unterminated last row)."""
        if self.unterminated and i == n - 1:
            return self.truncated(i, problem)
        return InputError(f"{self.path}: {problem}; {fix}")


def stem_of(path: Path) -> str:
    """A recording's name: its file name without the format suffix and a ``.gz``.

    Examples
    --------
    >>> stem_of(Path("runs/P02.csv.gz")), stem_of(Path("rec.csv"))
    ('P02', 'rec')
    """
    name = path.name[:-3] if path.name.lower().endswith(".gz") else path.name
    return Path(name).stem


def cells_to_float(raw: RawTable, name: str, cells: list) -> np.ndarray:
    """Parse text cells; missing tokens become NaN, anything else non-numeric is an error."""
    out = np.empty(len(cells))
    for i, cell in enumerate(cells):
        if cell is None:
            out[i] = np.nan
            continue
        try:
            out[i] = float(cell)
        except (TypeError, ValueError):
            text = str(cell)
            if text.strip().lower() in NAN_TOKENS:
                out[i] = np.nan
                continue
            shown = repr(text) if len(text) <= 40 else repr(text[:37] + "...")
            raise raw.row_error(i, len(cells), f"non-numeric cell {shown} in column '{name}' "
                                               f"at {raw.where(i)}",
                                "cells must be plain numbers with '.' as decimal point: fix "
                                "or delete that row") from None
    return out


def check_row_lengths(raw: RawTable) -> None:
    """Every CSV data row must have as many cells as the header has names."""
    rows = raw.rows or []
    m = len(raw.names)
    lens = np.fromiter(map(len, rows), dtype=int, count=len(rows))
    bad = np.flatnonzero(lens != m)
    if not bad.size:
        return
    i = int(bad[0])
    if i == len(rows) - 1:
        raise InputError(f"{raw.path}: truncated file: the last row, {raw.where(i)}, has "
                         f"{lens[i]} of {m} cells; delete that row or copy/export the file "
                         "again")
    kind = "missing cells" if lens[i] < m else "extra cells"
    raise InputError(f"{raw.path}: {raw.where(i)} has {lens[i]} cells but the header has {m} "
                     f"columns ({kind}); fix or delete that row")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def suggest(name: str) -> str | None:
    """Return the known column a misspelled name most likely means (difflib), or None."""
    low = name.strip().lower()
    if low in ALIASES:
        return ALIASES[low]
    lower = {k.lower(): k for k in KNOWN_COLUMNS}
    match = difflib.get_close_matches(low, list(lower), n=1, cutoff=0.5)
    return lower[match[0]] if match else None


def pick_columns(raw: RawTable) -> dict[str, str]:
    """Map each signal (t, x, a, xe) to the column that carries it."""
    names = raw.names
    path = raw.path
    given = [c for c in names if c.strip()]
    if given and all(_is_number(c) for c in given):
        raise InputError(f"{path}: the first line holds numbers, not column names; add a "
                         f"header line naming {LAYOUT}")
    seen: set[str] = set()
    for c in names:
        if c in seen and c in KNOWN_COLUMNS:
            raise InputError(f"{path}: column '{c}' appears twice in the header; rename or "
                             "delete one of them")
        seen.add(c)
    chosen: dict[str, str] = {}
    for sig, desc in SIGNALS.items():
        options = [sig] if sig == "t" else [sig, f"{sig}_mV"]
        present = [o for o in options if o in names]
        if len(present) == 2:
            raise InputError(f"{path}: has both '{sig}' and '{sig}_mV'; keep one of them "
                             "(SI or raw mV)")
        if present:
            chosen[sig] = present[0]
            continue
        for c in names:
            if c not in KNOWN_COLUMNS and suggest(c) in options:
                raise InputError(f"{path}: missing column '{sig}' ({desc}); found {c!r}: did "
                                 f"you mean '{suggest(c)}'? Rename it; the columns must be "
                                 f"{LAYOUT}")
        found = ", ".join(repr(c) for c in names[:12]) + (", ..." if len(names) > 12 else "")
        alt = "" if sig == "t" else f", or '{sig}_mV' in mV"
        raise InputError(f"{path}: missing column '{sig}' ({desc}{alt}); the header has "
                         f"{found or 'no names'}; the columns must be {LAYOUT}")
    return chosen


def check_gaps(raw: RawTable, name: str, arr: np.ndarray) -> None:
    """No NaN (missing) or infinite values."""
    bad = ~np.isfinite(arr)
    if not bad.any():
        return
    n = arr.size
    idx = np.flatnonzero(bad)
    if np.isinf(arr[idx[0]]):
        i = int(idx[0])
        raise raw.row_error(i, n, f"infinite value in column '{name}' at {raw.where(i)}",
                            "replace it with a finite number or cut the record there")
    if raw.unterminated and idx[0] == n - 1:
        raise raw.truncated(n - 1, f"no value in column '{name}'")
    breaks = np.flatnonzero(np.diff(idx) > 1)
    starts = np.r_[idx[0], idx[breaks + 1]]
    ends = np.r_[idx[breaks], idx[-1]]
    raise InputError(f"{raw.path}: column '{name}' has {idx.size} missing value(s) (NaN or "
                     f"empty) in {starts.size} gap(s), the first at "
                     f"{raw.where(int(starts[0]), int(ends[0]))}; fill the gaps (e.g. "
                     "interpolate) or cut the record before them")


def check_time(raw: RawTable, t: np.ndarray) -> None:
    """Strictly increasing, uniform time (each step within STEP_RTOL of the median)."""
    n = t.size
    d = np.diff(t)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise raw.row_error(i, n, f"time is not strictly increasing (non-monotonic) at "
                                  f"{raw.where(i)}: t = {t[i]:.10g} s after {t[i - 1]:.10g} s",
                            "sort the rows by t and remove duplicated samples")
    step = float(np.median(d))
    bad = np.flatnonzero(np.abs(d - step) > STEP_RTOL * step)
    if bad.size:
        i = int(bad[0]) + 1
        raise raw.row_error(i, n, f"non-uniform time step at {raw.where(i)}: t goes from "
                                  f"{t[i - 1]:.10g} to {t[i]:.10g} s, a step of "
                                  f"{d[i - 1]:.6g} s against the usual {step:.6g} s (rule: "
                                  f"within {STEP_RTOL:.0%})",
                            "resample to a uniform grid or cut the record there")


#: Samples the acceleration-units check looks at (longer records: their middle part; at
#: 6.4 kHz 2^20 samples are 164 s, hundreds of forcing periods).
_ACCEL_CHECK_SAMPLES = 1 << 20


def accel_ratio(x: np.ndarray, a: np.ndarray, fs: float,
                f: float) -> tuple[float | None, float]:
    """Return |A| / ((2 pi f_k)^2 |X|) at the strongest displacement line f_k in [f/2, 2f].

    ``a`` is the second derivative of ``x`` (one rigid body), so in SI units the ratio
    is about 1 whatever the motion. None when that line is below MIN_LINE_FOR_ACCEL
    (accelerometer noise would dominate).
    """
    if x.size > _ACCEL_CHECK_SAMPLES:         # a units check: the middle 2^20 samples
        mid = (x.size - _ACCEL_CHECK_SAMPLES) // 2
        x, a = x[mid:mid + _ACCEL_CHECK_SAMPLES], a[mid:mid + _ACCEL_CHECK_SAMPLES]
    n = x.size
    w = np.hanning(n)
    X = np.fft.rfft((x - x.mean()) * w)
    freqs = np.fft.rfftfreq(n, 1.0 / fs)
    band = np.flatnonzero((freqs >= 0.5 * f) & (freqs <= 2.0 * f))
    if not band.size:
        return None, f
    k = int(band[np.argmax(np.abs(X[band]))])
    if 4.0 * abs(X[k]) / n < MIN_LINE_FOR_ACCEL:
        return None, f
    A = np.fft.rfft((a - a.mean()) * w)[k]
    return float(abs(A) / ((2 * np.pi * freqs[k]) ** 2 * abs(X[k]))), float(freqs[k])


def check_units(raw: RawTable, cols: dict[str, str], sig: dict[str, np.ndarray],
                meta: Metadata, fs: float) -> None:
    """Displacements within 0.1 m; acceleration consistent with the displacement."""
    n = sig["t"].size
    for s in ("x", "xe"):
        mag = np.abs(sig[s])
        over = np.flatnonzero(mag > MAX_DISPLACEMENT)
        if not over.size:
            continue
        i = int(np.argmax(mag))
        if over.size == 1 and raw.unterminated and i == n - 1:
            raise raw.truncated(i, f"'{cols[s]}' jumps to {sig[s][i]:.4g} m")
        if cols[s] == s:
            raise InputError(f"{raw.path}: column '{s}' reaches {mag[i]:.4g} at "
                             f"{raw.where(i)}, more than {MAX_DISPLACEMENT} m: it looks like "
                             f"mm, not m; give '{s}' in metres (divide by 1000)")
        key = f"{s}_mV_per_mm"
        raise InputError(f"{raw.path}: column '{cols[s]}' converts to {mag[i]:.4g} m at "
                         f"{raw.where(i)} (more than {MAX_DISPLACEMENT} m) with {key} = "
                         f"{meta.sensitivity[key]:g}; fix {key} in {meta.source} or the "
                         "column's unit (mV)")
    ratio, freq = accel_ratio(sig["x"], sig["a"], fs, meta.frequency)
    lo, hi = ACCEL_RATIO_RANGE
    if ratio is not None and not lo <= ratio <= hi:
        guess = (" (it looks like g, not m/s^2)" if 0.05 < ratio < lo else
                 " (is it in mm/s^2?)" if 200 < ratio < 5000 else "")
        fix = (f"check a_mV_per_g in {meta.source}" if cols["a"] == "a_mV" else
               "give 'a' in m/s^2 (multiply g by 9.81)")
        raise InputError(f"{raw.path}: column '{cols['a']}' is {ratio:.3g} times what the "
                         f"displacement implies at {freq:.3g} Hz ((2 pi f)^2 |x|, expected "
                         f"about 1){guess}; {fix}")


def check_live(raw: RawTable, cols: dict[str, str], sig: dict[str, np.ndarray]) -> None:
    """Refuse a flat channel: a dead sensor, an unplugged cable or a channel never recorded.

    The LO displacement and acceleration of a driven rig always move; a channel whose
    readings never change cannot be analysed (it would read as 'no impact'). A flat
    base channel is allowed: without a base sensor the cycles are cut with the
    metadata's frequency, and the analysis says so.
    """
    for s in ("x", "a"):
        if np.ptp(sig[s]) == 0.0:
            raise InputError(f"{raw.path}: column '{cols[s]}' is constant ({sig[s][0]:g} "
                             "throughout): a dead or disconnected sensor; check the sensor, "
                             "its cable and the channel mapping")


def build_recording(raw: RawTable, cols: dict[str, str], values: dict[str, np.ndarray],
                    meta: Metadata) -> Recording:
    """Check the values (gaps, time, length, units) and convert them to a Recording."""
    path = raw.path
    sizes = {cols[s]: v.size for s, v in values.items()}
    if len(set(sizes.values())) > 1:
        text = ", ".join(f"{c}: {k}" for c, k in sizes.items())
        raise InputError(f"{path}: columns have different lengths ({text}); the file looks "
                         "truncated: copy/export it again")
    t = values["t"]
    n = t.size
    if n == 0:
        raise InputError(f"{path}: no data rows (empty or truncated file); copy/export the "
                         "recording again")
    for s, col in cols.items():
        check_gaps(raw, col, values[s])
    f = meta.frequency
    rule = (f"the rule is at least {MIN_DURATION:g} s and {MIN_PERIODS} forcing periods "
            f"({MIN_PERIODS / f:.3g} s at {f:g} Hz)")
    if n < 2:
        raise InputError(f"{path}: record too short: 1 sample; {rule}; record longer")
    check_time(raw, t)
    fs_t = (n - 1) / float(t[-1] - t[0])
    fs = fs_t
    if meta.sample_rate is not None:
        if abs(meta.sample_rate - fs_t) > RATE_RTOL * fs_t:
            raise InputError(f"{meta.source}: sample_rate = {meta.sample_rate:g} Hz disagrees "
                             f"with the time column of {path.name} ({fs_t:.6g} Hz from its "
                             f"mean step; tolerance {RATE_RTOL:.1%}); fix 'sample_rate' or "
                             "drop it (it defaults to what t says)")
        fs = float(meta.sample_rate)
    if fs < MIN_SAMPLES_PER_PERIOD * f:
        raise InputError(f"{path}: the time column gives {fs:.4g} Hz sampling, fewer than "
                         f"{MIN_SAMPLES_PER_PERIOD} samples per forcing period ({f:g} Hz): "
                         "is 't' in ms? 't' must be in seconds")
    duration = n / fs
    if duration < max(MIN_DURATION, MIN_PERIODS / f) * (1 - 1e-9):
        raise InputError(f"{path}: record too short: {duration:.4g} s ({n} samples); {rule}; "
                         "record longer")
    sens = meta.sensitivity
    missing = [f"{c.removesuffix('_mV')}_mV_per_{'g' if c == 'a_mV' else 'mm'}"
               for c in cols.values() if c.endswith("_mV")]
    missing = [k for k in missing if k not in sens]
    if missing:
        raise InputError(f"{path}: the file is in mV but {meta.source} gives no sensitivity "
                         f"{', '.join(missing)}; add them, e.g. \"sensitivity\": "
                         f"{{\"{missing[0]}\": ...}}, or pass --meta with them")
    sig = {"t": t}
    for s in ("x", "xe"):
        sig[s] = (values[s] / sens[f"{s}_mV_per_mm"] / 1000.0 if cols[s] == f"{s}_mV"
                  else values[s])
    sig["a"] = (values["a"] / sens["a_mV_per_g"] * G_ACCEL if cols["a"] == "a_mV"
                else values["a"])
    check_live(raw, cols, sig)
    check_units(raw, cols, sig, meta, fs)
    units = "mV" if any(c.endswith("_mV") for c in cols.values()) else "SI"
    meta = replace(meta, sample_rate=fs, extra={**meta.extra, "units": units})
    return Recording(t, sig["x"], sig["a"], sig["xe"], meta, name=stem_of(path))
