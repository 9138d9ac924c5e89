"""``vidiscover discover REC... --out DIR``: flight law and impact law per wall.

All recordings are read and checked first, then analysed and pooled
(:func:`vidiscover.discovery.discover`); the output directory is written
atomically (bad input leaves nothing behind):

* ``discovery.json`` -- the summary (the README's command table keys ``flight.mu``,
  ``flight.theta_deg``, ``flight.terms``, ``impact_law.right.formula``,
  ``impact_law.left.formula``; ``flight.identified`` and ``flight.reason``, with
  ``flight.mu``/``theta_deg`` null when the law is not identified and the raw fit
  under ``flight.diagnostic_fit``, its leave-one-recording-out spread under
  ``flight.jackknife``; per wall ``terms``, ``coefficients``,
  ``speed_range``, ``effect``, ``effect_threshold``, ``band``, the candidate
  tables, the comparison with a constant r, warnings);
* ``equations.txt`` -- the discovered laws as text;
* ``impacts.csv`` -- the pooled impacts used per wall (speed, r, standard error);
* ``candidates_right.csv``, ``candidates_left.csv`` -- every impact-law candidate
  with its AICc, CV error and bootstrap selection frequency;
* ``flight_residuals.csv`` and ``figures/impact_laws.png``,
  ``figures/flight_residuals.png``.

``--json`` prints the summary plus ``out`` and ``files``.
"""

from __future__ import annotations

import math
from pathlib import Path

import click

from ..cli import (
    _OWN_PROCESS,
    OUT_DIR_HELP,
    channels_option,
    check_out_dir,
    emit,
    handle_errors,
    recording_paths,
)
from ..errors import InputError

__all__ = ["discover", "run_discover", "human_lines"]


def run_discover(paths, out: Path, *, mu: float = 0.0, meta: Path | None = None,
                 seed: int = 0, n_boot: int = 200, level: float = 0.95,
                 criterion: str = "aicc", min_effect: float | None = None,
                 max_tilt: float = 10.0, flight: bool = True, figures: bool = True,
                 progress: bool = False, channels: dict | None = None,
                 rising: bool = False, n_jobs: int | None = 1) -> dict:
    """Discover the laws of pooled recordings and write the results (in-process CLI).

    Parameters
    ----------
    paths : sequence of path-like
        Recordings (CSV, Parquet or NPZ with a metadata sidecar or ``meta``).
    out : Path
        Output directory (created atomically).
    mu : float
        Friction coefficient assumed by the analyses, in [0, 2].
    meta : Path, optional
        Metadata JSON for every recording (default: each recording's sidecar).
    seed : int
        Seed of the bootstraps and cross-validation splits.
    n_boot : int
        Bootstrap resamples of the flight and impact laws.
    level : float
        Level of the intervals and bands, in (0, 1).
    criterion : {"aicc", "cv"}
        Impact-law selection rule.
    min_effect : float, optional
        Smallest change of r over the observed speeds for a reported speed
        dependence (default: the calibrated
        :data:`~vidiscover.discovery.impact_law.MIN_EFFECT`).
    max_tilt : float
        Largest admissible |theta| of the flight law (deg).
    flight : bool
        Run the flight-law discovery.
    figures : bool
        Render the figures.
    progress : bool
        Show a progress bar on stderr.
    channels : dict, optional
        Our names -> the recordings' column/channel names (``--channels``).
    rising : bool
        Also report impact laws in which r rises with speed (``--rising``; they must
        then clear 4x the reporting threshold). Off by default: no contact law rises,
        while the systematic errors of slow impacts make r look as if it did.
    n_jobs : int or None
        Cores to use (``--n-jobs``; None: all): the recordings are analysed side by
        side in forked processes (Linux). Same results whatever the number.

    Returns
    -------
    dict
        The summary plus ``out`` and ``files`` (relative to ``out``).

    Raises
    ------
    InputError
        Bad options, unreadable recordings or metadata, an output path that is a
        file. Nothing is written then.
    """
    from .._workers import gc_paused, short_blas_spin

    if _OWN_PROCESS[0]:        # before numpy loads OpenBLAS: its idle threads sleep
        short_blas_spin()
    with gc_paused():      # not while the stack is imported (8 % less CPU)
        import pandas as pd

        from .._atomic import atomic_directory, write_json
        from ..discovery import discover as discover_laws
        from ..io import read_recording

    if not (math.isfinite(mu) and 0.0 <= mu <= 2.0):
        raise InputError(f"--mu must be in [0, 2] (friction coefficient between ball "
                         f"and LO), was {mu!r}")
    from ..discovery.impact_law import MIN_EFFECT

    if n_boot < 0:
        raise InputError(f"--n-boot must be >= 0, was {n_boot}")
    if not (math.isfinite(level) and 0.0 < level < 1.0):
        raise InputError(f"--level must be in (0, 1), e.g. 0.95, was {level!r}")
    min_effect = MIN_EFFECT if min_effect is None else min_effect
    if not (math.isfinite(min_effect) and min_effect >= 0):
        raise InputError(f"--min-effect must be >= 0 (smallest change of r), "
                         f"was {min_effect!r}")
    if not (math.isfinite(max_tilt) and 0.0 < max_tilt < 90.0):
        raise InputError(f"--max-tilt must be in (0, 90) degrees, was {max_tilt!r}")
    if seed < 0:
        raise InputError(f"--seed must be >= 0, was {seed}")
    if n_jobs is not None and n_jobs < 1:
        raise InputError(f"--n-jobs must be >= 1 (cores to use), was {n_jobs!r}")
    paths = recording_paths(paths)
    out = check_out_dir(out)
    # check all inputs first
    recordings = [read_recording(p, meta=meta, channels=channels) for p in paths]
    if _OWN_PROCESS[0]:        # the vidiscover process: as short-lived as its workers
        from ..discovery.pipeline import _worker_start

        _worker_start()
    result = discover_laws(recordings, mu=mu, seed=seed, n_boot=n_boot, level=level,
                           criterion=criterion, flight=flight, progress=progress,
                           min_effect=float(min_effect), max_tilt_deg=float(max_tilt),
                           impact_kws={"rising": True} if rising else None, n_jobs=n_jobs)
    doc = result.summary()
    files = ["discovery.json", "equations.txt", "impacts.csv", "candidates_right.csv",
             "candidates_left.csv", "flight_residuals.csv"]
    with atomic_directory(out) as tmp:
        (tmp / "equations.txt").write_text("\n".join(result.equations()) + "\n")
        pd.concat([d.assign(side=side) for side, d in result.impact_data.items()],
                  ignore_index=True).to_csv(tmp / "impacts.csv", index=False)
        for side, law in result.impact_laws.items():
            law.candidates.to_csv(tmp / f"candidates_{side}.csv", index=False)
        result.flight_residuals().to_csv(tmp / "flight_residuals.csv", index=False)
        if figures:
            from ..discovery.figures import write_figures

            (tmp / "figures").mkdir()
            files += [f"figures/{f}" for f in write_figures(result, tmp / "figures")]
        doc = {**doc, "out": str(out), "files": files}
        write_json(tmp / "discovery.json", doc)
    return doc


def _fmt(x, spec: str = ".3g") -> str:
    return "n/a" if x is None else format(x, spec)


def human_lines(doc: dict) -> list[str]:
    """Text report of a ``discover`` summary."""
    lines = [f"discover: {doc['n_recordings']} recording(s) pooled, mu assumed "
             f"{doc['mu_assumed']:g}"]
    lines += ["  " + e for e in doc["equations"]]
    fl = doc["flight"]
    if fl.get("identified"):
        lines.append(f"  flight: mu = {_fmt(fl['mu'], '.4g')} "
                     f"[{_fmt(fl['mu_ci'][0])}, {_fmt(fl['mu_ci'][1])}], theta = "
                     f"{_fmt(fl['theta_deg'], '.4g')} deg [{_fmt(fl['theta_ci'][0])}, "
                     f"{_fmt(fl['theta_ci'][1])}]")
    lo = fl.get("lo_friction")
    if lo and lo.get("identified"):
        lines.append(f"  friction from the LO's reaction: mu = {_fmt(lo['mu'])} +/- "
                     f"{_fmt(lo['mu_se'], '.2g')} (standard error; independent of the "
                     "pulse areas)")
    elif lo:
        lines.append(f"  friction from the LO's reaction: not identified ({lo['reason']})")
    for side in ("right", "left"):
        law = doc["impact_law"][side]
        cis = ", ".join(f"{t}: {_fmt(c['value'], '.4g')} [{_fmt(c['ci'][0], '.4g')}, "
                        f"{_fmt(c['ci'][1], '.4g')}]" for t, c in law["coefficients"].items())
        lines.append(f"  {side}: coefficients {cis or 'none'}")
        if law["alternative"]:
            lines.append(f"  {side}: vs constant r: dAICc = "
                         f"{_fmt(law['delta_aicc_vs_constant'])}, p = "
                         f"{_fmt(law['p_value_vs_constant'])} ({law['alternative']}); "
                         f"chosen in {_fmt(law['support_frequency'], '.0%')} of resamples")
    lines += [f"  warning: {w}" for w in doc["warnings"]]
    if "out" in doc:
        lines.append(f"  written to {doc['out']}")
    return lines


@click.command("discover")
@click.argument("recordings", nargs=-1, type=click.Path(path_type=Path))
@click.option("--out", type=click.Path(file_okay=False, path_type=Path), required=True,
              help=f"Output directory. {OUT_DIR_HELP}")
@click.option("--mu", type=float, default=0.0, show_default=True,
              help="Friction coefficient assumed by the analyses (paper eq. 8).")
@click.option("--meta", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Metadata JSON for every recording, if not beside it (rec.json).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the bootstraps and cross-validation splits.")
@click.option("--n-boot", type=int, default=200, show_default=True,
              help="Bootstrap resamples of the flight and impact laws.")
@click.option("--level", type=float, default=0.95, show_default=True,
              help="Level of the intervals and bands.")
@click.option("--criterion", type=click.Choice(["aicc", "cv"]), default="aicc",
              show_default=True, help="Impact-law selection: AICc window or CV one-SE rule.")
@click.option("--min-effect", type=float, default=None,
              help="Smallest change of r over the observed speeds for a reported speed "
                   "dependence [default: 0.004, calibrated on constant-r data; "
                   "discovery.impact_law.MIN_EFFECT].")
@click.option("--max-tilt", type=float, default=10.0, show_default=True,
              help="Largest admissible |theta| of the flight law (deg).")
@channels_option
@click.option("--rising", is_flag=True,
              help="Also report impact laws in which r rises with speed (at 4x the "
                   "threshold). Off by default: no contact law rises, while systematic "
                   "errors of slow impacts look like it.")
@click.option("--n-jobs", type=int, default=None,
              help="Cores to use (default: all): the recordings are analysed side by side "
                   "in forked processes (Linux). Same results whatever the number.")
@click.option("--no-flight", is_flag=True, help="Skip the flight-law discovery.")
@click.option("--no-figures", is_flag=True, help="Skip the figures (faster).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document.")
@handle_errors
def discover(recordings, out, mu, meta, seed, n_boot, level, criterion, min_effect, max_tilt,
             channels, rising, n_jobs, no_flight, no_figures, as_json):
    """Discover the flight law and the impact law per wall from pooled recordings.

    RECORDINGS are CSV/Parquet/NPZ files with columns t, x, a, xe and a metadata
    sidecar (rec.json); pool several (e.g. different clearances) so that the
    impact speeds span a range. Writes discovery.json, equations.txt, CSV tables
    and figures/ into --out.
    """
    doc = run_discover(recordings, out, mu=mu, meta=meta, seed=seed, n_boot=n_boot,
                       level=level, criterion=criterion, min_effect=min_effect,
                       max_tilt=max_tilt, flight=not no_flight, figures=not no_figures,
                       progress=not as_json and len(recordings) > 1, channels=channels,
                       rising=rising, n_jobs=n_jobs)
    emit(as_json, doc, "\n".join(human_lines(doc)))
