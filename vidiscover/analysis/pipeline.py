"""Stages 1-4 in one call: :func:`analyze` a recording, no figures, no files.

>>> from vidiscover import preset, simulate, record, Effects
>>> res = simulate(preset("paper", b=0.009),
...                Effects.parse(["asymmetric_restitution=0.88,0.2"]), settle=3.0, duration=1.0)
>>> out = analyze(record(res)[0])
>>> s = out.summary()
>>> s["impacts"]["n"] > 0, round(s["restitution"]["right"]["rms"], 2)
(True, 0.88)
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .._atomic import to_jsonable
from ..errors import InputError
from .impacts import DetectionOptions, ImpactDetection, detect_impacts
from .pulse import PulseModel, PulseResponse
from .reconstruction import Reconstruction, reconstruct
from .restitution import MU_TABLE, RestitutionEstimate, estimate_restitution, mu_table
from .returnmap import FeatureContext, ReturnMap, compute_features, return_map
from .signals import Forcing, Offsets, estimate_offsets, fit_forcing

if TYPE_CHECKING:      # pandas is imported where a table is built, not to analyse
    import pandas as pd

__all__ = ["AnalysisResult", "analyze"]


@dataclass(frozen=True, eq=False)
class AnalysisResult:
    """Everything :func:`analyze` found in one recording.

    Attributes
    ----------
    name : str
        Recording label.
    b : float
        Half-clearance used (m).
    mu : float
        Friction coefficient assumed.
    forcing : Forcing
        Base excitation fitted to ``xe``.
    detection : ImpactDetection
        Stage 1.
    reconstruction : Reconstruction
        Stage 2.
    restitution : RestitutionEstimate
        Stage 3.
    returnmap : ReturnMap
        Stage 4.
    features : dict
        The features computed (name -> value), those of the set given to
        :func:`analyze` (default :data:`~vidiscover.analysis.returnmap.ANALYSIS_FEATURES`).
    regime_label : str or None
        Regime label (None until a classifier is attached).
    warnings : tuple of str
    theta_deg : float
        Inclination assumed (deg; from a flight law, else 0).
    offsets : Offsets
        Accelerometer bias and displacement zero offsets, removed before stages 2-4.
    """

    name: str
    b: float
    mu: float
    forcing: Forcing
    detection: ImpactDetection
    reconstruction: Reconstruction
    restitution: RestitutionEstimate
    returnmap: ReturnMap
    features: dict
    regime_label: str | None = None
    warnings: tuple = ()
    _recording: object = field(default=None, repr=False)
    theta_deg: float = 0.0
    offsets: Offsets = field(default_factory=Offsets)

    @property
    def recording(self):
        """The analysed :class:`~vidiscover.recording.Recording` (None if not kept).

        Its offsets (:attr:`offsets`) are removed.
        """
        return self._recording

    def summary(self) -> dict:
        """JSON-ready nested dict (the README's command table ``analyze`` keys and more).

        Keys: ``impacts`` {``n``, ``t``, ``side``, ``dv``, ``right``, ``left``,
        ``noise``}, ``restitution`` {``mu``, ``right``/``left`` {``n``, ``rms``,
        ``mean``, ``median``, ``std``, ``ci_low``, ``ci_high``, ...}}, ``regime``
        {``label``}, ``flights`` {``n``, ``stick``}, ``forcing``, ``features``,
        ``recording``, ``b``, ``mu``, ``warnings``, ``pulse_response`` {``kind``,
        ``order``, ``cutoff_hz``, ``tau``, ``delay``, ``centroid``, ``width``,
        ``learned``, ...} and ``offsets`` {``a_bias``, ``x_offset``, ``xe_offset``,
        ``n_cycles``}. NaN becomes None.
        """
        det = self.detection
        side = det.side
        fc = self.reconstruction.flight_columns
        return to_jsonable({
            "recording": self.name,
            "b": self.b,
            "mu": self.mu,
            "theta_deg": self.theta_deg,
            "duration": det.duration,
            "sample_rate": det.sample_rate,
            "forcing": {"frequency": self.forcing.frequency,
                        "amplitude": self.forcing.amplitude,
                        "phase": self.forcing.phase, "source": self.forcing.source},
            "impacts": {"n": det.n, "t": det.t, "side": [str(s) for s in side],
                        "dv": det.dv, "right": int((side == "right").sum()),
                        "left": int((side == "left").sum()), "noise": det.noise,
                        "unreliable": int((~det.columns["reliable"]).sum())},
            "restitution": {"mu": self.restitution.mu,
                            "level": self.restitution.level,
                            "right": self.restitution.right.to_dict(),
                            "left": self.restitution.left.to_dict()},
            "flights": {"n": int(fc["t_start"].size),
                        "stick": int((fc["kind"] == "stick").sum())},
            "returnmap": {"n_points": self.returnmap.n_points,
                          "clusters": self.returnmap.n_clusters},
            "features": self.features,
            "regime": {"label": self.regime_label},
            "pulse_response": _pulse_summary(det),
            "offsets": self.offsets.to_dict(),
            "warnings": list(self.warnings),
        })

    def tables(self) -> dict[str, pd.DataFrame]:
        """``{"impacts": ..., "flights": ...}`` DataFrames for CSV export.

        The impact table joins stage 1 (pulse), stage 2 (states) and stage 3
        (restitution) columns; the flight table is stage 2's.
        """
        return {"impacts": self.impact_table, "flights": self.reconstruction.flights}

    @functools.cached_property
    def impact_table(self) -> pd.DataFrame:
        """One row per impact with the pulse, the states and r."""
        d = self.detection.columns
        s = self.reconstruction.impact_columns
        r = self.restitution.columns
        cols = {"t": d["t"], "side": d["side"], "dv": d["dv"], "area": d["area"],
                "snr": d["snr"], "reliable": d["reliable"], "clipped": d["clipped"],
                "dropout": d["dropout"], "side_check": d["side_check"], "merged": d["merged"]}
        for k in ("x", "y", "v_minus", "v_plus", "w_minus", "w_plus", "u_minus", "u_plus"):
            cols[k] = s[k]
        cols.update({"r": r["r"], "r_status": r["status"], "r_used": r["used"],
                     "r_rel_error": r["rel_error"]})
        import pandas as pd

        return pd.DataFrame(cols)

    def mu_table(self, mus=MU_TABLE) -> pd.DataFrame:
        """Paper Table 2 for this recording (see :func:`restitution.mu_table`)."""
        if self._recording is None:
            raise InputError("mu_table needs the recording; analyse it again with analyze()")
        return mu_table(self.detection, self._recording, mus, b=self.b,
                        recon=self.reconstruction)


def analyze(rec, mu: float = 0.0, *, b: float | None = None,
            detection: DetectionOptions | None = None,
            n_boot: int = 1000, seed: int = 0, flight_law=None,
            pulse: PulseModel | PulseResponse | None = None, offsets: bool = True,
            features=None, overwrite: bool = False) -> AnalysisResult:
    """Run stages 1-4 on a recording: impacts, reconstruction, restitution, return map.

    Parameters
    ----------
    rec : Recording
        The recording.
    mu : float
        Friction coefficient assumed between ball and LO (paper eq. 8).
    b : float, optional
        Half-clearance (m); default ``rec.meta.b``.
    detection : DetectionOptions, optional
        The impact detector's settings (threshold, smoother window, ...; default
        :class:`~vidiscover.analysis.impacts.DetectionOptions`).
    n_boot : int
        Bootstrap resamples of the restitution confidence intervals.
    seed : int
        Seed of the bootstrap.
    flight_law : FlightLawResult or (mu, theta_deg), optional
        An identified flight law (:func:`vidiscover.discovery.discover_flight_law`)
        used instead of ``mu``: its friction reconstructs the flights, and its
        inclination corrects the ball velocity at every impact of a free flight
        (exactly: the tilt is absorbed by a change of frame). The plotted ball
        path between impacts stays the friction-only one.
    pulse : PulseModel or PulseResponse, optional
        A known pulse response (e.g. ``PulseModel()`` for the exact engine's default
        sensors), or one learned before from the same instrument
        (``AnalysisResult.detection.response``); default: learned from the recording
        (:func:`vidiscover.analysis.pulse.learn_pulse`).
    offsets : bool
        Estimate the accelerometer bias and the displacement zero offsets over whole
        forcing cycles and remove them before stages 2-4
        (:func:`vidiscover.analysis.signals.estimate_offsets`).
    features : FeatureSet, optional
        The features to compute (:class:`~vidiscover.analysis.returnmap.FeatureSet`;
        default the analysis's own,
        :data:`~vidiscover.analysis.returnmap.ANALYSIS_FEATURES`; the regime
        classifier needs ``vidiscover.regimes.features.ALL_FEATURES``).
    overwrite : bool
        Subtract the offsets in the recording's own (writable) arrays ``x``, ``a``
        and ``xe`` instead of in copies: the recording is changed, and a long one
        needs three full-length arrays less (the ``analyze`` command does this with
        the recordings it read itself; the numbers are the same).

    Returns
    -------
    AnalysisResult

    Raises
    ------
    InputError
        On unusable input (too short, bad time axis, no finite acceleration or
        displacement, impossible parameters).
    """
    if features is not None and not isinstance(features, Mapping):
        raise InputError("features must be a FeatureSet (name -> function), e.g. "
                         "vidiscover.regimes.features.ALL_FEATURES or ANALYSIS_FEATURES."
                         f"select([...]); got {type(features).__name__}")
    theta_deg = 0.0
    if flight_law is not None:
        mu, theta_deg = _law_mu_theta(flight_law)
    if not (isinstance(mu, (int, float)) and math.isfinite(mu) and 0 <= mu <= 2):
        raise InputError(f"mu must be in [0, 2] (friction coefficient), was {mu!r}")
    b = float(rec.meta.b if b is None else b)
    det = detect_impacts(rec, detection, mu=mu, b=b,                # checks the recording
                         pulse=pulse)
    forcing = fit_forcing(rec.t, rec.xe, rec.meta.frequency)
    off = Offsets()
    if offsets:
        off = estimate_offsets(rec.t, rec.x, rec.a, rec.xe, forcing, det.t)
        rec = _without_offsets(rec, off, overwrite)
    det = _smooth_part_corrected(det, off.a_bias)
    recon = reconstruct(det, rec, b=b, mu=mu, theta_deg=theta_deg)
    if theta_deg != 0.0:
        recon = _tilted(recon, det, rec, mu, theta_deg)
    rest = estimate_restitution(recon, det, n_boot=n_boot, seed=seed)
    rm = return_map(det.t, det.side, forcing.period)
    features = compute_features(FeatureContext.of(det, forcing, recon, rm, rec), features)
    warnings = list(det.warnings)
    if forcing.source != "xe":
        warnings.append("base displacement 'xe' has no usable sine: cycles are cut with the "
                        "metadata frequency and phase 0")
    if recon.laser_rail_share > 0:
        warnings.append(f"laser 'x' saturated on {100 * recon.laser_rail_share:.0f} % of its "
                        "samples (its extreme value, held): those samples are left out of "
                        "the LO's pinning; use a laser range that covers the LO's motion")
    for w in (rest.right, rest.left):
        if w.warn_slow:
            warnings.append(f"{w.side} wall: the ball is too slow for the friction "
                            f"correction (median ratio {w.friction_ratio:.2f}); r depends "
                            "more on mu than on the data")
    return AnalysisResult(name=rec.name, b=b, mu=float(mu), forcing=forcing, detection=det,
                          reconstruction=recon, restitution=rest, returnmap=rm,
                          features=features, regime_label=None, warnings=tuple(warnings),
                          _recording=rec, theta_deg=float(theta_deg), offsets=off)


def _pulse_summary(det: ImpactDetection) -> dict:
    """The pulse response used (learned or given) for ``summary.json``."""
    if det.response is not None:
        return det.response.to_dict()
    out = det.pulse.to_dict(det.sample_rate)
    out["learned"] = False
    return out


def _without_offsets(rec, off: Offsets, overwrite: bool = False):
    """``rec`` with the offsets subtracted (the same object when they are all 0).

    With ``overwrite``, in the recording's own arrays (a Recording keeps them
    read-only; they are made writable for the subtraction where numpy allows it, i.e.
    where their memory is writable) with the same arithmetic as the copies, so the
    same numbers.
    """
    if off.n_cycles == 0:
        return rec
    from dataclasses import replace

    def minus(v, c):
        if overwrite and v.dtype == np.float64:
            try:
                v.flags.writeable = True
            except ValueError:          # a view of read-only memory: a copy it is
                return v - c
            np.subtract(v, c, out=v)
            v.flags.writeable = False
            return v
        return v - c

    return replace(rec, x=minus(rec.x, off.x_offset), a=minus(rec.a, off.a_bias),
                   xe=minus(rec.xe, off.xe_offset))


def _smooth_part_corrected(det: ImpactDetection, a_bias: float) -> ImpactDetection:
    """``det`` with its smooth acceleration unbiased and advanced by the filter's delay.

    A causal anti-alias filter delays the slow forced response by its DC group
    delay (the learned response's centroid less half the contact); the
    reconstruction integrates that smooth part, so it is shifted back.
    """
    from dataclasses import replace

    from ..acquisition import dc_group_delay

    m = det.pulse
    lag = dc_group_delay(m.kind, m.order, m.cutoff) if m.causal else 0.0   # samples
    if a_bias == 0.0 and lag == 0.0:
        return det
    j = np.arange(det.n_samples, dtype=float)

    def fix(v):
        w = np.interp(j + lag, j, v) if lag else v
        return w - a_bias

    return replace(det, a_smooth=fix(det.a_smooth), baseline=fix(det.baseline))


def _law_mu_theta(law) -> tuple[float, float]:
    """``(mu, theta_deg)`` of a flight law or of a pair of numbers.

    A law is anything with a ``mu_theta()`` method (a
    :class:`~vidiscover.discovery.FlightLawResult`; the analysis does not import the
    discovery stage that makes them).
    """
    if callable(getattr(law, "mu_theta", None)):
        return law.mu_theta()
    try:
        mu, theta = (float(v) for v in law)
    except (TypeError, ValueError):
        raise InputError("flight_law must be a FlightLawResult or a pair (mu, theta_deg), "
                         f"was {law!r}") from None
    if not (math.isfinite(theta) and abs(theta) < 90):
        raise InputError(f"flight_law theta_deg must be in (-90, 90) degrees, was {theta!r}")
    return max(mu, 0.0), theta


def _tilted(recon: Reconstruction, det: ImpactDetection, rec, mu: float,
            theta_deg: float) -> Reconstruction:
    """``recon`` with the free-flight ball velocities solved under inclination."""
    from .flights import FlightData, solve_free_flights

    if recon.n_flights == 0:
        return recon
    sol = solve_free_flights(FlightData(rec, recon, det), mu, theta_deg)
    fc = {k: np.array(v, copy=True) for k, v in recon.flight_columns.items()}
    ic = {k: np.array(v, copy=True) for k, v in recon.impact_columns.items()}
    k = sol["flight"]
    fc["w_start"][k] = sol["w_start"]
    fc["w_end"][k] = sol["w_end"]
    fc["zd_start"] = fc["w_start"] - fc["v_start"]
    fc["zd_end"] = fc["w_end"] - fc["v_end"]
    ic["w_plus"][fc["i_start"][k]] = sol["w_start"]
    ic["w_minus"][fc["i_end"][k]] = sol["w_end"]
    ic["u_minus"] = ic["w_minus"] - ic["v_minus"]
    v_exit = np.array(ic["v_plus"], copy=True)        # the LO at each contact's exit
    v_exit[fc["i_start"]] = fc["v_start"]
    ic["u_plus"] = ic["w_plus"] - v_exit
    from dataclasses import replace

    return replace(recon, impact_columns=ic, flight_columns=fc)
