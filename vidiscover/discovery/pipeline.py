"""Stage 5 in one call: :func:`discover` the flight law and the impact law per wall.

Several recordings are pooled: each is analysed by :func:`vidiscover.analysis.analyze`
(stages 1-4), then

* **flight law** -- :func:`vidiscover.discovery.flight_law.discover_flight_law` on the
  analyses (friction mu, inclination theta, other terms). When it *identifies* a
  law (admissible, not confounded, the weak form holds) with friction
  (``mu > 0``) different from the assumed one, or an inclination (|theta| >= 0.05
  deg), the recordings are analysed again with it (``refine_mu``,
  ``analyze(..., flight_law=(mu, theta))``): r depends strongly on the friction
  correction of the flights (paper Table 2), and an r estimated with the wrong mu
  carries a speed-dependent bias that the impact-law discovery would report as a
  law. A law that is not identified is never fed back: the impact laws then come
  from the flights of the assumed ``mu`` (straight lines for mu = 0), and a
  warning says so;
* **impact law, per wall** -- the impacts whose r the analysis trusts (impact table
  column ``r_used``) give one point ``(v, r)`` each, with ``v = |u_minus|`` the
  relative pre-impact speed ``|z'-| = |w- - v_LO-|`` (m/s) and the standard error
  ``sigma = r_rel_error * r``; the points of all recordings are pooled (different
  clearances give different impact speeds) and :func:`discover_impact_law` selects
  the sparsest adequate law, cross-validating over whole recordings (``groups``);
* **flight residuals** (:meth:`DiscoveryResult.flight_residuals`) -- at every impact
  between two free flights, the momentum balance of the weak form,
  ``wbar_out - wbar_in - dw`` (m/s) with ``dw = -(m1/m2) dv`` from the pulse area,
  before (straight flights, the nominal law ``y'' = 0``) and after subtracting the
  tent integral of the discovered flight law along the straight-line ``z'(t)``.

>>> from vidiscover import Effects, preset, record, simulate
>>> fx = Effects.parse(["velocity_dependent_restitution=right=linear:0.95:0.12,left=0.3"])
>>> recs = [record(simulate(preset("paper", b=b), fx, settle=5.0, duration=2.0),
...                seed=1)[0] for b in (0.006, 0.009)]
>>> res = discover(recs, n_boot=20, flight=False)
>>> res.impact_laws["right"].kind, res.impact_laws["left"].formula
('linear', 'r = 0.3')
"""

from __future__ import annotations

import gc
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .._atomic import to_jsonable
from .._workers import WorkerPool, can_fork, gc_paused, n_workers
from ..analysis import AnalysisResult, DetectionOptions, analyze
from ..analysis.reconstruction import contact_durations
from ..errors import InputError
from ..recording import Recording
from .flight_law import MAX_TILT_DEG
from .impact_law import (
    CLAIMED_BEYOND,
    COMPLIANT_FORM_SCATTER,
    MIN_EFFECT,
    discover_impact_law,
)
from .impact_result import ImpactLawResult

__all__ = ["DiscoveryResult", "discover", "SIDES", "IMPACT_DATA_COLUMNS"]

#: The two walls, in the order of the paper's tables.
SIDES = ("right", "left")
#: Columns of :attr:`DiscoveryResult.impact_data` tables.
IMPACT_DATA_COLUMNS = ("recording", "group", "t", "v", "r", "sigma", "contact_s")
#: ``flight`` of the summary when the flight-law discovery did not run.
_NOT_RUN = {"identified": False, "reason": "flight-law discovery not run", "mu": None,
            "theta_deg": None, "terms": [], "coefficients": [], "equation": "not identified"}


@dataclass(frozen=True, eq=False)
class DiscoveryResult:
    """Flight law and per-wall impact laws discovered from pooled recordings.

    Attributes
    ----------
    recordings : tuple of str
        Names of the recordings, in input order (``group`` k is the k-th).
    analyses : tuple of AnalysisResult
        Stage 1-4 results of each recording.
    impact_data : Mapping[str, pandas.DataFrame]
        Per wall, the pooled impacts used (:data:`IMPACT_DATA_COLUMNS`).
    impact_laws : Mapping[str, ImpactLawResult]
        Per wall, the discovered restitution law.
    flight : FlightLawResult or None
        The flight-law result, identified or not (None when not run or it failed
        on its input; see ``warnings``).
    mu : float
        Friction coefficient assumed on input.
    mu_impacts : float
        Friction coefficient of the analyses the impact laws come from (the
        identified one after ``refine_mu``).
    theta_impacts : float
        Inclination (deg) of the analyses the impact laws come from.
    warnings : tuple of str
        Everything that limited the discovery.
    """

    recordings: tuple[str, ...]
    analyses: tuple = field(repr=False)
    impact_data: Mapping[str, pd.DataFrame] = field(repr=False)
    impact_laws: Mapping[str, ImpactLawResult]
    flight: Any
    mu: float
    mu_impacts: float
    theta_impacts: float = 0.0
    warnings: tuple[str, ...] = ()

    def equations(self) -> list[str]:
        """The discovered laws as text lines (flight law first)."""
        lines = []
        if self.flight is not None and self.flight.identified:
            lines.append(f"flight: {self.flight.equation}   (mu = {self.flight.mu:.4g}, "
                         f"theta = {self.flight.theta_deg:.4g} deg)")
        elif self.flight is not None:
            lines.append(f"flight: not identified ({self.flight.reason})")
        else:
            lines.append("flight: not identified (flight-law discovery not run)")
        for side in SIDES:
            law = self.impact_laws[side]
            rng = law.speed_range
            where = (f"v = |z'-| in {rng[0]:.3g}-{rng[1]:.3g} m/s, n = {law.n}"
                     if law.n else "no impacts")
            top = law.valid_range[1]
            if law.n and math.isfinite(top) and top < CLAIMED_BEYOND * rng[1] * (1 - 1e-9):
                where += f"; holds up to {top:.3g} m/s (r reaches 0 there)"
            if law.n_inconsistent:
                where += (f"; {law.n_inconsistent} impact(s) left out as inconsistent "
                          "(a missed impact before them)")
            lines.append(f"{side} wall: {law.formula}   ({where})")
        return lines

    def summary(self) -> dict:
        """JSON-ready dict (the README's command table ``discover`` keys and more).

        Keys: ``flight`` (``identified``, ``reason``, ``mu``, ``theta_deg``,
        ``terms``, ``equation``, intervals, ``diagnostic_fit``; ``mu``/``theta_deg``
        None when not identified or not run), ``impact_law`` {``right``, ``left``}
        (``formula``, ``kind``, ``terms``, ``coefficients`` with ``ci``, ``effect``,
        ``effect_threshold``, ``band``, ``delta_aicc_vs_constant``,
        ``p_value_vs_constant``, ``speed_range``, ``n``, ``candidates``, ...),
        ``equations``, ``recordings``, ``n_recordings``, ``mu_assumed``,
        ``mu_impacts``, ``theta_impacts`` (the flight law behind the impact laws),
        ``warnings``. NaN becomes None.
        """
        return to_jsonable({
            "recordings": list(self.recordings),
            "n_recordings": len(self.recordings),
            "mu_assumed": self.mu,
            "mu_impacts": self.mu_impacts,
            "theta_impacts": self.theta_impacts,
            "flight": _NOT_RUN if self.flight is None else self.flight.to_dict(),
            "impact_law": {side: self.impact_laws[side].to_dict() for side in SIDES},
            "equations": self.equations(),
            "warnings": list(self.warnings),
        })

    def flight_residuals(self) -> pd.DataFrame:
        """Weak-form momentum residual at each impact, before and after the flight law.

        Returns
        -------
        pandas.DataFrame
            Columns ``recording``, ``t`` (s), ``before`` and ``after`` (m/s): at every
            impact between two free flights, ``wbar_out - wbar_in - dw`` (nominal law:
            straight flights), and the same minus ``sum_j c_j int phi f_j(z') dt``
            over the two flights (``phi`` the tent peaking at the impact, ``z'`` along
            the straight flights). ``after`` equals ``before`` without a flight law.
        """
        frames = [_residuals(a, self.flight) for a in self.analyses]
        if not frames:
            return pd.DataFrame(columns=["recording", "t", "before", "after"])
        return pd.concat(frames, ignore_index=True)


# --------------------------------------------------------------------- residuals
def _residuals(analysis: AnalysisResult, flight) -> pd.DataFrame:
    rec = analysis.recording
    m1, m2 = (rec.meta.m1, rec.meta.m2) if rec is not None else (4.168, 0.032)
    fl = analysis.reconstruction.flights
    dv = np.asarray(analysis.detection.dv, dtype=float)
    recon = analysis.reconstruction
    funcs = []
    if flight is not None and flight.identified:
        try:
            from .flight_law import FLIGHT_TERMS
        except ImportError:  # pragma: no cover - depends on the flight-law module
            FLIGHT_TERMS = {}
        funcs = [(float(c), FLIGHT_TERMS[t]) for t, c in
                 zip(flight.terms, flight.coefficients, strict=True) if t in FLIGHT_TERMS]
    i_start = fl["i_start"].to_numpy()
    i_end = fl["i_end"].to_numpy()
    free = (fl["kind"] == "free").to_numpy()
    t0, t1 = fl["t_start"].to_numpy(), fl["t_end"].to_numpy()
    wbar = ((fl["y_end"] - fl["y_start"]) / (fl["t_end"] - fl["t_start"])).to_numpy()
    rows = []
    for k in range(1, len(fl)):
        if not (free[k - 1] and free[k] and i_end[k - 1] == i_start[k]):
            continue
        i = int(i_start[k])
        before = wbar[k] - wbar[k - 1] + (m1 / m2) * dv[i]
        rhs = 0.0
        for j, phi_up in ((k - 1, True), (k, False)):
            sel = (recon.t >= t0[j]) & (recon.t <= t1[j])
            ts = recon.t[sel]
            if ts.size < 2 or not funcs:
                continue
            zd = wbar[j] - recon.v[sel]
            phi = (ts - t0[j]) / (t1[j] - t0[j])
            phi = phi if phi_up else 1.0 - phi
            rhs += sum(c * np.trapezoid(phi * f(zd), ts) for c, f in funcs)
        rows.append((analysis.name, float(analysis.detection.t[i]), before, before - rhs))
    return pd.DataFrame(rows, columns=["recording", "t", "before", "after"])


# --------------------------------------------------------------------- pipeline
def _as_items(items) -> list:
    if isinstance(items, (str, os.PathLike, Recording, AnalysisResult)):
        return [items]
    try:
        out = list(items)
    except TypeError:
        raise InputError(f"discover needs recordings (paths, Recording or AnalysisResult "
                         f"objects), was {type(items).__name__}") from None
    if not out:
        raise InputError("discover needs at least one recording; pass one or more files")
    return out


def _analysis_of(item, mu: float, detection, meta) -> AnalysisResult:
    """The analysis of one input (analysed here unless it already is)."""
    if isinstance(item, AnalysisResult):
        return item
    if isinstance(item, (str, os.PathLike)):
        from ..io import read_recording

        item = read_recording(Path(item), meta=meta)
    if not isinstance(item, Recording):
        raise InputError(f"discover: each input must be a path, a Recording or an "
                         f"AnalysisResult, got {type(item).__name__}")
    return analyze(item, mu=mu, detection=detection, n_boot=0)


def _reanalysis(rec: Recording, detection, law: tuple[float, float], pulse) -> AnalysisResult:
    """The analysis of ``rec`` again, with the flight law ``(mu, theta_deg)``."""
    return analyze(rec, detection=detection, n_boot=0, flight_law=law, pulse=pulse)


def _impact_law(d: pd.DataFrame, kws: Mapping) -> ImpactLawResult:
    """:func:`discover_impact_law` of one wall's pooled impacts.

    A wall whose learned contact lasts (``contact_s`` > 0 in any recording: a
    compliant wall) is given the model-form scatter
    :data:`~vidiscover.discovery.impact_law.COMPLIANT_FORM_SCATTER`; a rigid one
    none.
    """
    form = COMPLIANT_FORM_SCATTER if bool((d["contact_s"] > 0).any()) else 0.0
    return discover_impact_law(d["v"], d["r"], sigma=d["sigma"], groups=d["group"],
                               **{"form_scatter": form, **kws})


def _instrument_of(analysis: AnalysisResult):
    """The pulse response an analysis used, for a re-analysis of the same recording.

    The instrument does not change with the friction assumed: a learned response is
    reused as it is (learning it again costs seconds and gives the same model), a
    given model is given again; None (learn) when learning found too few pulses.
    """
    det = analysis.detection
    if det.response is not None:
        return det.response
    if any(w.startswith("too few strong isolated pulses") for w in det.warnings):
        return None
    return det.pulse


# --------------------------------------------------------------------- processes
def _workers_for(n_jobs: int | None, width: int, *, fitting: bool) -> WorkerPool:
    """Forked workers for a discovery's independent tasks (:class:`WorkerPool`).

    ``width - 1`` workers (``width``: the most tasks at once, this process running
    one), at most ``2 n_jobs - 1``, so that e.g. three analyses on two cores run side
    by side (1.5 analyses long, not two in a row). ``n_jobs == 1``, or no fork (not
    Linux, or inside a daemonic worker), runs everything here. ``fitting``: the
    tasks fit laws, so the fitting libraries (:func:`_fitting_imports`) are loaded
    before the fork, once for every worker.
    """
    cores = n_workers(n_jobs)
    workers = min(width - 1, 2 * cores - 1)
    if cores > 1 and workers >= 1 and can_fork():
        if fitting:
            _fitting_imports()
        else:
            _analysis_imports()
        # forked now, before this process starts a thread of its own (the bar's)
        return WorkerPool(workers, warm_up=_law_worker_start if fitting else _worker_start)
    return WorkerPool(0)


#: Niceness added to the law workers (:func:`_law_worker_start`).
LAW_WORKER_NICE = 5


def _law_worker_start() -> None:
    """Warm-up of a law worker: :func:`_worker_start`, at a lower priority.

    The flight law runs in this process while the workers fit the impact laws: three
    processes on two cores, where the flight law (about 1 s) is the longest and the
    impact laws (about 0.8 s together) wait for nothing. At the same priority the
    scheduler may pair the flight law with a worker on one core; at nice
    :data:`LAW_WORKER_NICE` (a third of the weight) the flight law gets a core of its
    own and the workers share the other: at load 1.5 on 2 cores, the flight law's share
    of a core 0.82-0.92 -> 0.97-1.00 and the law phase 1.07-1.21 -> 1.00-1.04 s (6
    interleaved pairs); at load 4, 0.56 -> 0.61 and as long (1.81 vs 1.80 s). No effect
    on the results.
    """
    _worker_start()
    try:
        os.nice(LAW_WORKER_NICE)
    except OSError:                     # pragma: no cover - not allowed here
        pass


def _worker_start() -> None:
    """Warm-up of a short-lived worker: less memory and garbage-collector churn.

    * glibc keeps the memory freed for reuse: an analysis allocates and frees arrays
      of a few hundred kB to a few MB thousands of times, which by default glibc maps
      afresh and unmaps when freed, so that every page is faulted in again (25-35
      thousand page faults an analysis); served from the heap and kept (the worker is
      short-lived), the pages are reused: about 9 thousand faults, 8 % less CPU;
    * the objects inherited from this process (modules, the recordings) are frozen
      (:func:`gc.freeze`): the collector's full passes no longer walk them (nor copy
      their pages), about 5 % less CPU an analysis.

    Law fits gain 2-10 %. Also called by the ``discover`` command in its own process
    (:func:`vidiscover.commands.discover.run_discover`), which is as short-lived.
    No effect on the results; the first is skipped where the C library is not glibc.
    """
    import ctypes

    gc.freeze()
    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(-3, 32 << 20)       # M_MMAP_THRESHOLD: blocks below 32 MB on the heap
        libc.mallopt(-1, 256 << 20)      # M_TRIM_THRESHOLD: keep up to 256 MB freed
    except (OSError, AttributeError):    # pragma: no cover - not glibc
        pass


def _fitting_imports() -> None:
    """Load what the flight and impact laws need and the analyses do not.

    About 0.5-1 s: pysindy brings scikit-learn and scipy.stats. Then one tiny
    library and threshold sweep (:func:`_warm_fitting`), so that the processes forked
    after it do not each pay the first call's costs.
    """
    with gc_paused():
        import pysindy  # noqa: F401
        import scipy.optimize  # noqa: F401
        import scipy.special  # noqa: F401

        _warm_fitting()


def _warm_fitting() -> None:
    """Pay the one-time costs of the first pysindy fit in this process.

    scikit-learn's input check (run by every pysindy optimizer) looks up the installed
    dataframe plugins (entry points of every installed distribution) on its first call
    in a process, and pysindy and scikit-learn fill caches (signatures, parameter
    validation) on theirs: about 40-60 ms of CPU that the flight law here and each
    impact-law worker forked later paid again, in the law phase, where the three
    share two cores. Done once here, before the law workers fork, they inherit it.
    Nothing of it reaches a result (no random state, no setting).
    """
    from .sparse import library_matrix, threshold_sweep

    x = np.linspace(0.5, 1.0, 8)
    X = library_matrix(x, ("v", "v^2"), {"v": lambda v: v, "v^2": np.square})
    threshold_sweep(X, 0.9 - 0.1 * x, (0.05,), sr3_thresholds=(0.05,))


def _analysis_imports() -> None:
    """Load what every analysis imports on first use (about 0.15 s of CPU).

    Loaded once before the analysts fork rather than once in each of them; the
    fitting libraries load most of these modules anyway.
    """
    with gc_paused():
        import scipy.cluster.hierarchy  # noqa: F401
        import scipy.linalg  # noqa: F401
        import scipy.ndimage  # noqa: F401
        import scipy.optimize  # noqa: F401
        import scipy.spatial.distance  # noqa: F401

        from .. import _prototypes  # noqa: F401


def _fitting_loaded() -> bool:
    """Whether :func:`_fitting_imports` has nothing left to load."""
    import sys

    return "pysindy" in sys.modules


def _analysis_task(task: tuple) -> AnalysisResult:
    return _analysis_of(*task)


def _reanalysis_task(task: tuple) -> AnalysisResult:
    return _reanalysis(*task)


def _pool(analyses: Sequence[AnalysisResult], side: str) -> pd.DataFrame:
    frames = []
    for k, a in enumerate(analyses):
        it = a.impact_table
        sel = (it["r_used"].to_numpy(dtype=bool) & (it["side"] == side).to_numpy())
        r = it["r"].to_numpy(dtype=float)[sel]
        frames.append(pd.DataFrame({
            "recording": a.name, "group": k, "t": it["t"].to_numpy(dtype=float)[sel],
            "v": np.abs(it["u_minus"].to_numpy(dtype=float)[sel]), "r": r,
            "sigma": it["r_rel_error"].to_numpy(dtype=float)[sel] * np.abs(r),
            "contact_s": contact_durations(a.detection)[sel]}))
    return pd.concat(frames, ignore_index=True)[list(IMPACT_DATA_COLUMNS)]


def _flight_law(analyses, seed: int, n_boot: int, level: float, max_tilt_deg: float,
                flight_kws: Mapping | None):
    """(FlightLawResult or None, warning or None)."""
    from .flight_law import discover_flight_law

    kws = {"seed": seed, "n_boot": n_boot, "level": level, "max_tilt_deg": max_tilt_deg,
           **dict(flight_kws or {})}
    try:
        res = discover_flight_law(list(analyses), **kws)
    except InputError as err:
        return None, f"flight law not identified: {err}"
    if not res.identified:
        return res, f"flight law not identified: {res.reason}"
    return res, None


def discover(recordings, *, mu: float = 0.0, seed: int = 0, n_boot: int = 200,
             level: float = 0.95, criterion: str = "aicc",
             terms: Sequence[str] | None = None, min_effect: float = MIN_EFFECT,
             max_tilt_deg: float = MAX_TILT_DEG, detection: DetectionOptions | None = None,
             meta=None,
             flight: bool = True, flight_kws: Mapping | None = None,
             impact_kws: Mapping | None = None, refine_mu: bool = True,
             progress: bool = False, n_jobs: int | None = 1) -> DiscoveryResult:
    """Discover the flight law and the impact law per wall from one or more recordings.

    Parameters
    ----------
    recordings : path, Recording, AnalysisResult or a sequence of them
        The recordings to pool (e.g. one per clearance). Paths are read with
        :func:`vidiscover.io.read_recording`; recordings are analysed with
        :func:`vidiscover.analysis.analyze`; analyses are used as they are.
    mu : float, optional
        Friction coefficient assumed by the analyses (paper eq. 8).
    seed : int, optional
        Seed of every bootstrap and cross-validation split.
    n_boot : int, optional
        Bootstrap resamples of the flight law and of the impact laws (intervals,
        band, selection frequencies).
    level : float, optional
        Level of every interval and band.
    criterion : {"aicc", "cv"}, optional
        Impact-law selection rule (see :func:`discover_impact_law`).
    terms : sequence of str, optional
        Impact-law candidate terms (default: the whole registry).
    min_effect : float, optional
        Smallest effect (max - min of r over the observed speeds) of a reported
        speed dependence (default :data:`~vidiscover.discovery.impact_law.MIN_EFFECT`).
    max_tilt_deg : float, optional
        Largest admissible |theta| of the flight law (deg).
    detection : DetectionOptions, optional
        The impact detector's settings for the recordings analysed here (default
        :class:`~vidiscover.analysis.DetectionOptions`).
    meta : path-like, dict or Metadata, optional
        Metadata for paths without a sidecar JSON (applied to every path).
    flight : bool, optional
        Run the flight-law discovery.
    flight_kws : Mapping, optional
        Other keyword arguments of ``discover_flight_law`` (e.g. ``threshold``,
        ``window``).
    impact_kws : Mapping, optional
        Other keyword arguments of :func:`discover_impact_law` (e.g.
        ``aicc_window``, ``outlier_z``, ``max_terms``).
    refine_mu : bool, optional
        When the flight law is identified with friction ``mu_id > 0`` that differs
        from ``mu`` by more than 0.005, or an inclination of at least 0.05 deg,
        analyse the recordings again with it before the impact-law discovery.
    progress : bool, optional
        Show a tqdm progress bar over the recordings.
    n_jobs : int or None, optional
        Cores to use (None: all). Above 1 (on Linux), the recordings are analysed in
        forked worker processes side by side, and the impact laws are fitted in
        workers while this process discovers the flight law (on the analyses the
        impact laws then come from; refitted when the flight law has them redone).
        The results do not depend on it.

    Returns
    -------
    DiscoveryResult

    Raises
    ------
    InputError
        Unreadable recordings, bad options.
    """
    if not (isinstance(mu, (int, float)) and math.isfinite(mu) and 0 <= mu <= 2):
        raise InputError(f"mu must be in [0, 2] (friction coefficient), was {mu!r}")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise InputError(f"seed must be an integer >= 0, was {seed!r}")
    if not isinstance(n_boot, (int, np.integer)) or isinstance(n_boot, bool) or n_boot < 0:
        raise InputError(f"n_boot must be an integer >= 0, was {n_boot!r}")
    if not (isinstance(level, (int, float)) and 0.0 < level < 1.0):
        raise InputError(f"level must be in (0, 1), was {level!r}")
    for name, kws in (("flight_kws", flight_kws), ("impact_kws", impact_kws)):
        if kws is not None and not isinstance(kws, Mapping):
            raise InputError(f"{name} must be a mapping of keyword arguments, "
                             f"was {type(kws).__name__}")
    items = _as_items(recordings)
    kws = {"seed": int(seed), "n_boot": int(n_boot), "level": float(level),
           "criterion": criterion, "terms": terms, "min_effect": min_effect,
           **dict(impact_kws or {})}
    # the analyses side by side, in workers forked before the fitting libraries are
    # loaded: this process loads them meanwhile (the analyses do not need them), then
    # takes an analysis too; then the flight law here while workers forked with those
    # libraries fit the impact laws on the same analyses (used unless the flight law
    # sends them to be redone)
    todo = [k for k, it in enumerate(items) if not isinstance(it, AnalysisResult)]
    # loading the fitting libraries counts as one more task (about 0.5 s of CPU, as
    # long as half an analysis): with a worker per analysis, the analyses and the load
    # share the cores to the end, where this process would otherwise take an analysis
    # after the load and run it alone while the workers wait (3 recordings on 2 cores:
    # 1.75 -> 1.5 s of wall); one recording too: its analyst runs while this process
    # loads them, instead of the analysis after the load
    width = len(todo) + (len(todo) >= 1 and not _fitting_loaded())
    bar = None
    try:
        with _workers_for(n_jobs, width, fitting=False) as analysts:   # forks here
            if progress:
                from tqdm import tqdm

                bar = tqdm(total=len(items), desc="analyse", unit="rec")
            done = analysts.map(_analysis_task,
                                [(items[k], mu, detection, meta) for k in todo],
                                bar=bar, first=_fitting_imports)
        analyses = list(items)
        for k, a in zip(todo, done, strict=True):
            analyses[k] = a
        if bar is not None:
            bar.update(len(items) - len(todo))
    finally:
        if bar is not None:
            bar.close()           # stops its monitor thread: the next pool forks
    run = _workers_for(n_jobs, 1 + len(SIDES), fitting=True)   # forks here
    try:
        analyses = tuple(analyses)
        data = {side: _pool(analyses, side) for side in SIDES}
        ahead = {side: run.submit(_impact_law, data[side], kws) for side in SIDES} \
            if flight else {}
        warnings = [f"{a.name}: {w}" for a in analyses for w in a.warnings]
        flight_result = None
        if flight:
            flight_result, note = _flight_law(analyses, int(seed), int(n_boot), float(level),
                                              max_tilt_deg, flight_kws)
            if note:
                warnings.append(note)
        mu_impacts, theta_impacts = float(mu), 0.0
        if flight_result is None or not flight_result.identified:
            if flight:
                warnings.append(f"impact laws fitted with the flights of the assumed law "
                                f"(mu = {mu:g}, theta = 0"
                                f"{': straight lines' if mu == 0 else ''}), not with a "
                                "flight law")
        elif refine_mu:
            mu_id = float(flight_result.mu)
            theta_id = float(flight_result.theta_deg)
            theta_id = theta_id if abs(theta_id) >= 0.05 else 0.0
            recs = [a.recording for a in analyses]
            if (all(r is not None for r in recs)
                    and ((mu_id > 0 and abs(mu_id - mu) > 0.005) or theta_id)):
                mu_impacts, theta_impacts = min(max(mu_id, 0.0), 2.0), theta_id
                analyses = tuple(run.map(_reanalysis_task, [
                    (r, detection, (mu_impacts, theta_id), _instrument_of(a))
                    for r, a in zip(recs, analyses)]))
                data = {side: _pool(analyses, side) for side in SIDES}
                ahead = {}
        if not ahead:
            ahead = {side: run.submit(_impact_law, data[side], kws) for side in SIDES[:-1]}
        laws = {}
        for side in SIDES:
            laws[side] = run.result(ahead.get(side), _impact_law, data[side], kws)
            if laws[side].warning:
                warnings.append(f"{side} wall: {laws[side].warning}")
            if laws[side].note:
                warnings.append(f"{side} wall: {laws[side].note}")
    finally:
        run.close()
    return DiscoveryResult(recordings=tuple(a.name for a in analyses), analyses=analyses,
                           impact_data=data, impact_laws=laws, flight=flight_result,
                           mu=float(mu), mu_impacts=mu_impacts, theta_impacts=theta_impacts,
                           warnings=tuple(warnings))
