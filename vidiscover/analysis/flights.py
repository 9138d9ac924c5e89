"""The ball's flights between impacts under a flight law (friction and tilt).

Stage 3 of :func:`vidiscover.analysis.analyze` reconstructs the flights with an
assumed friction; when a flight law (mu, theta) is known, the flights are solved
again under it here (:func:`solve_free_flights`). The flight-law discovery
(:mod:`vidiscover.discovery.flight_law`) builds its weak form on the same
:class:`FlightData` and :func:`reconstruct_flights`, so both read the flights the
same way.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from ..errors import InputError
from ..params import G_ACCEL
from .friction import falling_frame, solve_flights
from .reconstruction import contact_durations, force_centroids

__all__ = ["FlightData", "STEPS", "force_centroids", "reconstruct_flights",
           "solve_free_flights"]

#: Integration steps per flight.
STEPS = 192


# ----------------------------------------------------------------- per recording
class FlightData:
    """Impacts, flights and LO motion of one analysed recording, as plain arrays.

    What the ball's flights are solved from: impact times and ball positions, LO
    velocity jumps (fitted pulse areas and raw ``area``), the flight table, and the
    LO velocity (without its jumps) and smooth acceleration at any time inside a
    flight.

    Parameters
    ----------
    recording : Recording
        The (offset-corrected) recording that was analysed.
    reconstruction : Reconstruction
        Its reconstruction (stage 3 of :func:`vidiscover.analysis.analyze`).
    detection : ImpactDetection
        Its impact detection (stage 1).
    name : str, optional
        Label (default: the recording's name).
    """

    def __init__(self, recording, reconstruction, detection, name: str | None = None) -> None:
        rec, recon, det = recording, reconstruction, detection
        imp = recon.impact_columns
        fl = recon.flight_columns
        self.name = rec.name if name is None else name
        self.ratio = float(rec.meta.m1) / float(rec.meta.m2)
        self.t_imp = np.asarray(imp["t"], float)
        self.y_imp = np.asarray(imp["y"], float)
        self.dv = np.asarray(imp["dv"], float)
        area = det.columns.get("area") if hasattr(det.columns, "get") else None
        self.area = (np.asarray(area, float) if area is not None and len(area) == len(self.dv)
                     else np.full(self.dv.shape, np.nan))
        side = np.asarray(imp["side"])
        self.sign = (np.where(side == "right", 1.0, -1.0) if side.dtype.kind in "UO"
                     else np.sign(side.astype(float)))
        self.v_minus = np.asarray(imp["v_minus"], float)
        self.v_plus = np.asarray(imp["v_plus"], float)
        n_imp = self.dv.size
        self.u_minus = (np.asarray(imp["u_minus"], float) if "u_minus" in imp
                        else np.full(n_imp, np.nan))
        self.u_plus = (np.asarray(imp["u_plus"], float) if "u_plus" in imp
                       else np.full(n_imp, np.nan))
        # contact duration (s) per impact: the learned pulse's, per wall; and the time
        # from the contact entry to the centroid of its force (the equivalent impact)
        self.tau = contact_durations(det)
        self.centroid = force_centroids(det, self.tau)
        self.reliable = np.asarray(det.columns["reliable"], bool)
        self.i_s = np.asarray(fl["i_start"], np.int64)
        self.i_e = np.asarray(fl["i_end"], np.int64)
        # flights from impact to impact (the flight law's weak form takes the contacts
        # as instantaneous at their entries) ...
        self.ts = self.t_imp[self.i_s]
        self.te = np.asarray(fl["t_end"], float)
        # ... and the reconstruction's, each from its contact's exit (time, ball
        # position, LO velocity; the impact's own where the contact takes no time)
        self.exit_t = np.asarray(fl["t_start"], float)
        self.exit_y = np.asarray(fl["y_start"], float)
        self.exit_v = np.asarray(fl["v_start"], float)
        self.kind = np.asarray(fl["kind"])
        t = np.asarray(recon.t, float)
        # LO velocity without its jumps, to be evaluated anywhere inside a flight
        cdv = np.concatenate([[0.0], np.cumsum(self.dv)])
        self._t = t
        self._cdv = cdv
        self._vc = np.asarray(recon.v, float) - cdv[np.searchsorted(self.t_imp, t, side="left")]
        # recon.v is the LO as recorded; the impacts, the exits and the baseline are in
        # the impacts' time frame (a causal instrument's lag apart): its velocity there
        self._shift = recon._shift
        self._acc = np.asarray(det.baseline, float)

    @classmethod
    def of(cls, analysis) -> FlightData:
        """From an :class:`~vidiscover.analysis.AnalysisResult` (its recording kept)."""
        rec = getattr(analysis, "recording", None)
        if rec is None:
            raise InputError("the flights need AnalysisResult objects from analyze(rec) "
                             "(their recording is missing)")
        return cls(rec, analysis.reconstruction, analysis.detection, name=analysis.name)

    def with_impacts(self, t=None, y=None, dv=None, area=None) -> FlightData:
        """A copy with other impact times, ball positions or velocity jumps.

        For diagnosis: e.g. the true jumps, or the equivalent instantaneous impacts of
        compliant contacts, in place of the analysed ones, to tell the analysis's
        errors from the flight-law estimator's. The flights' start and end times
        follow ``t``; the LO motion is kept. Impacts placed by ``t`` are instantaneous
        there (their contact durations become 0).

        Parameters
        ----------
        t, y, dv, area : ndarray, optional
            Impact times (s), ball positions (m), LO velocity jumps and raw pulse
            areas (m/s), one per impact; None keeps the analysed values.

        Returns
        -------
        FlightData
        """
        out = copy.copy(self)
        for name, val in (("t_imp", t), ("y_imp", y), ("dv", dv), ("area", area)):
            if val is None:
                continue
            val = np.array(val, dtype=float)
            if val.shape != self.dv.shape:
                raise InputError(f"with_impacts: {name} needs one value per impact "
                                 f"({self.dv.size}), got shape {val.shape}")
            setattr(out, name, val)
        out.ts, out.te = out.t_imp[self.i_s], out.t_imp[self.i_e]
        # instantaneous impacts at the given points
        out.exit_t, out.exit_y = out.ts, out.y_imp[self.i_s]
        out.exit_v = out.v_plus[self.i_s]
        if t is not None:
            out.tau = np.zeros_like(self.tau)
            out.centroid = np.zeros_like(self.centroid)
        return out

    def equivalent_impacts(self, scale: float = 1.0) -> FlightData:
        """A copy with every impact at the equivalent impact of its contact.

        A compliant contact is not an impact at its entry: the ball's approach and
        rebound lines (its motion under the contact force alone) meet at the centroid of
        the force, ``dt`` after the entry, ``dz = |u-| dt`` beyond the wall; ``dt`` is the
        learned pulse's (:func:`force_centroids`). The flights between those points are
        what the weak form's straight-line mean velocities describe; for an
        instantaneous impact (dt = 0) nothing moves. (The lines through the contact's
        entry and exit on the wall, ``dt = r tau / (1 + r)``, miss a Kelvin-Voigt wall's
        exit: its force ends with the ball still 0.1-0.2 mm inside, holdout6-001, whose
        equivalent impacts lie 144 us after the entries, not 113 us; the learned force's
        centroid, added to the detected entry, puts them within 0-7 us.)

        Parameters
        ----------
        scale : float
            Factor on the centroids (1: as learned; e.g. 0.3 to see how the flights
            move if the learned contact is 3 times too long).

        Returns
        -------
        FlightData
        """
        if not (math.isfinite(scale) and scale >= 0):
            raise InputError(f"equivalent_impacts: scale must be a finite factor >= 0, was "
                             f"{scale!r}")
        dt = np.where(np.isfinite(self.centroid), self.centroid, 0.0) * scale
        dz = np.nan_to_num(np.abs(self.u_minus)) * dt
        return self.with_impacts(t=self.t_imp + dt,
                                 y=self.y_imp + np.nan_to_num(self.v_minus) * dt
                                 + self.sign * dz)

    @property
    def n_flights(self) -> int:
        """Number of flights."""
        return int(self.ts.size)

    def lo_velocity(self, tq):
        """LO velocity (m/s) at times ``tq``, its jumps at the impacts included."""
        tq = np.asarray(tq, float)
        out = np.interp(tq, self._t, self._vc) + self._cdv[np.searchsorted(self.t_imp, tq)]
        if self._shift is not None:
            out = out + self._shift(tq - self._t[0])[1]
        return out

    def lo_acceleration(self, tq):
        """Smooth LO acceleration (m/s^2) at times ``tq`` (the detection's baseline)."""
        return np.interp(np.asarray(tq, float), self._t, self._acc)


def reconstruct_flights(t_s, t_e, y_s, y_e, v_start, v_end, lo_velocity, lo_acceleration,
                        mu: float, theta_deg: float, steps: int = STEPS) -> dict:
    """Ball motion in flights under ``y'' = -mu g sgn(z') + g sin(theta)``.

    A constant acceleration ``g0 = g sin(theta)`` is absorbed by a change of frame:
    with ``Y = y - g0 (t - t_s)^2 / 2`` and the LO velocity ``V = x' - g0 (t - t_s)``
    the relative velocity is unchanged, ``Y'' = -mu g sgn(Y' - V)`` and the ball
    sticks while ``|x'' - g0| <= mu g``, which is the pure-friction problem solved by
    :func:`vidiscover.analysis.friction.solve_flights` (z' may change sign, the ball
    may stick and slide again). Without friction the flight is a parabola.

    Parameters
    ----------
    t_s, t_e, y_s, y_e : ndarray
        Flight start/end times (s) and ball positions (m).
    v_start, v_end : ndarray
        LO velocity just after the start and before the end impact (m/s).
    lo_velocity, lo_acceleration : callable
        LO velocity (without jumps inside a flight) and acceleration at times (s).
    mu : float
        Friction coefficient (>= 0).
    theta_deg : float
        Inclination (deg).
    steps : int
        Integration steps per flight.

    Returns
    -------
    dict
        ``t``, ``w`` (ball velocity), ``v`` (LO velocity), ``zd`` (z'), ``acc`` (LO
        acceleration), shape (n_flights, steps + 1), and ``closure`` (m).
    """
    t_s, t_e = np.asarray(t_s, float), np.asarray(t_e, float)
    y_s, y_e = np.asarray(y_s, float), np.asarray(y_e, float)
    v_start, v_end = np.asarray(v_start, float), np.asarray(v_end, float)
    F, M = t_s.size, int(steps)
    g0 = G_ACCEL * math.sin(math.radians(theta_deg))
    frac = np.linspace(0.0, 1.0, M + 1)
    dt = t_e - t_s
    T = t_s[:, None] + dt[:, None] * frac[None, :]
    V = np.asarray(lo_velocity(T), float).reshape(F, M + 1)
    V[:, 0], V[:, -1] = v_start, v_end
    A = np.asarray(lo_acceleration(T), float).reshape(F, M + 1)
    if mu <= 0.0 or F == 0:
        w = (y_e - y_s) / dt - g0 * dt / 2.0
        W = w[:, None] + g0 * (T - t_s[:, None])
        return {"t": T, "w": W, "v": V, "zd": W - V, "acc": A, "closure": np.zeros(F)}

    vel, acc = falling_frame(lo_velocity, lo_acceleration, g0)
    sol = solve_flights(t_s, t_e, y_s, y_e - g0 * dt ** 2 / 2.0, vel, acc, mu,
                        v_start=v_start, v_end=v_end - g0 * dt, steps=M)
    W = sol.w + g0 * (sol.t - t_s[:, None])
    zd = sol.w - (V - g0 * (T - t_s[:, None]))
    zd[np.abs(zd) < 1e-12] = 0.0
    return {"t": T, "w": W, "v": V, "zd": zd, "acc": A, "closure": sol.closure}



def solve_free_flights(data: FlightData, mu: float, theta_deg: float) -> dict:
    """Ball launch/arrival velocities of every free flight under a flight law.

    The flights of the reconstruction (each from its contact's exit to the next
    contact's entry) are solved again with friction ``mu`` and inclination
    ``theta_deg`` (:func:`reconstruct_flights`) along the measured LO motion.

    Parameters
    ----------
    data : FlightData
    mu : float
        Friction coefficient (negative values are taken as 0).
    theta_deg : float
        Inclination (deg).

    Returns
    -------
    dict
        Arrays over the flights of kind ``"free"``: ``flight`` (row in the flight
        table), ``t_start``, ``t_end``, ``w_start``, ``w_end`` (m/s), ``zd_start``,
        ``zd_end`` (relative velocities, m/s), ``sign_changes``.
    """
    mu, theta = max(float(mu), 0.0), float(theta_deg)
    k = np.flatnonzero(data.kind == "free")
    v0, v1 = data.exit_v[k], data.v_minus[data.i_e[k]]
    fl = reconstruct_flights(data.exit_t[k], data.te[k], data.exit_y[k],
                             data.y_imp[data.i_e[k]], v0, v1, data.lo_velocity,
                             data.lo_acceleration, mu, theta)
    zd = fl["zd"]
    nz = np.where(zd == 0, 0.0, np.sign(zd))
    changes = np.array([int(np.count_nonzero(np.diff(r[r != 0]))) for r in nz], dtype=np.int64)
    return {"flight": k, "t_start": data.exit_t[k], "t_end": data.te[k],
            "w_start": fl["w"][:, 0],
            "w_end": fl["w"][:, -1], "zd_start": fl["w"][:, 0] - v0,
            "zd_end": fl["w"][:, -1] - v1, "sign_changes": changes}
