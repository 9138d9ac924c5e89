"""Command-level workflows shared by the CLI, the demo and the notebooks."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from .effects import Effects
from .errors import InputError
from .params import SystemParams

__all__ = ["simulate_recording", "simulate_to_memory"]

SUFFIXES = (".csv", ".parquet", ".npz")


def simulate_to_memory(params: SystemParams, effects: Effects | Iterable[str] = (),
                       seed: int = 0, settle: float = 20.0, duration: float = 5.12,
                       noise: float = 1.0, units: str = "SI", name: str = "simulated"):
    """Simulate, label and record in memory.

    Returns
    -------
    recording : Recording
    truth : dict
        Ground truth including ``regime`` (label and the quantities behind it).
    result : SimulationResult
    """
    from .regimes.labels import label_simulation
    from .sensors import SensorConfig, record
    from .simulation import simulate

    fx = effects if isinstance(effects, Effects) else Effects.parse(list(effects))
    if noise < 0:
        raise InputError(f"--noise must be >= 0 (a scale factor), was {noise!r}")
    result = simulate(params, fx, settle=settle, duration=duration)
    rec, truth = record(result, SensorConfig().scaled_noise(noise), seed=seed, units=units,
                        name=name)
    truth["regime"] = label_simulation(result, rec.sample_rate).to_dict()
    return rec, truth, result


def simulate_recording(params: SystemParams, effects: Effects | Iterable[str], out: Path,
                       **kw) -> dict:
    """Simulate and write ``out`` (+ ``.json`` metadata, ``.truth.json``); return a summary."""
    from .io import write_recording

    out = Path(out)
    if out.suffix.lower() not in SUFFIXES:
        raise InputError(f"--out {out}: unknown format '{out.suffix}'; use one of "
                         f"{', '.join(SUFFIXES)}")
    rec, truth, result = simulate_to_memory(params, effects, name=out.stem, **kw)
    files = write_recording(rec, out, truth=truth)
    sides = [i["side"] for i in truth["impacts"]]
    return {
        "files": [str(f) for f in files],
        "impacts": {"n": len(sides), "right": sides.count("right"),
                    "left": sides.count("left"),
                    "t": [i["t"] for i in truth["impacts"]], "side": sides},
        "regime": truth["regime"],
        "effects": result.effects.to_dict(),
        "effects_text": result.effects.describe(),
        "params": params.to_dict(),
        "status": result.status,
        "message": result.message,
    }
