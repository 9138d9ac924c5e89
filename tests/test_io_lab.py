"""Lab file formats (TDMS, UFF 58), channel mapping and their one-line errors.

The files are written by each library's own writer (npTDMS ``TdmsWriter``, pyuff
``UFF.write_sets``) from a simulated recording. Tolerances: TDMS keeps float64, so a
TDMS recording in SI equals the written values to the last bit and the time axis
rebuilt from ``wf_increment`` to 1e-15 of the record length; a unit conversion
(mm, g, mV) costs a few ulps (tested at 1e-14); pyuff writes 12 significant digits
in ASCII (tested at 1e-11, as CSV in tests/test_io.py).
"""

import dataclasses
import json
import sys

import numpy as np
import pytest
from click.testing import CliRunner

import vidiscover
from vidiscover import io as vio
from vidiscover.cli import main
from vidiscover.errors import InputError
from vidiscover.io import read_recording, write_recording
from vidiscover.params import G_ACCEL

nptdms = pytest.importorskip("nptdms")
pyuff = pytest.importorskip("pyuff")


@pytest.fixture(scope="module")
def simulated():
    """A short simulated recording (1.5 s at 6400 Hz) in SI."""
    res = vidiscover.simulate(vidiscover.preset("paper", b=0.009), settle=1.0, duration=1.5)
    return vidiscover.record(res, seed=0)[0]


def assert_single_line_error(err: pytest.ExceptionInfo, *parts: str) -> None:
    msg = str(err.value)
    assert "\n" not in msg and "\r" not in msg, msg
    for part in parts:
        assert part in msg, msg


def write_meta(rec, path):
    """The recording's metadata as the sidecar of ``path`` (rec.json)."""
    path.with_suffix(".json").write_text(json.dumps(rec.meta.to_dict()))


def write_tdms(path, rec, chans, *, group="Rig", waveform=True, extra=()):
    """``chans``: (name, values, unit) of one group, with waveform timing properties."""
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    step = float(rec.t[1] - rec.t[0])
    objs = [RootObject(), GroupObject(group)]
    for name, values, unit in chans:
        props = {"unit_string": unit} if unit is not None else {}
        if waveform:
            props.update(wf_increment=step, wf_start_offset=float(rec.t[0]))
        objs.append(ChannelObject(group, name, np.asarray(values), properties=props))
    objs.extend(extra)
    with TdmsWriter(str(path)) as writer:
        writer.write_segment(objs)
    write_meta(rec, path)
    return path


def write_uff(path, rec, chans):
    """``chans``: (id1, values, ordinate unit label, data-type code) as datasets 58."""
    sets = [pyuff.prepare_58(binary=0, id1=name, func_type=1, rsp_node=k + 1, rsp_dir=1,
                             ref_node=0, ref_dir=0, data=np.asarray(values, dtype=float),
                             x=rec.t, abscissa_spacing=1, abscissa_spec_data_type=17,
                             abscissa_axis_units_lab="s", ordinate_spec_data_type=code,
                             ordinate_axis_units_lab=unit, orddenom_spec_data_type=0,
                             z_axis_spec_data_type=0)
            for k, (name, values, unit, code) in enumerate(chans)]
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    write_meta(rec, path)
    return path


def si_channels(rec):
    return [("x", rec.x, "m"), ("a", rec.a, "m/s^2"), ("xe", rec.xe, "m")]


def assert_close(back, rec, rtol, signals=("x", "a", "xe")):
    for s in signals:
        ref = getattr(rec, s)
        err = np.max(np.abs(getattr(back, s) - ref)) / np.max(np.abs(ref))
        assert err <= rtol, (s, err)
    assert np.max(np.abs(back.t - rec.t)) <= 1e-15 * rec.t[-1]


# ============================================================================ TDMS
def test_tdms_round_trip_equals_the_csv_reading(tmp_path, simulated):
    rec = simulated
    back = read_recording(write_tdms(tmp_path / "rec.tdms", rec, si_channels(rec)))
    write_recording(rec, tmp_path / "ref.csv")
    ref = read_recording(tmp_path / "ref.csv")
    assert_close(back, rec, 0.0)                     # float64 kept
    assert_close(back, ref, 1e-11)                   # = CSV within its 12 digits
    assert back.meta.sample_rate == pytest.approx(rec.meta.sample_rate, rel=1e-12)
    assert back.meta.extra["units"] == "SI" and back.name == "rec"


def test_tdms_units_mm_g_and_mv_are_converted(tmp_path, simulated):
    rec = simulated
    sens = {"x_mV_per_mm": 10000.0, "xe_mV_per_mm": 8000.0, "a_mV_per_g": 50.34}
    rec = dataclasses.replace(rec, meta=dataclasses.replace(rec.meta, sensitivity=sens))
    chans = [("X", rec.x * 1e3, "mm"), ("A", rec.a / G_ACCEL, "g"),
             ("XE", rec.xe * 1e3 * sens["xe_mV_per_mm"] / 1e3, "V")]
    back = read_recording(write_tdms(tmp_path / "rec.tdms", rec, chans))
    assert_close(back, rec, 1e-14)
    assert back.meta.extra["units"] == "mV"          # a channel came in volts


def test_tdms_time_channel_in_ms(tmp_path, simulated):
    rec = simulated
    chans = [("Time", rec.t * 1e3, "ms"), *si_channels(rec)]
    back = read_recording(write_tdms(tmp_path / "rec.tdms", rec, chans, waveform=False),
                          channels={"t": "Time"})
    assert_close(back, rec, 0.0)


def test_tdms_channel_mapping_with_groups(tmp_path, simulated):
    from nptdms import ChannelObject, GroupObject

    rec = simulated
    other = [GroupObject("Spare"), ChannelObject("Spare", "Laser", rec.x * 0 + 1.0)]
    chans = [("Laser", rec.x, "m"), ("Accel", rec.a, "m/s^2"), ("Base", rec.xe, "m")]
    path = write_tdms(tmp_path / "rec.tdms", rec, chans, extra=other)
    back = read_recording(path, channels={"x": "Rig/Laser", "a": "accel", "xe": "Base"})
    assert_close(back, rec, 0.0)
    with pytest.raises(InputError) as err:           # 'Laser' is in two groups
        read_recording(path, channels={"x": "Laser", "a": "Accel", "xe": "Base"})
    assert_single_line_error(err, "'Rig/Laser'", "'Spare/Laser'", "--channels x=NAME")


def test_tdms_missing_channel_lists_the_channels(tmp_path, simulated):
    rec = simulated
    chans = [("Laser", rec.x, "m"), ("Accel", rec.a, "m/s^2"), ("Base", rec.xe, "m")]
    path = write_tdms(tmp_path / "rec.tdms", rec, chans)
    with pytest.raises(InputError) as err:
        read_recording(path)
    assert_single_line_error(err, "no channel for 'x'", "'Laser', 'Accel', 'Base'",
                             "--channels x=NAME,a=NAME,xe=NAME")
    with pytest.raises(InputError) as err:
        read_recording(path, channels={"x": "Lasr", "a": "Accel", "xe": "Base"})
    assert_single_line_error(err, "x=Lasr", "no channel 'Lasr'", "'Laser', 'Accel', 'Base'")


def test_tdms_unknown_or_misfit_unit(tmp_path, simulated):
    rec = simulated
    chans = [("x", rec.x, "furlong"), ("a", rec.a, "m/s^2"), ("xe", rec.xe, "m")]
    with pytest.raises(InputError) as err:
        read_recording(write_tdms(tmp_path / "rec.tdms", rec, chans))
    assert_single_line_error(err, "channel 'x'", "'furlong'", "unit_string", "mm")
    chans = [("x", rec.x, "m"), ("a", rec.a, "mm"), ("xe", rec.xe, "m")]
    with pytest.raises(InputError) as err:
        read_recording(write_tdms(tmp_path / "rec.tdms", rec, chans))
    assert_single_line_error(err, "channel 'a'", "'mm' (length)", "--channels a=NAME")


def test_tdms_channels_of_different_length(tmp_path, simulated):
    rec = simulated
    chans = [("x", rec.x, "m"), ("a", rec.a[:-5], "m/s^2"), ("xe", rec.xe, "m")]
    with pytest.raises(InputError) as err:
        read_recording(write_tdms(tmp_path / "rec.tdms", rec, chans))
    n = rec.t.size
    assert_single_line_error(err, "different lengths", f"'x': {n}", f"'a': {n - 5}")


def test_tdms_channels_at_different_rates(tmp_path, simulated):
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    rec = simulated
    step = float(rec.t[1] - rec.t[0])
    path = tmp_path / "rec.tdms"
    with TdmsWriter(str(path)) as writer:
        writer.write_segment([RootObject(), GroupObject("G")] + [
            ChannelObject("G", s, getattr(rec, s), properties={"wf_increment": step * k})
            for s, k in (("x", 1), ("a", 2), ("xe", 1))])
    write_meta(rec, path)
    with pytest.raises(InputError) as err:
        read_recording(path)
    assert_single_line_error(err, "different rates", "6400 Hz", "3200 Hz")


@pytest.mark.parametrize("cut", [0.5, 0.9999, 0.001])
def test_tdms_truncated_or_corrupted(tmp_path, simulated, cut):
    rec = simulated
    path = write_tdms(tmp_path / "rec.tdms", rec, si_channels(rec))
    data = path.read_bytes()
    path.write_bytes(data[:max(1, int(len(data) * cut))])
    with pytest.raises(InputError) as err:
        read_recording(path)
    assert_single_line_error(err, "not a readable TDMS file, truncated or corrupted",
                             "copy/export it again")


def test_tdms_garbage_is_corrupted(tmp_path, simulated):
    path = tmp_path / "rec.tdms"
    path.write_bytes(b"not a tdms file " * 64)
    write_meta(simulated, path)
    with pytest.raises(InputError) as err:
        read_recording(path)
    assert_single_line_error(err, "not a readable TDMS file", "ValueError")


def test_missing_library_says_how_to_install(tmp_path, simulated, monkeypatch):
    path = write_tdms(tmp_path / "rec.tdms", simulated, si_channels(simulated))
    monkeypatch.setitem(sys.modules, "nptdms", None)       # import nptdms -> ImportError
    with pytest.raises(InputError) as err:
        read_recording(path)
    assert_single_line_error(err, "reading .tdms needs npTDMS",
                             "pip install 'vidiscover[formats]'")


def test_lab_formats_are_read_only(tmp_path, simulated):
    with pytest.raises(InputError) as err:
        write_recording(simulated, tmp_path / "rec.tdms")
    assert_single_line_error(err, "does not write", ".csv")
    assert list(tmp_path.iterdir()) == []


# ============================================================================ UFF 58
@pytest.mark.parametrize("suffix", [".uff", ".unv"])
def test_uff_round_trip_equals_the_csv_reading(tmp_path, simulated, suffix):
    rec = simulated
    chans = [("x", rec.x, "m", 8), ("a", rec.a, "m/s^2", 12), ("xe", rec.xe, "", 8)]
    back = read_recording(write_uff(tmp_path / f"rec{suffix}", rec, chans))
    write_recording(rec, tmp_path / "ref.csv")
    assert_close(back, read_recording(tmp_path / "ref.csv"), 1e-11)
    assert_close(back, rec, 1e-11)


def test_uff_units_and_mapping(tmp_path, simulated):
    rec = simulated
    chans = [("Laser", rec.x * 1e3, "mm", 8), ("Accel", rec.a / G_ACCEL, "g", 12),
             ("Base", rec.xe * 1e6, "um", 8)]
    back = read_recording(write_uff(tmp_path / "rec.uff", rec, chans),
                          channels={"x": "Laser", "a": "Accel", "xe": "Base"})
    assert_close(back, rec, 1e-11)


def test_uff_data_type_checks_a_unitless_channel(tmp_path, simulated):
    rec = simulated
    chans = [("x", rec.x, "", 8), ("a", rec.a, "", 8), ("xe", rec.xe, "", 8)]
    with pytest.raises(InputError) as err:
        read_recording(write_uff(tmp_path / "rec.uff", rec, chans))
    assert_single_line_error(err, "channel 'a' holds length", "--channels a=NAME")


def test_uff_errors(tmp_path, simulated):
    rec = simulated
    chans = [("x", rec.x, "m", 8), ("a", rec.a, "m/s^2", 12), ("Base", rec.xe, "m", 8)]
    path = write_uff(tmp_path / "rec.uff", rec, chans)
    with pytest.raises(InputError) as err:
        read_recording(path)
    assert_single_line_error(err, "no channel for 'xe'", "'x', 'a', 'Base'")
    chans = [("x", rec.x, "m", 8), ("a", rec.a, "m/s^2", 12), ("xe", rec.xe, "inch", 8)]
    path = write_uff(tmp_path / "rec.uff", rec, chans)
    with pytest.raises(InputError) as err:
        read_recording(path)
    assert_single_line_error(err, "channel 'xe'", "'inch'", "ordinate units label")
    data = path.read_bytes()
    for cut in (len(data) - 300, len(data) // 2):
        path.write_bytes(data[:cut])
        with pytest.raises(InputError) as err:
            read_recording(path)
        assert_single_line_error(err, "not a readable UFF file, truncated or corrupted")


def test_uff_channels_of_different_length(tmp_path, simulated):
    rec = simulated
    chans = [("x", rec.x, "m", 8), ("a", rec.a, "m/s^2", 12), ("xe", rec.xe[:-3], "m", 8)]
    path = write_uff(tmp_path / "rec.uff", rec, chans)
    with pytest.raises(InputError) as err:
        read_recording(path)
    assert_single_line_error(err, "different lengths", f"'xe': {rec.t.size - 3}")


# ============================================================================ mapping
@pytest.mark.parametrize("suffix", [".csv", ".parquet", ".npz"])
def test_channels_rename_columns_of_csv_parquet_npz(tmp_path, simulated, suffix):
    rec = simulated
    path = tmp_path / f"rec{suffix}"
    write_recording(rec, path)
    ref = read_recording(path)
    cols = {"t": rec.t, "Laser": rec.x, "x": rec.x * 0 + 7.0, "Acc": rec.a, "xe": rec.xe}
    vio._write_data(suffix, path.with_name(f"ren{suffix}"), cols, "SI")
    write_meta(rec, path.with_name(f"ren{suffix}"))
    back = read_recording(path.with_name(f"ren{suffix}"), channels={"x": "Laser", "a": "acc"})
    for s in ("t", "x", "a", "xe"):
        np.testing.assert_array_equal(getattr(back, s), getattr(ref, s))
    with pytest.raises(InputError) as err:
        read_recording(path.with_name(f"ren{suffix}"), channels={"x": "Lsr", "a": "Acc"})
    assert_single_line_error(err, "x=Lsr", "no column 'Lsr'", "'Laser'", "'Acc'")


@pytest.mark.parametrize("text, part", [
    ("x", "expected KEY=NAME"), ("y=Laser", "unknown signal 'y'"),
    ("x=Laser,x_mV=Other", "'x' is mapped twice"), ("x=A,a=A", "both name channel 'A'"),
    ("x=", "x needs a channel name"), ("x=A,x=B", "'x' is given twice")])
def test_parse_channels_errors(text, part):
    from vidiscover.io_lab import parse_channels

    with pytest.raises(InputError) as err:
        parse_channels(text)
    assert_single_line_error(err, "--channels", part)


@pytest.mark.parametrize("command", ["analyze", "classify", "gap", "discover"])
def test_cli_channels_reach_the_reader(tmp_path, simulated, monkeypatch, command):
    rec = simulated
    chans = [("Laser", rec.x, "m"), ("Accel", rec.a, "m/s^2"), ("Base", rec.xe, "m")]
    path = write_tdms(tmp_path / "rec.tdms", rec, chans)
    real, seen = vio.read_recording, []

    def spy(*args, **kwargs):            # read for real, then stop before the analysis
        seen.append(real(*args, **kwargs))
        raise InputError("STOP after reading")

    monkeypatch.setattr(vio, "read_recording", spy)
    args = [command, str(path), "--channels", "x=Laser,a=Accel,xe=Base"]
    if command != "classify":
        args += ["--out", str(tmp_path / "out")]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2, res.output
    assert res.stderr == "vidiscover: error: STOP after reading\n"
    assert_close(seen[0], rec, 0.0)


def test_cli_wrong_channel_and_malformed_option_are_one_line(tmp_path, simulated):
    rec = simulated
    path = write_tdms(tmp_path / "rec.tdms", rec, si_channels(rec))
    res = CliRunner().invoke(main, ["classify", str(path), "--channels", "x=Lasr"])
    assert res.exit_code == 2
    assert res.stderr.count("\n") == 1 and "its channels are 'x', 'a', 'xe'" in res.stderr
    res = CliRunner().invoke(main, ["classify", str(path), "--channels", "x:Laser"])
    assert res.exit_code == 2
    assert res.stderr.count("\n") == 1
    assert "--channels 'x:Laser': expected KEY=NAME" in res.stderr
