"""``vidiscover analyze REC... --out DIR``: impacts, ball motion, restitution, report.

For every recording it writes ``summary.json`` (the README's command table keys
``impacts.n``, ``impacts.t``, ``impacts.side``, ``restitution.{side}.rms``,
``restitution.{side}.n``, ``regime.label``, plus the friction table ``mu_table``
and, for simulated recordings, ``truth``), ``impacts.csv``, ``flights.csv``,
``figures/*.png`` and a self-contained ``report.html``.

With one recording the files go into ``DIR``; with several, into ``DIR/<stem>/``
(stems made unique with ``-2``, ``-3`` ...) plus ``DIR/index.html`` linking the
reports. Every recording is read and checked before anything is written, and the
whole output is written atomically: bad input leaves no directory behind.

The regime label (``regime.label``) comes from the regime classifier: the model
given with ``--model``, else the model shipped with vidiscover if one is installed;
without a model the label is null ("not classified"). ``regime.proba`` holds the
class probabilities and the classifier's out-of-domain warnings are added to
``warnings``.

``--json`` prints one JSON document: for one recording its summary (the content
of ``summary.json``) plus ``out`` (the directory) and ``files`` (written, relative
to ``out``); for several, a list of such documents in the order given.
"""

from __future__ import annotations

import math
from pathlib import Path

import click

from ..cli import (
    OUT_DIR_HELP,
    channels_option,
    check_out_dir,
    emit,
    handle_errors,
    recording_paths,
)
from ..errors import InputError

__all__ = ["analyze", "run_analyze", "human_lines"]


def _check_mu(mu: float) -> float:
    if not (math.isfinite(mu) and 0.0 <= mu <= 2.0):
        raise InputError(f"--mu must be in [0, 2] (friction coefficient between ball "
                         f"and LO), was {mu!r}")
    return float(mu)


def _unique_stems(paths: list[Path]) -> list[str]:
    from .._io_checks import stem_of

    seen: dict[str, int] = {}
    out = []
    for p in paths:
        stem = stem_of(p)
        k = seen.get(stem, 0) + 1
        seen[stem] = k
        out.append(stem if k == 1 else f"{stem}-{k}")
    return out


def load_inputs(paths, meta: Path | None, channels: dict | None = None) -> list:
    """Read every recording (and truth) before any work: bad input fails at once."""
    return [_load(Path(p), meta, channels) for p in paths]


def _load(path: Path, meta: Path | None, channels: dict | None = None):
    """(Recording, truth or None) of one file; every problem is an InputError."""
    from ..io import read_recording, read_truth, truth_path

    rec = read_recording(path, meta=meta, channels=channels)
    truth_file = truth_path(path)
    truth = read_truth(truth_file) if truth_file.is_file() else None
    return rec, truth


def read_flight_law(path: Path) -> tuple[float, float]:
    """``(mu, theta_deg)`` from a ``discovery.json`` written by ``vidiscover discover``.

    Raises
    ------
    InputError
        If the file is missing, not JSON, or has no identified flight law.
    """
    import json

    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(f"--flight-law {path}: no such file; pass the discovery.json "
                         "written by `vidiscover discover`") from None
    except (OSError, ValueError) as err:
        raise InputError(f"--flight-law {path}: not a readable JSON file ({err}); pass the "
                         "discovery.json written by `vidiscover discover`") from None
    fl = doc.get("flight") if isinstance(doc, dict) else None
    try:
        mu, theta = float(fl["mu"]), float(fl["theta_deg"])
    except (TypeError, KeyError, ValueError):
        raise InputError(f"--flight-law {path}: has no identified flight law (flight.mu, "
                         "flight.theta_deg); run `vidiscover discover` without "
                         "--no-flight") from None
    if not (math.isfinite(mu) and math.isfinite(theta)):
        raise InputError(f"--flight-law {path}: flight.mu/theta_deg are not finite numbers")
    return max(mu, 0.0), theta


def run_analyze(paths, out: Path, *, mu: float = 0.0, meta: Path | None = None,
                figures: bool = True, seed: int = 0, progress: bool = False,
                model=None, theta_deg: float = 0.0, loaded=None,
                channels: dict | None = None) -> list[dict]:
    """Analyse recordings and write their reports (the ``analyze`` command, in-process).

    Parameters
    ----------
    paths : sequence of path-like
        Recordings (CSV, Parquet or NPZ with a metadata sidecar or ``meta``).
    out : Path
        Output directory (one recording) or parent of one subdirectory per
        recording plus ``index.html`` (several).
    mu : float
        Friction coefficient assumed between ball and LO, in [0, 2].
    meta : Path, optional
        Metadata JSON for every recording (default: each recording's sidecar).
    figures : bool
        Render the figures.
    seed : int
        Seed of the bootstrap confidence intervals.
    progress : bool
        Show a progress bar on stderr (only with several recordings).
    model : RegimeModel, optional
        Regime classifier (anything with ``classify_analysis(result)`` returning
        ``label``, ``proba``, ``warnings``); None leaves ``regime.label`` null.
    theta_deg : float
        Inclination of the rig assumed for the flights (deg; > 0 pulls the ball
        towards the right wall).
    loaded : list of (Recording, GroundTruth or None), optional
        The recordings already read (by :func:`load_inputs`); the list is emptied
        (each recording is released once handed to the analysis).
    channels : dict, optional
        Our names -> the recordings' column/channel names (``--channels``).

    Returns
    -------
    list of dict
        Per recording: its summary plus ``out`` and ``files``.

    Raises
    ------
    InputError
        Bad ``mu``, unreadable recording, metadata or ground truth, an output path
        that is a file. Nothing is written then.
    """
    mu = _check_mu(mu)
    if not (math.isfinite(theta_deg) and abs(theta_deg) < 90):
        raise InputError(f"--theta must be in (-90, 90) degrees, was {theta_deg!r}")
    law = (mu, float(theta_deg)) if theta_deg else None
    paths = recording_paths(paths)
    out = check_out_dir(out)
    if loaded is None:
        loaded = load_inputs(paths, meta, channels)
    # heavy imports only once every input has been checked
    from tqdm.auto import tqdm

    from .._atomic import atomic_directory
    from ..analysis import analyze as analyze_recording
    from ..regimes.features import ALL_FEATURES
    from ..report import attach_regime, write_analysis, write_index

    # the inputs are handed over one by one and not kept, and their offsets are
    # removed in place: a second full copy of a large file would stay alive for
    # nothing (77 MB of a 200 MB CSV's peak)
    pending = [list(item) for item in loaded]
    loaded.clear()

    def one(k: int, target: Path) -> dict:
        truth = pending[k][1]
        result, regime = attach_regime(analyze_recording(pending[k].pop(0), mu=mu, seed=seed,
                                                         flight_law=law,
                                                         features=ALL_FEATURES,
                                                         overwrite=True), model)
        pending[k] = None
        written = write_analysis(result, target, figures=figures, truth=truth,
                                 regime=regime)
        return {**written["summary"], "out": str(target), "files": written["files"]}

    if len(paths) == 1:
        return [one(0, out)]
    docs = []
    stems = _unique_stems(paths)
    with atomic_directory(out) as tmp:
        bar = tqdm(list(enumerate(stems)), desc="analyze", unit="rec", disable=not progress)
        for k, stem in bar:
            bar.set_postfix_str(stem)
            doc = one(k, tmp / stem)
            doc["out"] = str(out / stem)
            docs.append(doc)
        write_index([{"href": f"{stem}/report.html", "summary": d}
                     for stem, d in zip(stems, docs, strict=True)], tmp,
                    title="vidiscover analyze")
    return docs


def _ci(w: dict) -> str:
    from ..report.html import interval_text

    if w.get("rms") is None:
        return "no usable impact"
    lo, hi = w.get("ci_low"), w.get("ci_high")
    if lo is None or hi is None or not hi > lo:
        return f"{w['rms']:.3f} (n = {w['n']})"
    return f"{interval_text(w['rms'], lo, hi)} (n = {w['n']})"


def human_lines(doc: dict) -> list[str]:
    """A few lines describing one analysed recording."""
    imp = doc["impacts"]
    rest = doc["restitution"]
    regime = doc.get("regime") or {}
    label = regime.get("label") or "not classified (no regime model installed)"
    if regime.get("label") and regime.get("proba"):
        label += f" (p = {regime['proba'].get(regime['label'], float('nan')):.2f})"
    truth = doc.get("truth")
    if truth and (truth.get("regime") or {}).get("label"):
        label += f" (simulated truth: {truth['regime']['label']})"
    lines = [f"{doc['recording']}: {imp['n']} impacts ({imp['right']} right, "
             f"{imp['left']} left) in {doc['duration']:g} s, mu = {doc['mu']:g}",
             f"  r right RMS {_ci(rest['right'])}; r left RMS {_ci(rest['left'])}",
             f"  regime: {label}"]
    if truth:
        tr = truth["restitution"]
        fmt = [f"{s} {tr[s]['rms']:.3f}" for s in ("right", "left")
               if tr[s].get("rms") is not None]
        if fmt:
            lines.append(f"  true r RMS: {', '.join(fmt)}")
    lines += [f"  warning: {w}" for w in doc.get("warnings") or []]
    lines.append(f"  written to {doc['out']}/ (report.html)")
    return lines


@click.command("analyze")
@click.argument("recordings", nargs=-1, required=True,
                type=click.Path(path_type=Path))
@click.option("--out", type=click.Path(path_type=Path), required=True,
              help="Output directory (one subdirectory per recording when several). "
                   f"{OUT_DIR_HELP}")
@click.option("--mu", type=float, default=0.0, show_default=True,
              help="Friction coefficient assumed between ball and LO (paper eq. 8).")
@click.option("--theta", type=float, default=0.0, show_default=True,
              help="Inclination of the rig (deg, > 0 pulls the ball right).")
@click.option("--flight-law", type=click.Path(path_type=Path), default=None,
              help="discovery.json from `vidiscover discover`: use its identified mu and "
                   "theta instead of --mu/--theta.")
@click.option("--meta", type=click.Path(path_type=Path), default=None,
              help="Metadata JSON, if not beside the recording (rec.json).")
@click.option("--model", "model_path", type=click.Path(path_type=Path), default=None,
              help="Regime model (.skops from `vidiscover train`) labelling the regime; "
                   "default: the model shipped with vidiscover, if installed.")
@channels_option
@click.option("--no-figures", is_flag=True, help="Skip the figures (faster).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the bootstrap confidence intervals.")
@click.option("--json", "as_json", is_flag=True,
              help="Print one JSON document: the summary (one recording) or a list of "
                   "summaries (several).")
@handle_errors
def analyze(recordings, out, mu, theta, flight_law, meta, model_path, channels, no_figures,
            seed, as_json):
    """Find impacts, reconstruct the ball, estimate restitution per wall, report.

    RECORDINGS are CSV/Parquet/NPZ files with columns t, x, a, xe (or TDMS/UFF 58
    files with such channels) and a metadata sidecar (rec.json). Writes
    summary.json, impacts.csv, flights.csv, figures/ and a self-contained
    report.html; a simulated recording's ground truth (rec.truth.json) is overlaid
    when present.
    """
    if flight_law is not None:
        mu, theta = read_flight_law(flight_law)
    _check_mu(mu)
    paths = recording_paths(recordings)
    check_out_dir(out)
    loaded = load_inputs(paths, meta, channels)     # reject bad files before the heavy imports
    if model_path is not None:
        from ..regimes.classifier import load_model

        model = load_model(model_path)
    else:
        from ..report import default_regime_model

        model = default_regime_model()
    docs = run_analyze(paths, out, mu=mu, meta=meta, figures=not no_figures,
                       seed=seed, theta_deg=theta, channels=channels,
                       progress=not as_json and len(paths) > 1, model=model, loaded=loaded)
    human = [line for d in docs for line in human_lines(d)]
    if len(docs) > 1:
        human.append(f"index: {Path(out) / 'index.html'}")
    emit(as_json, docs[0] if len(docs) == 1 else docs, "\n".join(human))
