"""``vidiscover demo``: the toolkit end to end on the paper's clearances."""

from __future__ import annotations

from pathlib import Path

__all__ = ["run_demo", "DEMO_CLEARANCES_MM"]

#: Clearances studied in the paper (mm).
DEMO_CLEARANCES_MM = (6.0, 7.5, 9.0, 15.0, 17.5)
#: Restitution the paper reports at b = 9 mm (Table 2, mu = 0).
DEMO_EFFECTS = ("asymmetric_restitution=0.8782,0.2018",)


def run_demo(out: Path, seed: int = 0, progress: bool = True,
             clearances_mm: tuple[float, ...] = DEMO_CLEARANCES_MM) -> dict:
    """Simulate the paper presets and write recordings, ground truth and plots.

    Parameters
    ----------
    out : Path
        Output directory (written atomically: complete or untouched).
    seed : int
        Seed of the sensor noise (recording k uses ``seed + k``).
    progress : bool
        Show a progress bar on stderr.
    clearances_mm : tuple of float
        Clearances b to simulate (mm).

    Returns
    -------
    dict
        ``outputs`` (files written, relative to ``out``) and ``recordings`` (one
        summary per clearance).
    """
    from tqdm.auto import tqdm

    from .io import atomic_directory, write_recording
    from .params import preset
    from .plotting import plot_recording
    from .workflows import simulate_to_memory

    out = Path(out)
    outputs: list[str] = []
    recordings = []
    with atomic_directory(out) as tmp:
        bar = tqdm(clearances_mm, desc="demo", unit="rec", disable=not progress)
        for k, b_mm in enumerate(bar):
            stem = f"paper_b{b_mm:g}mm".replace(".", "p")
            bar.set_postfix_str(stem)
            rec, truth, _ = simulate_to_memory(preset("paper", b=b_mm * 1e-3), DEMO_EFFECTS,
                                               seed=seed + k, name=stem)
            files = write_recording(rec, Path(tmp) / f"{stem}.csv", truth=truth)
            plot_recording(rec, truth, Path(tmp) / f"{stem}.png")
            outputs += [Path(f).name for f in files] + [f"{stem}.png"]
            recordings.append({"name": stem, "b": b_mm * 1e-3,
                               "n_impacts": len(truth["impacts"]),
                               "regime": truth["regime"]["label"]})
    return {"outputs": outputs, "recordings": recordings, "out": str(out)}
