"""The ``vidiscover`` command line.

Heavy packages (numpy, scipy, matplotlib, pysindy, scikit-learn) are imported inside
the commands, so ``vidiscover --help`` starts fast. Every command takes ``--json``
(one JSON document on stdout) and exits with status 2 on bad input, printing one
line on stderr and leaving no half-written output.
"""

from __future__ import annotations

import functools
import json
import os
import sys
from pathlib import Path

import click

from ._interrupt import in_cleanup, interrupted, mark_interrupted
from .errors import InputError
from .params import PRESETS

__all__ = ["main"]

#: After a Ctrl-C, the KeyboardInterrupt is raised again this often (s) until the
#: command stops, in case a library swallowed it.
REPEAT_S = 0.25

PAPER_CLEARANCES_MM = (6.0, 7.5, 9.0, 15.0, 17.5)
#: Restitution the paper reports at b = 9 mm (Table 2, mu = 0), used by the demo.
PAPER_EFFECTS = ("asymmetric_restitution=0.8782,0.2018",)


def _fail(message: str) -> None:
    click.echo(f"vidiscover: error: {message}", err=True)
    sys.exit(2)


def handle_errors(func):
    """One line + exit 2 for :class:`InputError` and missing files.

    Ctrl-C is left to the command group (:class:`LazyGroup`), which reports it and
    exits with 130 whether it arrives inside a command or while one is imported;
    outputs are written atomically (:mod:`vidiscover._atomic`), so an interrupted
    command leaves neither output nor temporary files behind.
    """

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except InputError as err:
            _fail(str(err))
        except FileNotFoundError as err:
            _fail(f"{err.filename}: no such file; check the path")

    return wrapper


def emit(as_json: bool, payload: dict, human: str) -> None:
    """Print ``payload`` as JSON or ``human`` as text."""
    if as_json:
        from ._atomic import to_jsonable

        click.echo(json.dumps(to_jsonable(payload), indent=2))
    else:
        click.echo(human)


#: Appended to the help of every ``--out`` that names an output folder.
OUT_DIR_HELP = ("Replaced as a whole if vidiscover wrote it before; refused if it holds "
                "other files.")


def check_out_dir(out) -> Path:
    """``--out`` as a Path, refused in one line unless the command may write it.

    A directory may be written when it is new, empty or an earlier output of
    vidiscover (replaced as a whole); a file, a folder holding other files or an
    unwritable location is refused. Commands call this before any work so that a bad
    ``--out`` fails at once, not after minutes of computation; the writer
    (:func:`vidiscover._atomic.atomic_directory`) checks again when it writes.
    """
    from ._atomic import check_output_dir

    try:
        return check_output_dir(out)
    except InputError as err:
        raise InputError(f"--out {err}") from None


def check_out_file(out) -> Path:
    """``--out`` of a command writing files (not a folder), checked before any work."""
    from ._atomic import check_writable

    out = Path(out)
    if out.is_dir():
        raise InputError(f"--out {out}: is a directory; give a file name, e.g. {out}/rec.csv")
    try:
        check_writable(out)
    except InputError as err:
        raise InputError(f"--out {err}") from None
    return out


def recording_paths(paths) -> list[Path]:
    """The RECORDINGS arguments as Paths; one-line error when there are none."""
    paths = [Path(p) for p in paths]
    if not paths:
        raise InputError("no recording given; pass one or more recording files")
    return paths


def _parse_channels_option(ctx, param, value):
    """``--channels`` as ``{our name: channel name}``; one line + exit 2 when malformed."""
    if value is None:
        return None
    from .io_lab import parse_channels

    try:
        return parse_channels(value)
    except InputError as err:
        _fail(str(err))


def channels_option(func):
    """The ``--channels x=NAME,a=NAME,xe=NAME`` option of the commands that read recordings."""
    return click.option(
        "--channels", default=None, metavar="x=NAME,a=NAME,xe=NAME",
        callback=_parse_channels_option,
        help="Which columns/channels of the recording hold x, a, xe (and t), e.g. "
             "x=Laser,a=Accel,xe=Base; x_mV=NAME for a channel in mV. A TDMS channel may "
             "be GROUP/NAME. Default: those named x, a, xe. Lab files' units are read "
             "from the file.")(func)


def _fmt(value, digits: int = 3) -> str:
    """A number for human output ('n/a' for None/NaN)."""
    if value is None or value != value:
        return "n/a"
    return f"{value:.{digits}f}"


def parse_assignments(items, option: str) -> dict[str, float]:
    """``NAME=VALUE`` option values as ``{name: float}``, with one-line errors.

    >>> parse_assignments(["m2=0.05", "b = 0.009"], "--param")
    {'m2': 0.05, 'b': 0.009}
    """
    out: dict[str, float] = {}
    for item in items:
        name, eq, value = item.partition("=")
        if not eq:
            raise InputError(f"{option} {item!r}: expected NAME=VALUE, e.g. {option} m2=0.05")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise InputError(f"{option} {item!r}: VALUE must be a number") from None
    return out


#: True in the ``vidiscover`` process itself (console script or ``python -m``), not
#: when the command line runs inside another program (tests, notebooks).
_OWN_PROCESS = [False]


def _exit_interrupted() -> None:
    """Report the interrupt and exit with status 130.

    In its own process the command line leaves at once (``os._exit`` after flushing):
    leaving through the interpreter's shutdown (library exit handlers, threads being
    joined) after an interrupt ended in death by SIGINT instead of 130 in about one try
    of five. Outputs are already removed by the atomic writers by then.
    """
    click.echo("vidiscover: interrupted; no output was written", err=True)
    if _OWN_PROCESS[0]:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(130)
    sys.exit(130)


def entry() -> None:
    """The ``vidiscover`` console script: :func:`main` in a process of its own.

    A finished command leaves without the interpreter's teardown (:func:`_leave`).
    """
    import signal

    _OWN_PROCESS[0] = True
    try:
        main()
    except SystemExit as done:            # how click's main() always ends
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        _leave(done.code)
        raise
    finally:
        # the command is done (or its interrupt reported): a Ctrl-C during the
        # interpreter's shutdown must not turn its exit status into death by SIGINT
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def _leave(code) -> None:
    """Exit the finished command's process now with status ``code``.

    The exit handlers run (:mod:`atexit`: temporary folders, child processes) and the
    standard streams are flushed, then the process ends (``os._exit``) without the
    interpreter's teardown, which takes 0.3-0.9 s once numpy, pandas, scipy and
    scikit-learn are loaded (freeing every module's objects one by one) and changes
    nothing: every output file is closed by then. Returns (the caller exits the usual
    way) for a non-numeric status or while another non-daemon thread still runs.
    """
    import threading

    if not (code is None or isinstance(code, int)):
        return
    main_thread = threading.main_thread()
    if any(t is not main_thread and not t.daemon and t.is_alive()
           for t in threading.enumerate()):
        return
    import atexit

    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(code or 0)


class LazyGroup(click.Group):
    """A click group whose commands live in their own modules, imported on use.

    ``LAZY_COMMANDS`` maps a command name to ``"module:attribute"``; only the
    module of the command being run (or asked for help) is imported, so adding a
    command never slows ``vidiscover --help`` down.
    """

    def __init__(self, *args, lazy_commands: dict[str, str] | None = None, **kwargs):
        super().__init__(*args, **kwargs)
        self.lazy_commands = dict(lazy_commands or {})

    def list_commands(self, ctx):
        return sorted(set(super().list_commands(ctx)) | set(self.lazy_commands))

    def invoke(self, ctx):
        # Ctrl-C can land anywhere, also while a command module (and pandas, scipy
        # ...) is being imported, where a half-finished import may surface as some
        # other error. Whatever escapes after a SIGINT is reported as the interrupt.
        # Some libraries swallow the KeyboardInterrupt (an extension module's import
        # turns it into an ImportError that a fallback catches): after a Ctrl-C it is
        # raised again every REPEAT_S until the command stops.
        import signal

        exiting = []                           # the interrupt is being reported
        repeat = hasattr(signal, "setitimer")

        def on_repeat(signum, frame):
            if interrupted() and not exiting and not in_cleanup():
                raise KeyboardInterrupt

        def on_sigint(signum, frame):
            if interrupted() and (exiting or in_cleanup()):   # a second Ctrl-C: let the
                return                                         # cleanup or the exit end
            if not interrupted() and repeat:
                signal.signal(signal.SIGALRM, on_repeat)
                signal.setitimer(signal.ITIMER_REAL, REPEAT_S, REPEAT_S)
            mark_interrupted()                 # seen by _atomic before any commit
            raise KeyboardInterrupt

        try:
            previous = signal.signal(signal.SIGINT, on_sigint)
        except ValueError:                     # not the main thread: leave it be
            previous = None
        mark_interrupted(False)
        try:
            try:
                result = super().invoke(ctx)
            finally:
                if interrupted():
                    exiting.append(True)
                if interrupted() and repeat:   # no repeat from here on; a late one
                    signal.setitimer(signal.ITIMER_REAL, 0.0)   # is ignored
                    signal.signal(signal.SIGALRM, signal.SIG_IGN)
        except KeyboardInterrupt:
            mark_interrupted()                 # also one our handler did not raise
        except (Exception, SystemExit):        # e.g. a swallowed one turned "bad file"
            if not interrupted():
                raise
        finally:
            stopped = interrupted()
            mark_interrupted(False)
            if stopped:
                # exiting: a Ctrl-C a library held back and forwards late must not turn
                # exit status 130 into death by SIGINT
                signal.signal(signal.SIGINT, signal.SIG_IGN)
            elif previous is not None:
                signal.signal(signal.SIGINT, previous)
        if stopped:                            # (also when a library swallowed it)
            _exit_interrupted()
        return result

    def get_command(self, ctx, cmd_name):
        if cmd_name in self.lazy_commands:
            import importlib

            module, _, attr = self.lazy_commands[cmd_name].partition(":")
            return getattr(importlib.import_module(module), attr)
        return super().get_command(ctx, cmd_name)

    def format_commands(self, ctx, formatter):
        # Short help without importing every command module.
        rows = [(name, LAZY_HELP.get(name) or self._short_help(ctx, name))
                for name in self.list_commands(ctx)]
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def _short_help(self, ctx, name):
        cmd = super().get_command(ctx, name)
        return cmd.get_short_help_str(limit=200) if cmd is not None else ""


#: Commands defined outside this module: name -> "module:attribute".
LAZY_COMMANDS: dict[str, str] = {
    "analyze": "vidiscover.commands.analyze:analyze",
    "discover": "vidiscover.commands.discover:discover",
    "classify": "vidiscover.commands.regimes:classify",
    "train": "vidiscover.commands.regimes:train",
    "sweep": "vidiscover.commands.regimes:sweep",
    "gap": "vidiscover.commands.gap:gap",
    "gap-check": "vidiscover.commands.gap:gap_check",
    "orbits": "vidiscover.commands.orbits:orbits",
    "continue": "vidiscover.commands.orbits:continue_",
}

#: One-line help of the lazy commands (shown by ``vidiscover --help``).
LAZY_HELP: dict[str, str] = {
    "analyze": "Find impacts, reconstruct the ball, estimate restitution, report.",
    "discover": "Discover the flight law and the impact law per wall (pysindy).",
    "classify": "Label recordings by regime, with class probabilities.",
    "train": "Simulate a sweep, train and evaluate the regime classifier.",
    "sweep": "Sweep a parameter: table of regimes and a bifurcation diagram.",
    "gap": "Diagnose the sim-to-real gap of a recording against the nominal model.",
    "gap-check": "Validate the gap diagnosis on recordings with withheld effects.",
    "orbits": "Periodic impacting orbits of the exact model, with their stability.",
    "continue": "Follow orbit branches through a parameter, with their bifurcations.",
}


def _available_lazy() -> dict[str, str]:
    """Lazy commands whose module exists in this installation."""
    import importlib.util

    out = {}
    for name, target in LAZY_COMMANDS.items():
        if importlib.util.find_spec(target.partition(":")[0]) is not None:
            out[name] = target
    return out


@click.group(cls=LazyGroup, lazy_commands=None,
             context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="vidiscover")
def main() -> None:
    """Model discovery and regime classification of vibro-impact systems.

    A ball rattles inside a clearance of a linear oscillator driven by a shaker;
    vidiscover simulates such rigs, analyses their recordings (impacts, ball motion,
    restitution), discovers flight and impact laws, classifies regimes and
    diagnoses the sim-to-real gap. Start with `vidiscover demo`.

    Output folders (--out) are written whole or not at all: a folder that
    vidiscover wrote before is replaced as a whole (nothing of the earlier run
    survives), a new or empty one is created, and a folder holding other files is
    refused. Ctrl-C leaves no output (exit status 130).
    """


# --------------------------------------------------------------------------- simulate
#: Rig parameters that have their own option on ``simulate`` (besides ``--param``).
RIG_OPTIONS = {"m1": "LO mass (kg)", "m2": "ball mass (kg)", "c1": "LO damping (N s/m)",
               "k1": "LO stiffness (N/m)", "amplitude": "base amplitude (m)",
               "frequency": "drive frequency (Hz)"}


def _parse_params(preset_name: str, b: float | None, param: tuple[str, ...],
                  rig: dict | None = None):
    from .params import preset

    changes = parse_assignments(param, "--param")
    for name, value in (rig or {}).items():
        if value is not None:
            changes[name] = value
    if b is not None:
        changes["b"] = b
    return preset(preset_name, **changes)


def _mount_resonance(spec: str | None) -> dict:
    """``--mount-resonance HZ[:ZETA]`` as SensorConfig fields."""
    if spec is None:
        return {}
    hz, _, zeta = spec.partition(":")
    try:
        out = {"mount_resonance": float(hz)}
        if zeta:
            out["mount_zeta"] = float(zeta)
    except ValueError:
        raise InputError(f"--mount-resonance {spec!r}: expected HZ[:ZETA] with numbers, "
                         "e.g. --mount-resonance 12000:0.05") from None
    return out


_FULL_SCALE_KEYS = {"x": "x_full_scale", "xe": "xe_full_scale", "a": "a_full_scale"}
_SENSITIVITY_KEYS = ("x_mV_per_mm", "xe_mV_per_mm", "a_mV_per_g")


def sensor_config(*, sample_rate=None, anti_alias=None, a_bias=None, x_offset=None,
                  xe_offset=None, adc_bits=None, full_scale=(), mount_resonance=None,
                  sensitivity=(), noise: float = 1.0):
    """The instrument chain of the ``simulate`` options as a ``SensorConfig``.

    Options left at None keep the default sensor model's values (the paper's rig:
    6400 Hz, linear-phase anti-alias filter, no offsets, no quantisation).
    """
    from .sensors import SensorConfig

    fields: dict = {}
    if sample_rate is not None:
        fields["sample_rate"] = sample_rate
    if anti_alias is not None:
        fields.update(SensorConfig.parse_anti_alias(anti_alias))
    for name, value in (("a_bias", a_bias), ("x_offset", x_offset), ("xe_offset", xe_offset),
                        ("adc_bits", adc_bits)):
        if value is not None:
            fields[name] = value
    for key, value in parse_assignments(full_scale, "--full-scale").items():
        if key not in _FULL_SCALE_KEYS:
            raise InputError(f"--full-scale {key}=...: unknown channel; use x, xe or a "
                             "(e.g. --full-scale a=490)")
        fields[_FULL_SCALE_KEYS[key]] = value
    sens = parse_assignments(sensitivity, "--sensitivity")
    unknown = sorted(set(sens) - set(_SENSITIVITY_KEYS))
    if unknown:
        raise InputError(f"--sensitivity {unknown[0]}=...: unknown key; use "
                         f"{', '.join(_SENSITIVITY_KEYS)}")
    if sens:
        from .recording import PAPER_SENSITIVITY

        fields["sensitivity"] = {**PAPER_SENSITIVITY, **sens}
    fields.update(_mount_resonance(mount_resonance))
    if noise < 0:
        raise InputError(f"--noise must be >= 0 (a scale factor), was {noise!r}")
    return SensorConfig(**fields).scaled_noise(noise)


def _rig_option(name: str):
    return click.option(f"--{name}", name, type=float, default=None,
                        help=f"{RIG_OPTIONS[name]} (default: the preset's).")


def _rig_options(func):
    for name in reversed(list(RIG_OPTIONS)):
        func = _rig_option(name)(func)
    return func


@main.command()
@click.option("--preset", "preset_name", type=click.Choice(sorted(PRESETS)), default="paper",
              show_default=True, help="Parameter set (paper: Table 1 of Li et al. 2018).")
@click.option("--b", type=float, default=None,
              help="Nominal half-clearance in metres (e.g. 0.009 for 9 mm); "
                   "default: the preset's (paper: 0.0115).")
@_rig_options
@click.option("--param", multiple=True, metavar="NAME=VALUE",
              help="Change any parameter: m1, c1, k1, m2, b, amplitude, frequency, r.")
@click.option("--effect", multiple=True, metavar="NAME[=VALUE,...]",
              help="Switch on an effect, e.g. coulomb_friction=0.3, inclination=2, "
                   "asymmetric_restitution=0.88,0.2 (repeatable). Without values an effect "
                   "takes its defaults, e.g. coulomb_friction: mu = 0.1, inclination: 1 "
                   "deg (all listed in the README).")
@click.option("--contact", multiple=True, metavar="[SIDE=]KIND:KEY=VALUE,...",
              help="Compliant walls instead of instantaneous impacts: "
                   "kelvin-voigt:k=3e7,r=0.7 or hunt-crossley:k=1e9,alpha=0.3[,n=1.5] for "
                   "both walls, or right=... and left=... (repeat the option).")
@click.option("--anti-alias", "anti_alias", default=None, metavar="KIND[:ORDER:CUTOFF_HZ]",
              help="Anti-alias filter: linear-phase (default, delay-compensated), or causal "
                   "butter, bessel, cheby1 (0.5 dB ripple) of order 2-8, e.g. butter:4:2500.")
@click.option("--sample-rate", "sample_rate", type=float, default=None,
              help="Sampling rate in Hz (default 6400).")
@click.option("--a-bias", "a_bias", type=float, default=None,
              help="Accelerometer DC bias (m/s^2).")
@click.option("--x-offset", "x_offset", type=float, default=None,
              help="Laser zero offset (m): the LO at rest does not read 0.")
@click.option("--xe-offset", "xe_offset", type=float, default=None,
              help="Base-sensor zero offset (m).")
@click.option("--adc-bits", "adc_bits", type=int, default=None,
              help="Quantise each channel to 2^N levels over its full scale (and clip).")
@click.option("--full-scale", "full_scale", multiple=True, metavar="CHANNEL=VALUE",
              help="Full scale of a channel for --adc-bits: x=0.01, xe=0.01 (m), "
                   "a=490.5 (m/s^2, 50 g) by default.")
@click.option("--mount-resonance", "mount_resonance", default=None, metavar="HZ[:ZETA]",
              help="Accelerometer mounted resonance, e.g. 12000:0.05.")
@click.option("--sensitivity", multiple=True, metavar="KEY=VALUE",
              help="Sensor sensitivities for --units mV: x_mV_per_mm, xe_mV_per_mm, "
                   "a_mV_per_g (default: the paper's 10000, 10000, 50.34).")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the sensor noise.")
@click.option("--settle", type=float, default=20.0, show_default=True,
              help="Simulated time before the record starts (s).")
@click.option("--duration", type=float, default=5.12, show_default=True,
              help="Record length (s).")
@click.option("--noise", type=float, default=1.0, show_default=True,
              help="Scale factor of all sensor noise levels.")
@click.option("--units", type=click.Choice(["SI", "mV"]), default="SI", show_default=True,
              help="Write SI columns or raw sensor voltages (see --sensitivity).")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Recording to write (.csv, .parquet or .npz); metadata and ground "
                   "truth go beside it (rec.json, rec.truth.json).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document.")
@handle_errors
def simulate(preset_name, b, m1, m2, c1, k1, amplitude, frequency, param, effect, contact,
             anti_alias, sample_rate, a_bias, x_offset, xe_offset, adc_bits, full_scale,
             mount_resonance, sensitivity, seed, settle, duration, noise, units, out,
             as_json):
    """Simulate a rig and write a realistic recording plus its ground truth.

    Without --contact the impacts are instantaneous (exact event-driven engine);
    with it the walls are compliant (contacts of finite duration, integrated).
    The instrument options model the acquisition chain of a real rig.
    """
    from .workflows import simulate_recording

    out = check_out_file(out)
    rig = {"m1": m1, "m2": m2, "c1": c1, "k1": k1, "amplitude": amplitude,
           "frequency": frequency}
    params = _parse_params(preset_name, b, param, rig)
    contact_model = None
    if contact:
        from .simulation.contact import ContactModel

        contact_model = ContactModel.parse(list(contact))
    sensors = sensor_config(sample_rate=sample_rate, anti_alias=anti_alias, a_bias=a_bias,
                            x_offset=x_offset, xe_offset=xe_offset, adc_bits=adc_bits,
                            full_scale=full_scale, mount_resonance=mount_resonance,
                            sensitivity=sensitivity, noise=noise)
    summary = simulate_recording(params, effect, out, seed=seed, settle=settle,
                                 duration=duration, units=units, sensors=sensors,
                                 contact=contact_model)
    imp = summary["impacts"]
    engine = "exact" if contact_model is None else f"compliant ({contact_model.describe()})"
    human = (f"wrote {', '.join(summary['files'])}\n"
             f"{imp['n']} impacts ({imp['right']} right, {imp['left']} left) in "
             f"{duration:g} s; regime {summary['regime']['label']}; engine {engine}; "
             f"effects: {summary['effects_text']}")
    emit(as_json, summary, human)


# --------------------------------------------------------------------------- demo
@main.command()
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              default=Path("demo-output"), show_default=True,
              help=f"Output directory. {OUT_DIR_HELP}")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document.")
@handle_errors
def demo(out, seed, as_json):
    """Run the whole toolkit on the paper's clearances (6, 7.5, 9, 15, 17.5 mm)."""
    out = check_out_dir(out)               # before minutes of simulation
    from .demo import run_demo

    result = run_demo(out, seed=seed, progress=not as_json)
    lines = [f"demo: {len(result['outputs'])} files written to {out}/; open {result['index']}"]
    for r in result.get("recordings", []):
        lines.append(f"  {r['name']}: {r['detected']} impacts detected of "
                     f"{r['n_detectable']} detectable ({r['n_impacts']} true, the others "
                     f"below the noise), regime {r['regime_classified'] or 'n/a'} "
                     f"(true {r['regime']}); "
                     f"r right {_fmt(r['r_right_rms'])} (true {_fmt(r['r_right_true_rms'])}), "
                     f"r left {_fmt(r['r_left_rms'])} (true {_fmt(r['r_left_true_rms'])}) "
                     f"-> {r['report']}")
    human = "\n".join(lines)
    emit(as_json, result, human)


main.lazy_commands = _available_lazy()


if __name__ == "__main__":  # pragma: no cover
    entry()
