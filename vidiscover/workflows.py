"""Command-level workflows shared by the CLI, the demo, sweeps, training and the gap.

The one chain ``simulate -> record -> label`` lives here: :func:`simulate_to_memory`
(and :func:`record_simulation` for a motion simulated already), so every caller
gets the same recording, ground truth and regime label for the same arguments.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from .effects import Effects
from .errors import InputError
from .params import SystemParams
from .recording import Recording
from .truth import GroundTruth

if TYPE_CHECKING:  # pragma: no cover
    from .sensors import SensorConfig
    from .simulation import SimOptions

__all__ = ["known_pulse", "Simulated", "record_simulation", "simulate_recording",
           "simulate_to_memory"]

SUFFIXES = (".csv", ".parquet", ".npz")


class Simulated(NamedTuple):
    """A simulated recording with its ground truth and the simulation behind it.

    A named tuple: ``rec, truth, result = simulate_to_memory(...)`` works too.

    Attributes
    ----------
    recording : Recording
        What the sensors recorded.
    truth : GroundTruth
        Ground truth, with its ``regime`` when labelled.
    result : SimulationResult
        The exact (or compliant-contact) motion.
    """

    recording: Recording
    truth: GroundTruth
    result: Any


def record_simulation(result, sensors: SensorConfig | None = None, *, seed: int = 0,
                      noise: float = 1.0, units: str = "SI", name: str = "simulated",
                      label: bool = True) -> Simulated:
    """Record a simulated motion through the sensor model and label its regime.

    Parameters
    ----------
    result : SimulationResult
        The motion; the record covers [settle, settle + duration].
    sensors : SensorConfig, optional
        Acquisition chain (default :class:`~vidiscover.sensors.SensorConfig`).
    seed : int
        Seed of the sensor noise.
    noise : float
        Scale factor of every noise level of ``sensors``.
    units : {"SI", "mV"}
        See :func:`vidiscover.sensors.record`.
    name : str
        Recording label.
    label : bool
        Attach the ground-truth regime (:func:`vidiscover.regimes.labels.label_simulation`
        at the recording's sampling rate).

    Returns
    -------
    Simulated
    """
    from .sensors import SensorConfig, record

    if not noise >= 0:
        raise InputError(f"--noise must be >= 0 (a scale factor), was {noise!r}")
    sensors = (sensors if sensors is not None else SensorConfig()).scaled_noise(noise)
    rec, truth = record(result, sensors, seed=seed, units=units, name=name)
    if label:
        from .regimes.labels import label_simulation

        truth = truth.with_regime(label_simulation(result, rec.sample_rate))
    return Simulated(rec, truth, result)


def simulate_to_memory(params: SystemParams, effects: Effects | Iterable[str] = (), *,
                       contact=None, sensors: SensorConfig | None = None,
                       options: SimOptions | None = None, seed: int = 0,
                       settle: float = 20.0, duration: float = 5.12, noise: float = 1.0,
                       units: str = "SI", name: str = "simulated",
                       label: bool = True) -> Simulated:
    """Simulate, record and label in memory: the one ``simulate -> record -> label``.

    Parameters
    ----------
    params : SystemParams
        The rig.
    effects : Effects or iterable of str
        Switched-on effects (CLI syntax accepted).
    contact : ContactModel, str or list of str, optional
        Compliant walls (:func:`vidiscover.simulation.simulate`); None: the exact
        engine.
    sensors : SensorConfig, optional
        Acquisition chain (default :class:`~vidiscover.sensors.SensorConfig`).
    options : SimOptions, optional
        Other simulation options (initial state, event bounds...); ``settle`` and
        ``duration`` always come from the arguments below.
    seed : int
        Seed of the sensor noise.
    settle, duration : float
        Simulated time before the record and record length (s).
    noise : float
        Scale factor of every noise level of ``sensors``.
    units : {"SI", "mV"}
        See :func:`vidiscover.sensors.record`.
    name : str
        Recording label.
    label : bool
        Attach the ground-truth regime label to ``truth``.

    Returns
    -------
    Simulated
        ``recording``, ``truth`` (:class:`~vidiscover.truth.GroundTruth`) and
        ``result`` (the simulation).

    Examples
    --------
    >>> from vidiscover.params import preset
    >>> sim = simulate_to_memory(preset("paper", b=0.009), settle=2.0, duration=1.0)
    >>> sim.truth.impacts.n > 0, sim.truth.label is not None
    (True, True)
    """
    from .simulation import simulate

    fx = effects if isinstance(effects, Effects) else Effects.parse(list(effects))
    if not noise >= 0:
        raise InputError(f"--noise must be >= 0 (a scale factor), was {noise!r}")
    kw = {} if contact is None else {"contact": contact}
    result = simulate(params, fx, options, settle=settle, duration=duration, **kw)
    return record_simulation(result, sensors, seed=seed, noise=noise, units=units, name=name,
                             label=label)


def simulate_recording(params: SystemParams, effects: Effects | Iterable[str], out: Path,
                       **kw) -> dict:
    """Simulate and write ``out`` (+ ``.json`` metadata, ``.truth.json``); return a summary.

    Keyword arguments go to :func:`simulate_to_memory`.
    """
    from .io import write_recording

    out = Path(out)
    if out.suffix.lower() not in SUFFIXES:
        raise InputError(f"--out {out}: unknown format '{out.suffix}'; use one of "
                         f"{', '.join(SUFFIXES)}")
    rec, truth, result = simulate_to_memory(params, effects, name=out.stem, **kw)
    files = write_recording(rec, out, truth=truth)
    sides = truth.impacts.side.tolist()
    return {
        "files": [str(f) for f in files],
        "impacts": {"n": len(sides), "right": sides.count("right"),
                    "left": sides.count("left"), "t": truth.impacts.t.tolist(),
                    "side": sides},
        "regime": truth.regime,
        "effects": result.effects.to_dict(),
        "effects_text": result.effects.describe(),
        "params": params.to_dict(),
        "status": result.status,
        "message": result.message,
    }


def known_pulse(sensors: SensorConfig | None = None, effects: Effects | None = None,
                contact=None):
    """The pulse response of a simulated acquisition chain, when it is known exactly.

    Recordings vidiscover simulates itself (sweeps, training sets, the simulated side
    of the gap) need not learn their instrument: the analysis is given it. Returns
    None (learn it from the recording) for compliant walls, whose contact pulse
    depends on the impact, and for a mounted accelerometer resonance, which the pulse
    models do not describe.
    """
    from .analysis.pulse import PulseModel
    from .sensors import SensorConfig

    sensors = sensors if sensors is not None else SensorConfig()
    if contact is not None or sensors.mount_resonance is not None:
        return None
    tau = effects.tau if effects is not None else 0.0
    if sensors.anti_alias == "linear-phase":
        return PulseModel(cutoff=sensors.fc / sensors.sample_rate,
                          halfwidth=sensors.kernel_halfwidth, tau=tau)
    return PulseModel(cutoff=sensors.fc / sensors.sample_rate, tau=tau,
                      kind=sensors.anti_alias, order=sensors.aa_order)
