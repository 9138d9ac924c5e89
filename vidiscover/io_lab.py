"""Lab file formats (LabVIEW TDMS, UFF dataset 58) and the mapping of channel names.

A vibration lab's acquisition software rarely writes our CSV: LabVIEW and NI DAQ
systems write TDMS files, modal-analysis software UFF (universal file, ``.uff`` or
``.unv``) with one dataset 58 per channel. :func:`read_lab` reads both into the
:class:`~vidiscover._io_checks.RawTable` that :func:`vidiscover.io.read_recording`
checks like any CSV:

* the channels ``x``, ``a``, ``xe`` (and optionally ``t``) are found by name
  (case-insensitive) or by a mapping ``{"x": "Laser", "a": "Accel", ...}``
  (``--channels x=Laser,a=Accel,xe=Base`` on the command line);
* the time axis comes from the file: a mapped/``t`` channel, else the waveform
  properties ``wf_increment``/``wf_start_offset`` (TDMS) or the abscissa minimum and
  increment (UFF 58);
* units come from the file where it carries them (TDMS ``unit_string``, UFF 58
  ordinate/abscissa unit labels, the UFF data-type code as a check) and are
  converted: m, mm, um, cm -> m; m/s^2, mm/s^2, g -> m/s^2; mV, V -> the raw-mV
  columns that the metadata's sensitivities convert; s, ms -> s. A channel without a
  unit is taken as named: ``x`` in SI, ``x_mV`` in mV.

npTDMS and pyuff are optional (``pip install 'vidiscover[formats]'``) and imported
only when such a file is read. :func:`map_columns` applies the same mapping to the
columns of a CSV, Parquet or NPZ file.
"""

from __future__ import annotations

import importlib
import io as _stdio
import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import _io_checks as checks
from .errors import InputError
from .params import G_ACCEL

__all__ = ["LAB_FORMATS", "CHANNEL_KEYS", "parse_channels", "check_channels", "read_lab",
           "map_columns"]

#: Recording formats read by this module, by suffix.
LAB_FORMATS = (".tdms", ".uff", ".unv")
#: Names a channel mapping may assign (``x`` in SI, ``x_mV`` in mV, ...).
CHANNEL_KEYS = checks.KNOWN_COLUMNS
_KEYS_TEXT = "t, x, a, xe (or x_mV, a_mV, xe_mV for channels in mV)"
_EXAMPLE = "--channels x=NAME,a=NAME,xe=NAME"
#: Library (import name, distribution name) of each format.
_LIBRARIES = {".tdms": ("nptdms", "npTDMS"), ".uff": ("pyuff", "pyuff"),
              ".unv": ("pyuff", "pyuff")}
#: Physical quantity of each signal.
_QUANTITY = {"t": "time", "x": "length", "xe": "length", "a": "acceleration"}
#: Units understood (normalised text -> quantity, factor to s, m, m/s^2 or mV).
_UNITS: dict[str, tuple[str, float]] = {
    "s": ("time", 1.0), "sec": ("time", 1.0), "ms": ("time", 1e-3),
    "m": ("length", 1.0), "cm": ("length", 1e-2), "mm": ("length", 1e-3),
    "um": ("length", 1e-6), "\u00b5m": ("length", 1e-6), "\u03bcm": ("length", 1e-6),
    "m/s^2": ("acceleration", 1.0), "m/s2": ("acceleration", 1.0),
    "m/s**2": ("acceleration", 1.0), "m/s/s": ("acceleration", 1.0),
    "ms^-2": ("acceleration", 1.0), "m*s^-2": ("acceleration", 1.0),
    "mm/s^2": ("acceleration", 1e-3), "mm/s2": ("acceleration", 1e-3),
    "g": ("acceleration", G_ACCEL), "gn": ("acceleration", G_ACCEL),
    "mv": ("voltage", 1.0), "v": ("voltage", 1e3),
}
_UNITS_TEXT = {"time": "s or ms", "length": "m, mm, um or cm (or mV, V)",
               "acceleration": "m/s^2, mm/s^2 or g (or mV, V)"}
#: UFF dataset 58 ordinate/abscissa specific data types (the codes vidiscover reads).
_UFF_QUANTITY = {2: "stress", 3: "strain", 5: "temperature", 8: "length", 9: "force",
                 11: "velocity", 12: "acceleration", 13: "force", 15: "pressure",
                 17: "time", 18: "frequency"}
#: UFF dataset 58 function types that are time histories (0 general, 1 time response).
_UFF_TIME_FUNCTIONS = (0, 1)
#: Relative agreement required between the sampling steps of the channels.
_STEP_RTOL = 1e-6


# ============================================================================ mapping
def check_channels(channels: Mapping[str, str] | None) -> dict[str, str]:
    """A channel mapping ``{our name: name in the file}``, checked.

    Parameters
    ----------
    channels : mapping or None
        Keys among :data:`CHANNEL_KEYS` (``x`` in SI, ``x_mV`` in mV ...), values the
        names of channels (or columns) in the file; None: no mapping.

    Returns
    -------
    dict
        The mapping (empty for None).

    Raises
    ------
    InputError
        Unknown key, empty name, a signal mapped twice (``x`` and ``x_mV``) or two
        signals mapped to one channel.

    Examples
    --------
    >>> check_channels({"x": "Laser", "a": "Accel"})
    {'x': 'Laser', 'a': 'Accel'}
    """
    if channels is None:
        return {}
    if not isinstance(channels, Mapping):
        raise InputError(f"channels must map names like 'x' to channel names, e.g. "
                         f"{{'x': 'Laser'}}, was {type(channels).__name__}")
    out: dict[str, str] = {}
    signals: dict[str, str] = {}
    targets: dict[str, str] = {}
    for key, name in channels.items():
        key = str(key).strip()
        if key not in CHANNEL_KEYS:
            raise InputError(f"channels: unknown signal {key!r}; map {_KEYS_TEXT} to channel "
                             f"names, e.g. {_EXAMPLE}")
        if not isinstance(name, str) or not name.strip():
            raise InputError(f"channels: {key} needs a channel name, e.g. {key}=Laser, was "
                             f"{name!r}")
        sig = key.removesuffix("_mV")
        if sig in signals:
            raise InputError(f"channels: '{sig}' is mapped twice ({signals[sig]} and {key}); "
                             "map it once")
        name = name.strip()
        if name.lower() in targets:
            raise InputError(f"channels: {targets[name.lower()]} and {key} both name channel "
                             f"{name!r}; each signal needs its own channel")
        signals[sig] = key
        targets[name.lower()] = key
        out[key] = name
    return out


def parse_channels(text: str) -> dict[str, str]:
    """The ``--channels`` option value ``x=NAME,a=NAME,xe=NAME`` as a checked mapping.

    Parameters
    ----------
    text : str
        Comma-separated ``KEY=NAME`` pairs; a NAME may hold ``=`` and spaces, not
        commas.

    Returns
    -------
    dict
        See :func:`check_channels`.

    Raises
    ------
    InputError
        One line starting with ``--channels``: malformed pairs or a bad mapping.

    Examples
    --------
    >>> parse_channels("x=Laser, a=Accel,xe=Base/xe")
    {'x': 'Laser', 'a': 'Accel', 'xe': 'Base/xe'}
    """
    pairs: dict[str, str] = {}
    for item in str(text).split(","):
        key, eq, name = item.partition("=")
        if not eq or not key.strip():
            raise InputError(f"--channels {text!r}: expected KEY=NAME pairs separated by "
                             f"commas, e.g. {_EXAMPLE}")
        if key.strip() in pairs:
            raise InputError(f"--channels {text!r}: '{key.strip()}' is given twice; map it "
                             "once")
        pairs[key.strip()] = name
    try:
        return check_channels(pairs)
    except InputError as err:
        raise InputError(f"--channels {text!r}: {str(err).removeprefix('channels: ')}") \
            from None


def _listing(names: list[str], limit: int = 12) -> str:
    shown = ", ".join(repr(n) for n in names[:limit])
    return (shown + (", ..." if len(names) > limit else "")) or "none"


def _find(names: list[str], wanted: str) -> list[str]:
    """Exact match, else the case-insensitive ones."""
    if wanted in names:
        return [wanted]
    low = wanted.strip().lower()
    return [n for n in names if n.strip().lower() == low]


def map_columns(raw: checks.RawTable, channels: Mapping[str, str] | None) -> checks.RawTable:
    """Rename the mapped columns of a CSV, Parquet or NPZ table to our names.

    A column of the file that a mapped signal replaces (``x`` when ``x=Laser``) is
    ignored; the others are kept, so an unmapped ``t`` is still found by name.

    Raises
    ------
    InputError
        A mapped column that the file does not have (the message lists its columns).
    """
    mapping = check_channels(channels)
    if not mapping:
        return raw
    rename: dict[str, str] = {}            # column in the file -> our name
    for key, wanted in mapping.items():
        found = _find(raw.names, wanted)
        if len(found) != 1:
            what = "no column" if not found else "several columns"
            raise InputError(f"{raw.path}: channel mapping {key}={wanted}: {what} {wanted!r} "
                             f"in the file; its columns are {_listing(raw.names)}; fix the "
                             "name (--channels)")
        if found[0] in rename:
            raise InputError(f"{raw.path}: channel mapping: {rename[found[0]]} and {key} both "
                             f"name column {found[0]!r}; each signal needs its own column")
        rename[found[0]] = key
    mapped = {k.removesuffix("_mV") for k in mapping}
    names = [rename.get(n, n) for n in raw.names
             if n in rename or not (n in CHANNEL_KEYS and n.removesuffix("_mV") in mapped)]
    back = {ours: col for col, ours in rename.items()}

    def fetch(_: checks.RawTable, wanted: list[str]) -> dict[str, np.ndarray]:
        cols = [back.get(n, n) for n in wanted]
        got = raw.fetch(raw, cols)       # the file's own names: its messages name them
        return {n: got[c] for n, c in zip(wanted, cols)}

    return checks.RawTable(raw.path, names, fetch,
                           parse=None if raw.parse is None else raw._table,
                           unterminated=raw.unterminated)


# ============================================================================ channels
@dataclass
class _Channel:
    """One channel of a lab file, before mapping and unit conversion."""

    name: str                       # as shown to the user (unique in the file)
    values: np.ndarray
    unit: str = ""                  # as written in the file ("" when none)
    quantity: str | None = None     # from a UFF data-type code
    step: float | None = None       # sampling step, in time_unit
    start: float = 0.0
    time_unit: str = ""
    times: np.ndarray | None = None  # uneven abscissa
    aliases: tuple[str, ...] = field(default=())


@dataclass
class _LabFile:
    kind: str                       # "TDMS" or "UFF"
    unit_field: str                 # where the file keeps a channel's unit
    channels: list[_Channel]


def _library(path: Path, fmt: str) -> Any:
    module, dist = _LIBRARIES[fmt]
    try:
        return importlib.import_module(module)
    except ImportError:
        raise InputError(f"{path}: reading {fmt} needs {dist}: pip install "
                         "'vidiscover[formats]'") from None


def _corrupt(path: Path, kind: str, detail: str) -> InputError:
    return InputError(f"{path}: not a readable {kind} file, truncated or corrupted "
                      f"({detail}); copy/export it again")


class _Collect(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


def _read_tdms(path: Path, data: bytes) -> _LabFile:
    from .io import _first_sentences

    nptdms = _library(path, ".tdms")
    # npTDMS reads a truncated file as far as it goes and only logs a warning: catch
    # it (a truncated recording must not pass for a short one) and keep it off stderr
    collect = _Collect()
    parent = logging.getLogger("nptdms")
    parent.addHandler(collect)
    try:
        from nptdms.log import log_manager
        console = log_manager.console_handler
    except (ImportError, AttributeError):   # pragma: no cover - other npTDMS layouts
        console = None
    level = console.level if console is not None else None
    if console is not None:
        console.setLevel(logging.CRITICAL + 1)
    try:
        tdms = nptdms.TdmsFile.read(_stdio.BytesIO(data))
    except Exception as err:  # noqa: BLE001 - any reader failure means a damaged file
        raise _corrupt(path, "TDMS", f"{type(err).__name__}: {_first_sentences(str(err))}") \
            from None
    finally:
        parent.removeHandler(collect)
        if console is not None:
            console.setLevel(level)
    if collect.messages:
        raise _corrupt(path, "TDMS", f"npTDMS: {_first_sentences(collect.messages[0])}")
    pairs = [(g.name, c) for g in tdms.groups() for c in g.channels()]
    counts: dict[str, int] = {}
    for _, c in pairs:
        counts[c.name] = counts.get(c.name, 0) + 1
    out = []
    for group, c in pairs:
        props = c.properties
        full = f"{group}/{c.name}"
        step = props.get("wf_increment")
        values = c[:]
        if values.dtype.kind == "M":         # a timestamp channel: seconds from its start
            values = (values - values[0]) / np.timedelta64(1, "s") if values.size else \
                np.zeros(0)
        out.append(_Channel(
            name=c.name if counts[c.name] == 1 else full, values=np.asarray(values),
            unit=str(props.get("unit_string", "") or ""),
            step=None if step is None else float(step),
            start=float(props.get("wf_start_offset", 0.0) or 0.0),
            time_unit=str(props.get("wf_xunit_string", "") or ""), aliases=(c.name, full)))
    return _LabFile("TDMS", "unit_string property", out)


def _uff_label(text: Any) -> str:
    text = str(text or "").strip()
    return "" if text.upper() == "NONE" else text


def _read_uff(path: Path, data: bytes) -> _LabFile:
    from .io import _first_sentences

    pyuff = _library(path, path.suffix.lower())
    lines = data.rstrip().splitlines()
    if not lines or lines[-1].strip() != b"-1":
        # every UFF dataset ends with a '-1' line; pyuff drops an incomplete one silently
        raise _corrupt(path, "UFF", "the last dataset does not end with its '-1' line")
    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception as err:  # noqa: BLE001 - any reader failure means a damaged file
        raise _corrupt(path, "UFF", f"{type(err).__name__}: {_first_sentences(str(err))}") \
            from None
    sets = [sets] if isinstance(sets, Mapping) else list(sets or [])
    if not sets:
        raise _corrupt(path, "UFF", "pyuff found no dataset")
    d58 = [d for d in sets if d.get("type") == 58]
    if not d58:
        types = sorted({str(d.get("type")) for d in sets})
        raise InputError(f"{path}: holds no UFF dataset 58 (function at nodal DOF), only "
                         f"dataset(s) {', '.join(types)}; export the time histories as "
                         "dataset 58")
    ids = [_uff_label(d.get("id1")) or f"node {d.get('rsp_node')} dir {d.get('rsp_dir')}"
           for d in d58]
    out = []
    for k, (d, ident) in enumerate(zip(d58, ids)):
        name = ident if ids.count(ident) == 1 else f"{ident} #{k + 1}"
        values = np.asarray(d.get("data", []))
        func = int(d.get("func_type", 0) or 0)
        if func not in _UFF_TIME_FUNCTIONS:
            raise InputError(f"{path}: dataset 58 {name!r} is not a time history (function "
                             f"type {func}, e.g. 4 is a frequency response); export the time "
                             "histories (function type 1)")
        if np.iscomplexobj(values):
            raise InputError(f"{path}: dataset 58 {name!r} holds complex values, not a time "
                             "history; export the measured time histories")
        n_pts = d.get("num_pts")
        if n_pts is not None and int(n_pts) != values.size:
            raise _corrupt(path, "UFF", f"dataset 58 {name!r} has {values.size} of its "
                                        f"{int(n_pts)} values")
        even = int(d.get("abscissa_spacing", 1) or 0) == 1
        x = d.get("x")
        out.append(_Channel(
            name=name, values=values, unit=_uff_label(d.get("ordinate_axis_units_lab")),
            quantity=_UFF_QUANTITY.get(int(d.get("ordinate_spec_data_type", 0) or 0)),
            step=float(d["abscissa_inc"]) if even and d.get("abscissa_inc") else None,
            start=float(d.get("abscissa_min", 0.0) or 0.0),
            time_unit=_uff_label(d.get("abscissa_axis_units_lab")),
            times=None if even or x is None else np.asarray(x, dtype=float),
            aliases=(name, ident)))
    return _LabFile("UFF", "ordinate units label", out)


# ============================================================================ conversion
def _norm_unit(unit: str) -> str:
    return (unit.strip().replace(" ", "").replace("\u00b2", "^2").replace("sec", "s")
            .lower())


def _resolve(path: Path, lab: _LabFile, channels: dict[str, str]) -> dict[str, _Channel]:
    """Our name (``x``, ``a_mV`` ...) -> the file's channel, by mapping or by name."""
    names = [c.name for c in lab.channels]
    listing = _listing(names)

    def lookup(key: str, wanted: str, explicit: bool) -> _Channel | None:
        exact = [c for c in lab.channels if wanted in c.aliases]
        found = exact or [c for c in lab.channels
                          if wanted.strip().lower() in (a.strip().lower() for a in c.aliases)]
        if len(found) > 1:
            raise InputError(f"{path}: {len(found)} channels are named {wanted!r} "
                             f"({_listing([c.name for c in found])}); choose one with "
                             f"--channels {key.removesuffix('_mV')}=NAME")
        if not found and explicit:
            raise InputError(f"{path}: channel mapping {key}={wanted}: no channel {wanted!r} "
                             f"in the file; its channels are {listing}; fix the name "
                             "(--channels)")
        return found[0] if found else None

    chosen: dict[str, _Channel] = {key: lookup(key, name, True)  # type: ignore[misc]
                                   for key, name in channels.items()}
    mapped = {k.removesuffix("_mV") for k in chosen}
    for key in CHANNEL_KEYS:
        sig = key.removesuffix("_mV")
        if sig in mapped:
            continue
        ch = lookup(key, key, False) or (lookup(key, "time", False) if key == "t" else None)
        if ch is not None:
            chosen[key] = ch
            mapped.add(sig)
    for sig in ("x", "a", "xe"):
        if sig not in mapped:
            raise InputError(f"{path}: no channel for '{sig}' ({checks.SIGNALS[sig]}); the "
                             f"file has channels {listing}; name them x, a, xe or map them: "
                             f"{_EXAMPLE}")
    used: dict[str, str] = {}
    for key, ch in chosen.items():
        if ch.name in used:
            raise InputError(f"{path}: channel {ch.name!r} is mapped to both {used[ch.name]} "
                             f"and {key}; each signal needs its own channel")
        used[ch.name] = key
    return chosen


def _convert(path: Path, lab: _LabFile, key: str, ch: _Channel) -> tuple[str, np.ndarray]:
    """(column name for the checks, values): SI (``x``) or mV (``x_mV``) as the unit says."""
    sig = key.removesuffix("_mV")
    want = _QUANTITY[sig]
    if ch.values.dtype.kind not in "fiub":
        raise InputError(f"{path}: channel {ch.name!r} ({sig}) holds {ch.values.dtype} "
                         "values, not numbers; map a numeric channel")
    values = ch.values.astype(float)
    unit = _norm_unit(ch.unit)
    if not unit:
        if ch.quantity is not None and ch.quantity != want:
            raise InputError(f"{path}: channel {ch.name!r} holds {ch.quantity} (its UFF data "
                             f"type), not {want}, but is mapped to {sig}; map a {want} "
                             f"channel: --channels {sig}=NAME")
        return key, values
    if unit not in _UNITS:
        raise InputError(f"{path}: channel {ch.name!r} ({sig}) has unit {ch.unit!r}, which "
                         f"vidiscover does not convert; set its {lab.unit_field} to "
                         f"{_UNITS_TEXT[want]}, or convert the channel")
    quantity, factor = _UNITS[unit]
    if quantity == "voltage" and sig != "t":
        return f"{sig}_mV", values * factor
    if quantity != want:
        raise InputError(f"{path}: channel {ch.name!r} has unit {ch.unit!r} ({quantity}) but "
                         f"is mapped to {sig} ({checks.SIGNALS[sig]}); map a {want} channel: "
                         f"--channels {sig}=NAME")
    return sig, values * factor


def _time_factor(path: Path, ch: _Channel) -> float:
    unit = _norm_unit(ch.time_unit)
    if not unit:
        return 1.0
    quantity, factor = _UNITS.get(unit, ("", 0.0))
    if quantity != "time":
        raise InputError(f"{path}: channel {ch.name!r} has a time axis in {ch.time_unit!r}, "
                         "not s or ms; export the time history")
    return factor


def _time_axis(path: Path, chosen: dict[str, _Channel], n: int) -> np.ndarray:
    """Time of the samples from the channels' waveform properties or abscissa."""
    ref = chosen.get("x") or chosen["x_mV"]
    if ref.times is not None:
        return ref.times * _time_factor(path, ref)
    if ref.step is None:
        raise InputError(f"{path}: no time axis: no channel 't' and channel {ref.name!r} "
                         "has no sampling step (wf_increment); add a time channel or map one "
                         "with --channels t=NAME")
    steps = {}
    for key, ch in chosen.items():
        if ch.step is not None and ch.times is None:
            steps[ch.name] = (key.removesuffix("_mV"), ch.step * _time_factor(path, ch))
    step = ref.step * _time_factor(path, ref)
    if any(abs(s - step) > _STEP_RTOL * step for _, s in steps.values()):
        text = ", ".join(f"{sig} {name!r}: {1 / s:.6g} Hz" for name, (sig, s) in steps.items())
        raise InputError(f"{path}: channels sampled at different rates ({text}); resample them "
                         "to one rate")
    return ref.start * _time_factor(path, ref) + np.arange(n) * step


def read_lab(path: Path, data: bytes,
             channels: Mapping[str, str] | None = None) -> checks.RawTable:
    """Read a TDMS or UFF 58 file into the table the common checks expect.

    Parameters
    ----------
    path : Path
        The file (``.tdms``, ``.uff`` or ``.unv``), for messages and for pyuff.
    data : bytes
        Its content.
    channels : mapping, optional
        ``{our name: channel name}``; default: channels named ``x, a, xe`` (``t`` or
        ``time``), case-insensitive. A TDMS channel may be named ``GROUP/NAME``.

    Returns
    -------
    RawTable
        Columns ``t`` and ``x``/``x_mV``, ``a``/``a_mV``, ``xe``/``xe_mV`` as the
        channels' units say, in s, m, m/s^2 or mV.

    Raises
    ------
    InputError
        The library is missing, the file is truncated or corrupted, a channel is
        missing (the message lists the file's channels), a unit is unknown or does
        not fit, channels differ in length or sampling rate, or there is no time axis.
    """
    channels = check_channels(channels)
    fmt = path.suffix.lower()
    lab = _read_tdms(path, data) if fmt == ".tdms" else _read_uff(path, data)
    chosen = _resolve(path, lab, channels)
    cols: dict[str, np.ndarray] = {}
    for key, ch in chosen.items():
        name, values = _convert(path, lab, key, ch)
        cols[name] = values
    sizes = {f"{ch.name!r}": ch.values.size for ch in chosen.values()}
    if len(set(sizes.values())) > 1:
        text = ", ".join(f"{k}: {v}" for k, v in sizes.items())
        raise InputError(f"{path}: channels have different lengths ({text}); the file looks "
                         "truncated or its channels were sampled differently: copy/export it "
                         "again or resample")
    n = next(iter(sizes.values()))
    if "t" not in cols:
        cols = {"t": _time_axis(path, chosen, n), **cols}
    return checks.RawTable(path, list(cols), lambda raw, names: {c: cols[c] for c in names})
