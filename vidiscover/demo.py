"""``vidiscover demo``: the toolkit end to end on the paper's clearances."""

from __future__ import annotations

from pathlib import Path

__all__ = ["run_demo", "DEMO_CLEARANCES_MM"]

#: Clearances studied in the paper (mm).
DEMO_CLEARANCES_MM = (6.0, 7.5, 9.0, 15.0, 17.5)
#: Restitution the paper reports at b = 9 mm (Table 2, mu = 0).
DEMO_EFFECTS = ("asymmetric_restitution=0.8782,0.2018",)


def run_demo(out: Path, seed: int = 0, progress: bool = True,
             clearances_mm: tuple[float, ...] = DEMO_CLEARANCES_MM, *,
             settle: float = 20.0, duration: float = 5.12, figures: bool = True) -> dict:
    """Simulate the paper presets, analyse each recording and write one report each.

    For every clearance b the demo writes the recording with its metadata and
    ground truth (``paper_b9mm.csv``, ``.json``, ``.truth.json``), a plot of the
    simulated signals (``paper_b9mm.png``) and the analysis of the recording as
    ``vidiscover analyze`` writes it (``paper_b9mm/summary.json``, ``impacts.csv``,
    ``flights.csv``, ``figures/``, ``report.html``, the truth overlaid; the regime
    labelled by the shipped classifier when one is installed), then ``index.html``
    linking the reports.

    Parameters
    ----------
    out : Path
        Output directory (written atomically: complete or untouched).
    seed : int
        Seed of the sensor noise (recording k uses ``seed + k``) and of the bootstrap.
    progress : bool
        Show a progress bar on stderr.
    clearances_mm : tuple of float
        Clearances b to simulate (mm).
    settle, duration : float
        Simulated time before the record and record length (s).
    figures : bool
        Render the report figures.

    Returns
    -------
    dict
        ``outputs`` (files written, relative to ``out``), ``recordings`` (one
        summary per clearance: true and estimated numbers, report path), ``index``
        and ``out``.
    """
    from tqdm.auto import tqdm

    from .analysis import analyze, detectable_truth
    from .io import atomic_directory, write_recording
    from .params import preset
    from .plotting import plot_recording
    from .regimes.features import ALL_FEATURES
    from .report import attach_regime, default_regime_model, write_analysis, write_index
    from .workflows import simulate_to_memory

    out = Path(out)
    model = default_regime_model()          # None until a regime model is installed
    outputs: list[str] = []
    recordings = []
    entries = []
    with atomic_directory(out) as tmp:
        bar = tqdm(clearances_mm, desc="demo", unit="rec", disable=not progress)
        for k, b_mm in enumerate(bar):
            stem = f"paper_b{b_mm:g}mm".replace(".", "p")
            bar.set_postfix_str(stem)
            rec, truth, _ = simulate_to_memory(preset("paper", b=b_mm / 1000), DEMO_EFFECTS,
                                               seed=seed + k, name=stem, settle=settle,
                                               duration=duration)
            files = write_recording(rec, Path(tmp) / f"{stem}.csv", truth=truth)
            plot_recording(rec, truth, Path(tmp) / f"{stem}.png")
            outputs += [Path(f).name for f in files] + [f"{stem}.png"]
            result, regime = attach_regime(analyze(rec, seed=seed, features=ALL_FEATURES), model)
            written = write_analysis(result, Path(tmp) / stem, truth=truth, figures=figures,
                                     regime=regime)
            outputs += [f"{stem}/{f}" for f in written["files"]]
            summary = written["summary"]
            entries.append({"href": f"{stem}/report.html", "summary": summary})
            rest = summary["restitution"]
            recordings.append({"name": stem, "b": b_mm / 1000,
                               "n_impacts": truth.impacts.n,
                               "n_detectable": int(detectable_truth(truth).sum()),
                               "regime": truth.label,
                               "regime_classified": summary["regime"]["label"],
                               "detected": summary["impacts"]["n"],
                               "r_right_rms": rest["right"]["rms"],
                               "r_left_rms": rest["left"]["rms"],
                               "r_right_true_rms": summary["truth"]["restitution"]["right"]["rms"],
                               "r_left_true_rms": summary["truth"]["restitution"]["left"]["rms"],
                               "report": f"{stem}/report.html"})
        write_index(entries, tmp, title="vidiscover demo: the paper's clearances")
        outputs.append("index.html")
    return {"outputs": outputs, "recordings": recordings, "index": str(out / "index.html"),
            "out": str(out)}
