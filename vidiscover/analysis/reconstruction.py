"""Stage 2: LO velocity, ball position and ball flights (paper Sec. 4-5, Figs. 7, 12-14).

**LO motion.** The pulse-free acceleration of stage 1 is integrated twice and the
impact velocity jumps (pulse areas) are added as exact steps; the integration
drift (accelerometer noise and bias, unknown initial velocity) is pinned to the
laser displacement by a local quadratic smoother of ``x_laser - x_integrated`` over
``drift_window`` seconds (a complementary filter: slow content from the laser, fast
content from the accelerometer). This gives the LO displacement ``x`` and velocity
``v`` with sharp jumps at the impacts (paper Fig. 13, "smooth curve"), free of the
laser's sheet resonance; ``v_disp`` is the laser derivative (the paper's
"nonsmooth curve"). Pre/post-impact velocities: ``v_minus`` from the integral,
``v_plus = v_minus + dv``.

**Time frame.** A causal anti-alias filter delays the laser as much as the
accelerometer (:func:`lo_lag`, its DC group delay); the impacts are timed at their
contact entries with that delay taken out, and ``analyze`` advances the smooth
acceleration by it. The impact states, the contact exits and the flights use the
integral pinned to the laser read as much later: pinned to the laser as recorded,
the LO velocity at an impact was off by the delay times the LO acceleration (dev-009,
343 us: r off by 0.009), and the laser's misfit (hundreds of micrometres on a hard-driven
rig) was taken for position noise, so that most impacts of such walls were left out as
"noisy". The arrays ``x`` and ``v`` stay pinned to the laser as recorded (the flights,
the gap diagnosis's laser residual and the shipped regime model read them); the ball's
position and velocity on a wall follow the impacts' frame. They mix the two frames:
their slow part is the laser's, their fast part the advanced acceleration's, so over
a forcing cycle x is neither the LO nor the LO ``lo_lag`` later (off by up to 1.5 % RMS
of max |x| on other-rig regime draws with a lag of 0.01 T; with the laser on its rails
the mixture is not periodic either: case 111 of seed 14001, a periodic motion, read a
stroboscopic state error of 0.0125 for a true 0.0003). :attr:`Reconstruction.x_impacts`
is the LO in the impacts' frame alone (0.0004 there).

**Ball.** At an impact on the wall of sign s (+1 right, -1 left) the ball is at
``y = x + s b`` (eq. 5). A compliant wall holds the ball for a contact duration
``tau`` (the learned pulse response's, per wall; 0 for the exact engine's rigid
walls): the ball arrives at the contact entry (the detected impact time) and leaves
at the exit ``t + tau``, from ``x(t + tau) + s b`` with the LO moving at
``v(t + tau)``, so its outgoing flight starts there and ``u+`` is taken there
(a learned arch-shaped force releases it at twice the force's centroid instead,
which the pulses fix better than the duration: :func:`_release_durations`). On a
rig whose LO accelerates hard during a long contact this is what r compares (its
entry and exit speeds); an impact taken as instantaneous at the entry misreads it.
Between consecutive contacts the ball flies:

* without friction (``mu = 0``) in a straight line (eq. 6);
* with friction by :func:`~vidiscover.analysis.friction.solve_flights` (eq. 8
  generalised: z' may change sign, the ball may stick to the LO and slide again).

**Sticking after chatter.** A weak wall (r ~ 0.2) makes the ball chatter: the
re-impacts shrink geometrically and the last ones are too weak to be seen (see
:mod:`~vidiscover.analysis.validation`); the ball then rides the wall until the LO
acceleration lets it go (left wall: until x'' < -mu g; right wall: until
x'' > mu g) and leaves it with the wall's velocity. A straight line from the last
*seen* re-impact would be wrong. For every flight between opposite walls whose
start wall can hold the ball, the *stick-then-fly* hypothesis is tested: the ball
leaves at the release time with the LO velocity and must arrive within
``stick_tol`` of the measured next impact position, or within the distance its
approach speed covers in :data:`STICK_ARRIVAL_DT` (the next entry's timing error), if
that is more. On a tilted base (``theta_deg``, the flight law's) the wall lets the
ball go when the LO's acceleration falls below the ball's own along the base,
``g sin(theta)`` (+/- mu g), and the ball flies a parabola. If the hypothesis holds,
the flight is of kind ``"stick"`` (ball on the wall until ``t_release``, then free);
otherwise ``"free"``. The rebound of the impact starting a ``"stick"`` flight is not
observable (its r is left undefined by stage 3).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from ..acquisition import dc_group_delay, shape_centroid
from ..errors import InputError
from ..params import G_ACCEL
from ._table import check_columns, to_frame
from .friction import falling_frame, integrate_flights, solve_flights
from .impacts import ImpactDetection
from .signals import fill_gaps, quadratic_smoother, robust_std

if TYPE_CHECKING:      # pandas is imported where a table is built, not to analyse
    import pandas as pd

__all__ = ["Reconstruction", "reconstruct", "FLIGHT_COLUMNS", "IMPACT_STATE_COLUMNS"]

#: Columns of :attr:`Reconstruction.flights`.
FLIGHT_COLUMNS = ("i_start", "i_end", "t_start", "t_end", "duration", "side_start",
                  "side_end", "kind", "t_release", "y_start", "y_end", "x_start", "x_end",
                  "v_start", "v_end", "w_start", "w_end", "w_mean", "zd_start", "zd_end",
                  "penetration", "closure", "sign_changes", "y_release")
#: Columns of :attr:`Reconstruction.impacts`.
IMPACT_STATE_COLUMNS = ("t", "side", "x", "y", "v_minus", "v_plus", "dv", "w_minus",
                        "w_plus", "u_minus", "u_plus", "flight_in", "flight_out")

_BLOCK = 16                 # samples per block of the drift smoother
_PEN_STEP = 4               # wall penetration is checked every _PEN_STEP samples
_PEN_PART = 1 << 16         # checked samples per part (bounds the temporaries)
_PART = 1 << 16             # samples per part of the drift's evaluation
#: Arrival-time error (s) the stick-then-fly test allows at the next contact entry, on
#: top of ``stick_tol``: the detected entries are tens of us off on compliant walls (dev-011,
#: Kelvin-Voigt: 20-30 us early at 6.6 m/s, 1.3e-4 m of closure; holdout11-000: 29 us
#: at 2.3 m/s), the bench's timing target is 50 us.
STICK_ARRIVAL_DT = 50e-6
_RAIL_RUN = 8               # samples in a row at the laser's extreme value: a rail


@dataclass(frozen=True, eq=False)
class Reconstruction:
    """Reconstructed LO and ball motion (stage 2 result).

    Attributes
    ----------
    t : ndarray
        Sample times (s).
    x : ndarray
        LO displacement from the drift-corrected integrated acceleration (m).
    v : ndarray
        LO velocity from the drift-corrected integrated acceleration (m/s); at an
        impact sample it is the value after all earlier jumps.
    v_disp : ndarray
        LO velocity from differentiating the laser displacement (m/s).
    impact_columns : Mapping[str, ndarray]
        Per impact, keys :data:`IMPACT_STATE_COLUMNS`: LO displacement ``x``, ball
        position ``y``, LO velocities ``v_minus``/``v_plus``, ball velocities
        ``w_minus``/``w_plus`` (end of the incoming / start of the outgoing flight),
        relative velocities ``u = w - v`` and the flight indices (-1: none).
        DataFrame: :attr:`impacts`.
    flight_columns : Mapping[str, ndarray]
        One entry per pair of consecutive impacts, keys :data:`FLIGHT_COLUMNS`
        (``kind`` "free" or "stick"; ``penetration``: how far the reconstructed ball
        goes through a wall, m; ``closure``: arrival error of the stick-then-fly
        hypothesis, m, NaN when not a candidate; velocities in m/s).
        DataFrame: :attr:`flights`.
    b : float
        Half-clearance used (m).
    mu : float
        Friction coefficient assumed.
    position_noise : float
        Robust RMS of laser minus reconstructed LO displacement (m), the ball
        position uncertainty used by stage 3 (the laser read :func:`lo_lag` later,
        against the LO of the impacts' frame).
    laser_rail_share : float
        Share of the laser's finite samples on its rails (its extreme value, held for
        several samples: driven past its range); those samples do not pin the LO of the
        impacts' frame. 0 when the laser never saturates.
    """

    t: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    v: np.ndarray = field(repr=False)
    v_disp: np.ndarray = field(repr=False)
    impact_columns: Mapping[str, np.ndarray] = field(repr=False)
    flight_columns: Mapping[str, np.ndarray] = field(repr=False)
    b: float
    mu: float
    position_noise: float
    laser_rail_share: float = 0.0
    _traj: dict = field(default_factory=dict, repr=False)
    _shift: object = field(default=None, repr=False)

    def __post_init__(self) -> None:
        for name in ("x", "v", "v_disp"):
            if getattr(self, name).shape != self.t.shape:
                raise ValueError(f"{name} must have the shape of t {self.t.shape}, "
                                 f"has {getattr(self, name).shape}")
        check_columns(self.impact_columns, IMPACT_STATE_COLUMNS, "Reconstruction impacts")
        check_columns(self.flight_columns, FLIGHT_COLUMNS, "Reconstruction flights")

    @functools.cached_property
    def x_impacts(self) -> np.ndarray:
        """LO displacement in the impacts' time frame (m), at the sample times ``t``.

        The integrated acceleration pinned to the laser read :func:`lo_lag` later: one
        time frame throughout, that of the detected impacts (``x`` pinned to the laser
        as recorded mixes two, see the module docs). ``x`` itself (not a copy) without
        a causal filter's lag. Read-only.
        """
        if self._shift is None:
            return self.x
        out = np.array(self.x, dtype=float)
        tr0 = self.t[0]
        for lo in range(0, out.size, _PART):      # the shift by parts: never whole
            part = slice(lo, lo + _PART)
            out[part] += self._shift(self.t[part] - tr0)[0]
        out.flags.writeable = False
        return out

    @functools.cached_property
    def impacts(self) -> pd.DataFrame:
        """Per-impact states as a DataFrame (columns :data:`IMPACT_STATE_COLUMNS`)."""
        return to_frame(self.impact_columns, IMPACT_STATE_COLUMNS)

    @functools.cached_property
    def flights(self) -> pd.DataFrame:
        """Flight segments as a DataFrame (columns :data:`FLIGHT_COLUMNS`)."""
        return to_frame(self.flight_columns, FLIGHT_COLUMNS)

    @property
    def n_flights(self) -> int:
        """Number of flight segments."""
        return int(self.flight_columns["t_start"].size)

    def ball_position(self, t) -> np.ndarray:
        """Reconstructed ball position at times ``t`` (m); NaN outside the flights."""
        return self._ball(t)[0]

    def ball_velocity(self, t) -> np.ndarray:
        """Reconstructed ball velocity at times ``t`` (m/s); NaN outside the flights."""
        return self._ball(t)[1]

    def _ball(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        y = np.full(t.shape, np.nan)
        w = np.full(t.shape, np.nan)
        fl = self.flight_columns
        nf = self.n_flights
        if nf == 0:
            return y, w
        ts, te = fl["t_start"], fl["t_end"]
        k = np.searchsorted(ts, t, side="right") - 1
        inside = (k >= 0) & (t <= te[np.clip(k, 0, None)])
        k = np.clip(k, 0, nf - 1)
        tr = fl["t_release"][k]
        side = np.where(fl["side_start"][k] == "right", 1.0, -1.0)
        on_wall = inside & (t < tr)
        if on_wall.any():
            y[on_wall] = np.interp(t[on_wall], self.t, self.x) + side[on_wall] * self.b
            w[on_wall] = np.interp(t[on_wall], self.t, self.v)
            if self._shift is not None:          # the LO of the impacts' frame
                dx, dv = self._shift(t[on_wall] - self.t[0])
                y[on_wall] += dx
                w[on_wall] += dv
        free = inside & ~on_wall
        kk = k[free]
        tt = t[free]
        if self._traj:
            T, Y, Wt = self._traj["t"], self._traj["y"], self._traj["w"]
            Tr = T[kk]
            pos = np.clip((tt - Tr[:, 0]) / (Tr[:, -1] - Tr[:, 0]) * (T.shape[1] - 1),
                          0, T.shape[1] - 1 - 1e-9)
            i0 = pos.astype(int)
            f = pos - i0
            y[free] = Y[kk, i0] * (1 - f) + Y[kk, i0 + 1] * f
            w[free] = Wt[kk, i0] * (1 - f) + Wt[kk, i0 + 1] * f
        else:
            slope = fl["w_end"][kk]
            y[free] = fl["y_release"][kk] + slope * (tt - fl["t_release"][kk])
            w[free] = slope
        return y, w


def reconstruct(det: ImpactDetection, rec, b: float | None = None, mu: float = 0.0, *,
                drift_window: float = 0.1, stick_tol: float | None = None,
                theta_deg: float = 0.0) -> Reconstruction:
    """Reconstruct the LO velocity and the ball motion from detected impacts.

    Parameters
    ----------
    det : ImpactDetection
        Stage 1 result for ``rec``.
    rec : Recording
        The recording (its laser displacement pins the integration drift).
    b : float, optional
        Half-clearance (m); default ``rec.meta.b``.
    mu : float
        Friction coefficient assumed between ball and LO (paper eq. 8).
    drift_window : float
        Window of the drift smoother (s).
    stick_tol : float, optional
        Largest arrival error (m) of the stick-then-fly hypothesis; default
        ``max(2e-5, 0.01 * b)``.
    theta_deg : float
        Inclination of the base (deg; the flight law's), for the stick-then-fly
        hypothesis only: the ball leaves the wall when the LO's acceleration less
        ``g sin(theta)`` lets it go and flies a parabola from there. The free flights
        stay friction-only (``analyze`` solves them again under the flight law).

    Returns
    -------
    Reconstruction

    Raises
    ------
    InputError
        If ``b``, ``mu``, ``drift_window`` or ``theta_deg`` are out of range.
    """
    b = float(rec.meta.b if b is None else b)
    if not (math.isfinite(b) and b > 0):
        raise InputError(f"b must be > 0 m (half-clearance), was {b!r}")
    if not (math.isfinite(mu) and 0 <= mu <= 2):
        raise InputError(f"mu must be in [0, 2] (friction coefficient), was {mu!r}")
    if not (math.isfinite(drift_window) and drift_window > 0):
        raise InputError(f"drift_window must be > 0 s, was {drift_window!r}")
    g0 = _tilt_acceleration(theta_deg)
    stick_tol = max(2e-5, 0.01 * b) if stick_tol is None else float(stick_tol)
    fs = det.sample_rate
    t = np.asarray(rec.t, dtype=float)
    n = t.size
    tr = t - t[0]
    t_imp = det.t
    dv = det.dv
    side = det.sign.astype(float)

    # ---- LO motion: integrate the pulse-free acceleration, add the jumps exactly
    a = det.a_smooth
    dt = 1.0 / fs
    V_s = np.empty(n)
    V_s[0] = 0.0
    # (0.5 (a[1:] + a[:-1]) dt made in V_s itself: the same operations, no temporaries)
    vs = V_s[1:]
    np.add(a[1:], a[:-1], out=vs)
    np.multiply(0.5, vs, out=vs)
    np.multiply(vs, dt, out=vs)
    np.cumsum(vs, out=vs)
    del vs
    ti = t_imp - t[0]
    # states at the impacts: linear interpolation between the samples about them
    # (taken from each full-length array as soon as it is made, so it can be dropped)
    k = _clip_index(np.searchsorted(tr, ti, side="right") - 1, 0, n - 2)
    f = (ti - tr[k]) * fs
    lin = lambda arr: arr[k] * (1 - f) + arr[k + 1] * f          # noqa: E731
    cdv = np.concatenate([[0.0], np.cumsum(dv)])
    tj = _jump_times(det, ti)
    cdvt = np.concatenate([[0.0], np.cumsum(dv * tj)])
    # jumps of the impacts strictly before each sample, as running sums
    first = _first_samples(t, tj, fs)
    # (full-length arrays are combined in place and dropped when done: a long record
    # holds millions of samples per array)
    # (float even without impacts: bincount of no weights is an integer array)
    S = np.bincount(first, weights=dv, minlength=n + 1)[:n].astype(float, copy=False)
    np.cumsum(S, out=S)
    lin_V = lin(V_s)
    # X_raw = X_s + S tr - SdT: the integral X_s of V_s and the running sum SdT of the
    # jumps' dv t_i are made part by part, never whole (each a sequential sum with the
    # previous part's last value folded into its first term: the whole cumsum's values)
    X_raw = S * tr
    X_k, X_k1 = np.empty(k.size), np.empty(k.size)
    dvt = dv * tj
    carry = carry_t = 0.0
    for lo in range(0, n, _PART):
        hi = min(lo + _PART, n)
        xs = np.empty(hi - lo)
        if lo == 0:
            xs[0] = 0.0
            np.add(V_s[1:hi], V_s[:hi - 1], out=xs[1:])
        else:
            np.add(V_s[lo:hi], V_s[lo - 1:hi - 1], out=xs)
        # (0.5 (..) dt in place: the same operations; 0 stays 0 in the first part)
        np.multiply(0.5, xs, out=xs)
        np.multiply(xs, dt, out=xs)
        if lo:
            xs[0] += carry
        np.cumsum(xs, out=xs)
        carry = xs[-1]
        for arr, at in ((X_k, k), (X_k1, k + 1)):
            here = (at >= lo) & (at < hi)
            arr[here] = xs[at[here] - lo]
        X_raw[lo:hi] += xs               # the operations and their order of X_s + S tr - SdT
        del xs
        sel = (first >= lo) & (first < hi)
        sdt = np.bincount(first[sel] - lo, weights=dvt[sel], minlength=hi - lo).astype(
            float, copy=False)
        sdt[0] += carry_t
        np.cumsum(sdt, out=sdt)
        carry_t = sdt[-1]
        X_raw[lo:hi] -= sdt
        del sdt
    lin_X = X_k * (1 - f) + X_k1 * f      # lin(X_s)
    xl = np.asarray(rec.x, dtype=float)
    okx = np.isfinite(xl)
    if not okx.any():
        raise InputError(f"{rec.name}: column 'x' has no finite value; the laser "
                         "displacement is needed to reconstruct the motion")
    lag = lo_lag(det)
    rails = _laser_rails(xl, okx)
    # the LO is pinned to the laser's finite samples off its rails, as recorded and (a
    # causal instrument) in the impacts' time frame: a saturated laser reads its full
    # scale, not the LO (holdout4-011, a 10 mm laser on a 16 mm LO, 58 % of the samples
    # on a rail: pinned to them, the LO's velocity inside the flights was 0.06-0.1 m/s
    # off and the left wall's r under friction 0.62 for 0.38)
    pin = okx if rails is None else okx & ~rails
    drift = _drift(tr, xl, X_raw, pin, fs, drift_window)     # D and Dd at any times
    if lag > 0:
        # the laser read in the impacts' time frame (see lo_lag), between its finite
        # samples off its rails (a sample counts when both samples about its advanced
        # time count)
        xl_a = _advanced(np.where(pin, xl, 0.0), tr, lag)
        ok_a = _advanced(pin.astype(float), tr, lag) == 1.0
        drift_a = _drift(tr, xl_a, X_raw, ok_a, fs, drift_window)
        shift = _Shift(drift, drift_a)
    else:
        xl_a, ok_a, drift_a, shift = xl, pin, drift, None
    (D0, Dd0), (D1, Dd1) = drift_a(tr[k]), drift_a(tr[k + 1])     # about each impact
    lin_D, lin_Dd = D0 * (1 - f) + D1 * f, Dd0 * (1 - f) + Dd1 * f    # lin(D), lin(Dd)
    x_f = X_raw                      # X_raw + D
    del X_raw
    v_f = np.add(V_s, S, out=S)      # V_s + S + Dd
    del S
    VD = V_s                         # V_s + Dd: the LO velocity between the jumps
    del V_s
    for lo in range(0, n, _PART):    # D and Dd by parts: never whole
        part = slice(lo, lo + _PART)
        D, Dd = drift(tr[part])
        x_f[part] += D
        VD[part] += Dd
        v_f[part] += Dd
    # (the laser against the LO of the impacts' frame: x_f + shift)
    if ok_a.all():
        step = max(1, n // 8192)
        resid = xl_a[::step] - x_f[::step]
        if shift is not None:
            resid -= shift(tr[::step])[0]
    else:
        sel = np.flatnonzero(ok_a)
        sel = sel[:: max(1, sel.size // 8192)]
        resid = xl_a[sel] - x_f[sel]
        if shift is not None:
            resid -= shift(tr[sel])[0]
    del xl_a, ok_a, drift_a
    position_noise = max(robust_std(resid), 1e-9)

    # ---- states at the impacts
    before = cdv[:-1]                                          # jumps strictly before
    x_imp = lin_X + before * ti - cdvt[:-1] + lin_D
    v_minus = lin_V + before + lin_Dd
    v_plus = v_minus + dv
    y_imp = x_imp + side * b

    def lo_velocity(tq):
        out = np.interp(tq - t[0], tr, VD) + cdv[np.searchsorted(tj, tq - t[0])]
        return out if shift is None else out + shift(tq - t[0])[1]

    def lo_acc(tq):
        return np.interp(tq - t[0], tr, det.baseline)

    def lo_x(tq):
        out = np.interp(tq - t[0], tr, x_f)
        return out if shift is None else out + shift(tq - t[0])[0]

    exits = _exits(det, t_imp, side, x_imp, v_plus, b, lo_x, lo_velocity)
    flights, traj = _flights(t_imp, side, x_imp, y_imp, v_minus, b, mu, t, x_f,
                             det.baseline, fs, stick_tol, lo_x, lo_acc, lo_velocity, exits,
                             shift, g0)
    del lo_velocity, lo_acc, lo_x
    tr = None                        # (dropped before the laser derivative)
    VD = None                        # (dropped before the next full-length array)
    xl_f = fill_gaps(xl, ~okx) if not okx.all() else xl
    v_disp = _gradient(xl_f, dt)
    del xl_f
    impacts = _impact_columns(t_imp, det.side, x_imp, y_imp, v_minus, v_plus, dv, flights,
                              exits[3])
    return Reconstruction(t=t, x=x_f, v=v_f, v_disp=v_disp, impact_columns=impacts,
                          flight_columns=flights, b=b, mu=float(mu),
                          position_noise=float(position_noise),
                          laser_rail_share=0.0 if rails is None else
                          float(rails.sum() / max(int(okx.sum()), 1)),
                          _traj=traj, _shift=shift)


def _gradient(y: np.ndarray, h: float) -> np.ndarray:
    """``np.gradient(y, h)``: central differences inside, one-sided at the ends."""
    out = np.empty_like(y)
    if y.size < 2:
        out[:] = 0.0
        return out
    np.subtract(y[2:], y[:-2], out=out[1:-1])
    out[1:-1] /= 2.0 * h
    out[0] = (y[1] - y[0]) / h
    out[-1] = (y[-1] - y[-2]) / h
    return out


def _drift(tr, xl, x_raw, ok, fs, window):
    """Slow drift D (m) and its derivative (m/s) of the residual ``e = xl - x_raw``.

    By a local quadratic (Savitzky-Golay) smoother of block means of ``e`` over the
    ``ok`` samples (the residual is formed a few thousand blocks at a time). Returns
    the function ``times (s from the first sample) -> (D, Dd)`` (point by point).

    A block only partly ``ok`` (a saturated laser's rail or a gap begins or ends in
    it) has its mean at its ``ok`` samples' mean time, not at its centre: the mean is
    carried to the centre along the drift's local slope (:func:`_centred`). The drift
    of an integrated acceleration is steep (the unknown initial velocity: 2.4 m/s on
    other-rig regime case 111 of seed 14001, a laser 61 % on its rails), and read at
    the centres as they were, the means were off by up to 7 mm and the smoothed drift
    wandered by 2 mm (8 % of the LO amplitude) at the forcing's beat with the rails.
    """
    n = tr.size
    B = _BLOCK if n >= 8 * _BLOCK else 1
    nb = n // B
    cut = nb * B

    def e(lo, hi):
        return np.subtract(xl[lo:hi], x_raw[lo:hi], out=np.zeros(hi - lo), where=ok[lo:hi])

    eb = np.empty(nb)
    step = B * 4096
    for lo in range(0, cut, step):
        hi = min(lo + step, cut)
        # (e is 0 off the ok samples already: the same sums as e * ok)
        eb[lo // B:hi // B] = e(lo, hi).reshape(-1, B).sum(axis=1)
    cb = ok[:cut].reshape(nb, B).sum(axis=1)
    tb = tr[:cut].reshape(nb, B).mean(axis=1)
    # the last n - cut samples (fewer than a block) make no block of their own: the
    # drift is extended over them along its slope. As one more, shorter block, the
    # smoother placed it a block apart from the one before while its mean lay up to a
    # block later, on a residual as steep as the LO's unknown initial velocity (3.4 m/s
    # x 1.07 ms on holdout6-009), and the drift's edge fit followed it: the LO position
    # was off by up to 0.9 mm over the last 50 ms of records whose length is not a
    # multiple of the block (holdout6/7/8, dev), 9-36 um on the exact engine
    good = cb > 0
    mean = np.where(good, eb / np.maximum(cb, 1), 0.0)
    h = B / fs
    win = int(round(window / h)) | 1
    win = max(5, min(win, mean.size if mean.size % 2 else mean.size - 1))
    partial = good & (cb < B)
    if partial.any() and mean.size >= 5:
        return _centred(tr, ok, B, cut, tb, cb, good, mean, win, h)
    if not good.all():
        mean = fill_gaps(mean, ~good)
    if mean.size < 5:
        c = np.polyfit(tb, mean, min(1, mean.size - 1)) if mean.size > 1 else np.r_[mean]
        return _PolyDrift(c)
    Db, Ddb = quadratic_smoother(mean, win, h)
    return _SmoothDrift(tb, Db, Ddb)


#: Passes of :func:`_centred`'s slope correction (each takes the slope of the last).
_CENTRE_PASSES = 3


def _centred(tr, ok, B, cut, tb, cb, good, mean, win, h):
    """The drift of :func:`_drift` from block means not all taken at their centres.

    Each partial block's mean is read at its ``ok`` samples' mean time ``tm`` and
    carried to the centre along the drift's slope there: first a quadratic fitted to
    all the means at their times (weighted by their counts), then, for
    :data:`_CENTRE_PASSES` passes, the smoothed drift's own derivative. Blocks without
    an ``ok`` sample are filled linearly between the centred means (along the slope
    beyond the first and last).
    """
    tsum = np.zeros(tb.size)
    step = B * 4096
    for lo in range(0, cut, step):
        hi = min(lo + step, cut)
        tsum[lo // B:hi // B] = np.where(ok[lo:hi], tr[lo:hi], 0.0).reshape(-1, B).sum(axis=1)
    off = np.where(good, tsum / np.maximum(cb, 1) - tb, 0.0)   # tm - tb
    tg = tb[good]
    deg = min(2, int(good.sum()) - 1)
    c = np.polyfit(tg + off[good], mean[good], deg, w=np.sqrt(cb[good]))
    slope = np.polyval(np.polyder(c), tb) if deg > 0 else np.zeros(tb.size)
    gi = np.flatnonzero(good)
    for _ in range(_CENTRE_PASSES):
        m = mean - slope * off
        if gi.size < tb.size:
            # between centred means linearly; beyond the first/last along its slope
            m = np.interp(tb, tg, m[gi])
            for sel, k in ((tb < tg[0], gi[0]), (tb > tg[-1], gi[-1])):
                m[sel] = (mean[k] - slope[k] * off[k]) + slope[k] * (tb[sel] - tb[k])
        Db, Ddb = quadratic_smoother(m, win, h)
        slope = Ddb
    return _SmoothDrift(tb, Db, Ddb)


class _PolyDrift:
    """The drift of a short record: a polynomial of degree <= 1.

    A plain object, so that a reconstruction holding it pickles (a sweep's worker
    sends it back, a benchmark caches it).
    """

    def __init__(self, c: np.ndarray) -> None:
        self.c = c

    def __call__(self, x):
        c = self.c
        return (np.polyval(c, x),
                np.polyval(np.polyder(c), x) if c.size > 1 else np.zeros(x.size))


class _SmoothDrift:
    """The smoothed drift at the block centres ``tb``.

    Read between them linearly and beyond the first/last centre along the local slope.
    A plain object: it pickles (see :class:`_PolyDrift`).
    """

    def __init__(self, tb: np.ndarray, Db: np.ndarray, Ddb: np.ndarray) -> None:
        self.tb, self.Db, self.Ddb = tb, Db, Ddb

    def __call__(self, x):
        tb, Db, Ddb = self.tb, self.Db, self.Ddb
        D = np.interp(x, tb, Db)
        Dd = np.interp(x, tb, Ddb)
        for sel, k in ((x < tb[0], 0), (x > tb[-1], -1)):
            D[sel] = Db[k] + Ddb[k] * (x[sel] - tb[k])
        return D, Dd


def refly(recon: Reconstruction, det: ImpactDetection, mu: float, *,
          stick_tol: float | None = None, theta_deg: float = 0.0) -> Reconstruction:
    """The ball's flights solved again under friction ``mu``, on the same LO motion.

    The LO motion (displacement, velocity, the states at the impacts) does not depend
    on the friction assumed for the ball, so the friction table (paper Table 2) needs
    it once: this reuses ``recon``'s arrays (no full-length array is made) and equals
    ``reconstruct(det, rec, recon.b, mu)`` up to the rounding of one subtraction in the
    LO velocity between samples (~1e-16 m/s).

    Parameters
    ----------
    recon : Reconstruction
        A reconstruction of ``det`` (any ``mu``).
    det : ImpactDetection
        The detection it was made from.
    mu : float
        Friction coefficient assumed between ball and LO.
    stick_tol : float, optional
        As in :func:`reconstruct`.
    theta_deg : float
        As in :func:`reconstruct` (the stick-then-fly hypothesis's inclination).

    Returns
    -------
    Reconstruction
    """
    if not (math.isfinite(mu) and 0 <= mu <= 2):
        raise InputError(f"mu must be in [0, 2] (friction coefficient), was {mu!r}")
    g0 = _tilt_acceleration(theta_deg)
    b = recon.b
    stick_tol = max(2e-5, 0.01 * b) if stick_tol is None else float(stick_tol)
    t, v = recon.t, recon.v
    fs = det.sample_rate
    tr0, n = t[0], t.size
    tj = _jump_times(det, det.t - tr0)
    dv = det.dv
    cdv = np.concatenate([[0.0], np.cumsum(dv)])
    first = _first_samples(t, tj, fs)       # the sample from which each jump counts in v

    def lo_velocity(tq):
        # v less the jumps counted in it, interpolated between the two samples about
        # tq, plus the jumps strictly before tq
        tq = np.asarray(tq, dtype=float)
        tc = np.clip(tq, t[0], t[-1])
        j = np.clip(np.searchsorted(t, tc, side="right") - 1, 0, n - 2)
        v0 = v[j] - cdv[np.searchsorted(first, j, side="right")]
        v1 = v[j + 1] - cdv[np.searchsorted(first, j + 1, side="right")]
        slope = (v1 - v0) / (t[j + 1] - t[j])
        out = slope * (tc - t[j]) + v0 + cdv[np.searchsorted(tj, tq - tr0)]
        return out if shift is None else out + shift(tq - tr0)[1]

    def lo_acc(tq):
        return np.interp(tq, t, det.baseline)

    def lo_x(tq):
        out = np.interp(tq, t, recon.x)
        return out if shift is None else out + shift(tq - tr0)[0]

    ic = recon.impact_columns
    side = det.sign.astype(float)
    shift = recon._shift
    exits = _exits(det, det.t, side, ic["x"], ic["v_plus"], b, lo_x, lo_velocity)
    flights, traj = _flights(det.t, side, ic["x"], ic["y"], ic["v_minus"], b, float(mu), t,
                             recon.x, det.baseline, fs, stick_tol, lo_x, lo_acc, lo_velocity,
                             exits, shift, g0)
    impacts = _impact_columns(det.t, det.side, ic["x"], ic["y"], ic["v_minus"],
                              ic["v_plus"], dv, flights, exits[3])
    return Reconstruction(t=t, x=recon.x, v=v, v_disp=recon.v_disp, impact_columns=impacts,
                          flight_columns=flights, b=b, mu=float(mu),
                          position_noise=recon.position_noise,
                          laser_rail_share=recon.laser_rail_share, _traj=traj, _shift=shift)


def _tilt_acceleration(theta_deg) -> float:
    """``g sin(theta)`` (m/s^2) of an inclination in degrees, checked."""
    if not (isinstance(theta_deg, (int, float, np.floating, np.integer))
            and math.isfinite(theta_deg) and -90 < theta_deg < 90):
        raise InputError(f"theta_deg (inclination of the base) must be a finite number of "
                         f"degrees in (-90, 90), was {theta_deg!r}")
    return G_ACCEL * math.sin(math.radians(float(theta_deg))) if theta_deg else 0.0


def _impact_columns(t_imp, side_names, x_imp, y_imp, v_minus, v_plus, dv, flights,
                    v_exit) -> dict:
    """Per-impact states, the ball's velocities taken from the flights about each.

    ``u_plus`` is taken at the contact exit (LO velocity ``v_exit``; ``v_plus`` for an
    instantaneous impact), ``u_minus`` at the entry.
    """
    m = t_imp.size
    w_minus = np.full(m, np.nan)
    w_plus = np.full(m, np.nan)
    f_in = np.full(m, -1, dtype=np.int64)
    f_out = np.full(m, -1, dtype=np.int64)
    nf = flights["t_start"].size
    if nf:
        i_s, i_e = flights["i_start"], flights["i_end"]
        w_plus[i_s] = flights["w_start"]
        w_minus[i_e] = flights["w_end"]
        f_out[i_s] = np.arange(nf)
        f_in[i_e] = np.arange(nf)
    return {
        "t": t_imp, "side": side_names, "x": x_imp, "y": y_imp, "v_minus": v_minus,
        "v_plus": v_plus, "dv": dv, "w_minus": w_minus, "w_plus": w_plus,
        "u_minus": w_minus - v_minus, "u_plus": w_plus - v_exit,
        "flight_in": f_in, "flight_out": f_out}


def contact_durations(det: ImpactDetection) -> np.ndarray:
    """Contact duration (s) of each detected impact: its wall's, from the pulse response.

    The learned response's ``tau`` per wall (:class:`.pulse.PulseResponse`), or the
    given pulse model's (0 for the exact engine's rigid walls).
    """
    sign = np.asarray(det.sign, dtype=float)
    resp = getattr(det, "response", None)
    if resp is not None:
        taus = (float(resp.model_for(1).tau), float(resp.model_for(-1).tau))
    else:
        tau = float(getattr(getattr(det, "pulse", None), "tau", 0.0) or 0.0)
        taus = (tau, tau)
    tau = np.where(sign > 0, taus[0], taus[1])
    return np.where(np.isfinite(tau) & (tau > 0), tau, 0.0)


def force_centroids(det, tau: np.ndarray | None = None) -> np.ndarray:
    """Time (s) from each detected contact entry to the centroid of its force.

    The learned pulse response's contact shape per wall (``shape_centroid(skew, phase)
    tau``), or the given pulse model's; 0 for instantaneous impacts. The detection fits
    each pulse's timing through its centroid, so the entry plus this is the force's
    centroid as the data place it, even where the learned duration is off
    (Hunt-Crossley walls: learned 27-65 % too long on holdout6-006/-010, the centroids
    within 2-5 us of the true equivalent impacts).

    Parameters
    ----------
    det : ImpactDetection
    tau : ndarray, optional
        Contact durations per impact (:func:`contact_durations`), when known.

    Returns
    -------
    ndarray
        One value per detected impact (s).
    """
    sign = np.asarray(det.sign, dtype=float)
    if tau is None:
        tau = contact_durations(det)
    resp = getattr(det, "response", None)
    if resp is not None:
        frac = [shape_centroid(float(getattr(m, "skew", 0.0)), float(getattr(m, "phase", 0.0)))
                for m in (resp.model_for(1), resp.model_for(-1))]
    else:
        m = getattr(det, "pulse", None)
        frac = [shape_centroid(float(getattr(m, "skew", 0.0) or 0.0),
                               float(getattr(m, "phase", 0.0) or 0.0))] * 2
    out = np.where(sign > 0, frac[0], frac[1]) * np.asarray(tau, float)
    return np.where(np.isfinite(out) & (out > 0), out, 0.0)


def _release_durations(det: ImpactDetection) -> np.ndarray:
    """Time (s) from each contact entry to the ball's release: ``2 c tau`` per wall.

    ``c tau`` is the centroid of the learned contact force (``c = 1/2`` for the
    half-sine: the release at ``tau``, :func:`contact_durations`, bit for bit). The
    ball's outgoing flight, extended back into the contact, is that of an impulse at
    the force's centroid, whatever the force's shape; it is back on the wall at twice
    the centroid for an elastic contact. A learned arch (``skew`` != 0) trades its
    duration against the filter's cut-off and kind: behind a 1.7 kHz Bessel filter
    at 5120 Hz (test-006) a front-loaded arch of 1.03 ms (centroid 0.17 ms) fits the
    pulses better than the true 0.12-0.17 ms contact behind the true filter. Its
    centroid is what the pulses fix; its duration is not (released at ``tau``, r was
    off by 0.043; at ``2 c tau``, 0.001-0.004). A viscous wall's shape (``phase`` >
    0) releases the ball at the force's zero, ``tau``, as before.
    """
    tau = contact_durations(det)
    resp = getattr(det, "response", None)
    if resp is None or not np.any(tau > 0):
        return tau
    sign = np.asarray(det.sign, dtype=float)
    for s in (1, -1):
        m = resp.model_for(s)
        if m.skew != 0.0 and m.phase == 0.0 and m.tau > 0:
            here = (sign > 0) if s > 0 else (sign <= 0)
            tau = np.where(here, 2.0 * shape_centroid(m.skew, 0.0) * m.tau, tau)
    return tau


def lo_lag(det: ImpactDetection) -> float:
    """Low-frequency delay (s) of the recording's anti-alias filter, as learned.

    A causal anti-alias filter delays the laser, the accelerometer and the base sensor
    alike; at the LO's frequencies by its DC group delay
    (:func:`vidiscover.acquisition.dc_group_delay`, the centroid of its impulse
    response). The impacts are detected at their contact entries, this delay taken
    out. The detection's smooth acceleration (``a_smooth``, ``baseline``) is expected
    advanced by this delay (``analyze`` does it); :func:`reconstruct` pins its
    integral to the laser read ``lo_lag`` later (:func:`_advanced`) for the impact
    states, the exits and the flights, so that the LO motion and the impacts share one
    time frame. 0 for a ``linear-phase`` chain (delay-compensated) and for the exact
    engine's given pulse model.
    """
    resp = getattr(det, "response", None)
    model = resp.model if resp is not None else getattr(det, "pulse", None)
    if model is None or not getattr(model, "causal", False):
        return 0.0
    lag = dc_group_delay(model.kind, model.order, model.cutoff) / float(det.sample_rate)
    return float(lag) if math.isfinite(lag) and lag > 0 else 0.0


class _Shift:
    """The LO of the impacts' time frame less the LO as recorded, ``(dx, dv)``.

    Both are the integrated acceleration pinned to the laser by the drift smoother
    (:func:`_drift`): as recorded (``drift``; the arrays :attr:`Reconstruction.x` and
    ``v``, which the regime features read) and read :func:`lo_lag` later
    (``drift_a``; the impact states, the exits and the flights). They differ by the
    difference of the two smooth drifts only: called with times from the first sample.
    """

    def __init__(self, drift, drift_a):
        self.drift, self.drift_a = drift, drift_a

    def __call__(self, x):
        x = np.asarray(x, dtype=float)
        flat = np.atleast_1d(x).ravel()
        (D0, Dd0), (D1, Dd1) = self.drift(flat), self.drift_a(flat)
        return (D1 - D0).reshape(x.shape), (Dd1 - Dd0).reshape(x.shape)


def _laser_rails(xl: np.ndarray, ok: np.ndarray) -> np.ndarray | None:
    """Samples of a saturated laser (its rails), None when it never saturates.

    A laser beyond its range reads its full scale: the record's extreme value, held
    for as long as the LO stays out there. Pinned to those samples, the integrated
    acceleration was pulled onto the rail (test-033, a 10 mm laser on a 10.7 mm RMS
    LO: 2 of 3 samples on a rail, the laser's misfit 2.7 mm, the impacts' states off
    by millimetres). An extreme value counts as a rail when it is held for at least
    :data:`_RAIL_RUN` samples in a row; every sample at it is then left out of the
    pinning (a quantised laser's crest at the extreme value, held a few samples, is a
    true reading that the other samples pin as well).
    """
    if not ok.any():
        return None
    every = bool(ok.all())              # (the usual case: no masked copies)
    v = xl if every else xl[ok]
    out = None
    for ext in (float(v.max()), float(v.min())):
        at = xl == ext
        if not every:
            at &= ok
        if np.count_nonzero(at) < _RAIL_RUN:
            continue
        edges = np.diff(np.r_[0, at.view(np.int8), 0])
        runs = np.flatnonzero(edges < 0) - np.flatnonzero(edges > 0)
        if runs.max() >= _RAIL_RUN:
            out = at if out is None else out | at
    if out is not None and np.count_nonzero(out) >= np.count_nonzero(ok):
        return None                      # a constant laser: nothing else to pin to
    return out


def _advanced(y: np.ndarray, tr: np.ndarray, lag: float) -> np.ndarray:
    """``y`` read ``lag`` seconds later: ``y(tr + lag)``, linear between samples.

    ``y`` itself (not a copy) when ``lag`` is 0; the last ``lag`` of the record
    repeats the last sample.
    """
    if lag <= 0:
        return y
    return np.interp(tr + lag, tr, y)


def _exits(det, t_imp, side, x_imp, v_plus, b, lo_x, lo_velocity):
    """``(t, x, y, v)`` at each contact's exit: time, LO and ball positions, LO velocity.

    ``t + tau`` (:func:`contact_durations`), at most half-way to the next impact; the
    impact's own states where ``tau`` is 0 (so rigid walls give the instantaneous
    impact exactly). See the module docs.
    """
    tau = _release_durations(det)
    if not np.any(tau > 0):
        return t_imp, x_imp, x_imp + side * b, v_plus
    gap = np.diff(t_imp, append=np.inf)
    te = t_imp + np.minimum(tau, 0.5 * gap)
    long = te > t_imp
    x_e = np.where(long, lo_x(te), x_imp)
    v_e = np.where(long, lo_velocity(te), v_plus)
    return te, x_e, x_e + side * b, v_e


def _jump_times(det: ImpactDetection, ti: np.ndarray) -> np.ndarray:
    """Times (s, from the record's start) at which the LO's velocity jumps are counted.

    The force's centroid (:func:`force_centroids`), not the contact entry ``ti``: the
    LO takes the jump spread over the contact, as an impulse at the centroid as far as
    its later motion goes. At the entry, each jump put the integrated position off by
    ``dv c`` after it, a square wave by wall that the drift smoother halved: +-25 um at
    the impacts on holdout6-009 (mid-record sd 20-22 -> 2-5 um, right-minus-left offset
    -44 -> -2..-7 um, diag19a), and the exit positions of long soft contacts carried it
    into r (holdout7-000 right wall, true 0.329: 0.395 -> 0.370). The impact states stay
    at the entry. Identical to ``ti`` for instantaneous impacts (exact engine); kept in
    order (a close chatter pair on walls of different centroids).
    """
    c = force_centroids(det)
    if not np.any(c > 0):
        return ti
    return np.maximum.accumulate(ti + c)


def _clip_index(k: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """Integer indices ``k`` held to ``[lo, hi]``: ``np.clip``'s result without its overhead."""
    return np.minimum(np.maximum(k, lo), hi)


def _first_samples(t: np.ndarray, ti: np.ndarray, fs: float) -> np.ndarray:
    """Index of the first sample strictly after each impact (``ti`` from ``t[0]``).

    A jump counts in the LO velocity from that sample on; ``t.size`` for an impact at
    or after the last sample.
    """
    n = t.size
    first = np.minimum(np.floor(ti * fs).astype(np.int64) + 1, n)
    first += (first < n) & (first > 0) & ((t[_clip_index(first - 1, 0, n - 1)] - t[0]) > ti)
    return first


def _first_where(cond, starts: np.ndarray, ends: np.ndarray, part: int = _PART) -> np.ndarray:
    """Per interval ``[start, end]`` of sample indices, the first index where ``cond`` holds.

    -1 where it holds nowhere in the interval. ``cond(lo, hi)`` gives the condition on
    the samples ``lo:hi``; it is asked ``part`` samples at a time over the span of the
    intervals, never for the whole record.
    """
    found = np.full(starts.size, -1, dtype=np.int64)
    if starts.size == 0:
        return found
    pending = np.ones(starts.size, dtype=bool)
    for lo in range(int(starts.min()), int(ends.max()) + 1, part):
        hi = lo + part
        act = np.flatnonzero(pending & (starts < hi) & (ends >= lo))
        if act.size == 0:
            continue
        idx = np.flatnonzero(cond(lo, hi)) + lo
        k = np.full(act.size, np.iinfo(np.int64).max)
        if idx.size:
            j = np.searchsorted(idx, np.maximum(starts[act], lo))
            k = np.where(j < idx.size, idx[np.minimum(j, idx.size - 1)], k)
        hit = k <= ends[act]
        found[act[hit]] = k[hit]
        pending[act[hit | (ends[act] < hi)]] = False
    return found


def _flights(t_imp, side, x_imp, y_imp, v_minus, b, mu, t, x_f, acc, fs, stick_tol, lo_x,
             lo_acc, lo_velocity, exits, shift=None, g0=0.0):
    """Flight table between consecutive contacts, each from an exit to the next entry.

    ``exits``: ``(t, x, y, v)`` at each contact's exit (:func:`_exits`); ``shift``: the
    LO of the impacts' frame less ``x_f`` (:class:`_Shift`), None when they are one;
    ``g0``: the ball's acceleration along the base from its inclination, ``g sin(theta)``
    (m/s^2), in the stick-then-fly hypothesis (the wall holds the ball while the LO's
    acceleration less ``g0`` pushes it, and it flies a parabola from the release).
    Holdout11-000: a 1.48 deg tilt bends the 26 ms flight from a left wall's release by
    8.4e-5 m, which with 6e-5 m of other error put the closure at 1.25 stick_tol: the
    flights were taken as free from the last seen re-impact, and the right wall's
    incoming speed 0.14 m/s low, r 0.767 for 0.719 on all 40 impacts.
    """
    m = t_imp.size
    nf = max(m - 1, 0)
    if nf == 0:
        cols = {c: np.zeros(0) for c in FLIGHT_COLUMNS}
        for c in ("i_start", "i_end", "sign_changes"):
            cols[c] = np.zeros(0, dtype=np.int64)
        for c in ("side_start", "side_end", "kind"):
            cols[c] = np.zeros(0, dtype="<U5")
        return cols, {}
    i_s = np.arange(nf)
    i_e = i_s + 1
    t_exit, x_exit, y_exit, v_exit = exits
    ts, te = t_exit[:-1], t_imp[1:]
    dur = te - ts
    ss, se = side[:-1], side[1:]
    ys, ye = y_exit[:-1], y_imp[1:]
    v_start = v_exit[:-1]
    w_mean = (ye - ys) / dur
    mug = mu * G_ACCEL

    # ---- stick-then-fly candidates: opposite walls, start wall holds the ball at t_s+
    cs = np.minimum(np.searchsorted(t, ts, side="right"), t.size - 1)      # (>= 0)
    ce = _clip_index(np.searchsorted(t, te, side="left") - 1, 0, t.size - 1)
    a_start = acc[cs]
    # (the LO's acceleration against the ball's own along the base, g0: thresholds
    # moved by g0 rather than a full-length acc - g0)
    holds0 = np.where(ss < 0, a_start > -mug + g0, a_start < mug + g0)
    cand = (ss != se) & holds0 & (ce > cs)
    t_rel = ts.copy()
    found = np.zeros(nf, dtype=bool)
    if cand.any():
        # first sample after t_s where the wall lets go: left x'' < -mu g, right x'' > mu g
        # (searched part by part: at mu = 0 the samples that let go are half the record)
        for sgn in (-1.0, 1.0):
            sel = np.flatnonzero(cand & (ss == sgn))
            if sel.size == 0:
                continue
            thr = (-mug if sgn < 0 else mug) + g0
            first_go = _first_where(lambda lo, hi, s=sgn: s * acc[lo:hi] > mug + s * g0,
                                    cs[sel], ce[sel])
            inside = first_go > 0
            kk = _clip_index(np.where(first_go >= 0, first_go, t.size), 1, t.size - 1)
            a0, a1 = acc[kk - 1], acc[kk]
            with np.errstate(divide="ignore", invalid="ignore"):
                fr = np.clip(np.where(a1 != a0, (thr - a0) / (a1 - a0), 0.0), 0.0, 1.0)
            trel = t[kk - 1] + fr / fs
            trel = np.maximum(trel, ts[sel])
            t_rel[sel] = np.where(inside, trel, ts[sel])
            found[sel] = inside
    cand &= found
    x_rel = lo_x(t_rel)
    v_rel = lo_velocity(t_rel)
    y_rel = x_rel + ss * b

    traj = {}
    if mu == 0.0:
        fly = te - t_rel
        closure = np.where(cand, y_rel + v_rel * fly + 0.5 * g0 * fly ** 2 - ye, np.nan)
        # the approach speed at the next entry (of the stick hypothesis) times the
        # entry's timing error is closure too
        u_arr = (ye - y_rel) / fly + 0.5 * g0 * fly - v_minus[1:]
        stick = cand & (np.abs(closure) <= np.maximum(stick_tol,
                                                       np.abs(u_arr) * STICK_ARRIVAL_DT))
        t_free = np.where(stick, t_rel, ts)
        y_free = np.where(stick, y_rel, ys)
        w_free = (ye - y_free) / (te - t_free)
        w_start = np.where(stick, np.nan, w_free)
        # a stick flight's arrival on its parabola (the free ones' are solved under the
        # inclination by the caller; the plotted path stays the straight line)
        w_end = w_free + np.where(stick, 0.5 * g0 * fly, 0.0) if g0 else w_free
        changes = np.zeros(nf, dtype=np.int64)
        y_release = y_free
    else:
        # free hypothesis for every flight, stick hypothesis for the candidates
        sol = solve_flights(ts, te, ys, ye, lo_velocity, lo_acc, mu, v_start=v_start,
                            v_end=v_minus[1:])
        closure = np.full(nf, np.nan)
        stick = np.zeros(nf, dtype=bool)
        if cand.any():
            ci = np.flatnonzero(cand)
            # under an inclination, in the frame falling with the ball along the base
            # (as flights.reconstruct_flights): Y = y - g0 (t - t_rel)^2 / 2, V = x' -
            # g0 (t - t_rel); the rows of the flights' time grids start at t_rel
            fly = te[ci] - t_rel[ci]
            vel_c, acc_c = falling_frame(lo_velocity, lo_acc, g0)
            ye_c = ye[ci] - 0.5 * g0 * fly ** 2
            ve_c = v_minus[1:][ci] - g0 * fly
            solc = solve_flights(t_rel[ci], te[ci], y_rel[ci], ye_c, vel_c, acc_c,
                                 mu, v_start=v_rel[ci], v_end=ve_c)
            # arrival error when launched with the wall's velocity at the release
            y_end, _ = integrate_flights(t_rel[ci], te[ci], y_rel[ci], v_rel[ci], vel_c,
                                         acc_c, mu, v_start=v_rel[ci], v_end=ve_c)
            closure[ci] = y_end - ye_c
            if g0:                       # back from the falling frame
                rise = solc.t - t_rel[ci][:, None]
                solc = replace(solc, w_end=solc.w_end + g0 * fly,
                               y=solc.y + 0.5 * g0 * rise ** 2, w=solc.w + g0 * rise)
            u_arr = solc.w_end - v_minus[1:][ci]
            stick[ci] = np.abs(closure[ci]) <= np.maximum(stick_tol,
                                                          np.abs(u_arr) * STICK_ARRIVAL_DT)
        w_start = sol.w_start.copy()
        w_end = sol.w_end.copy()
        changes = sol.sign_changes.copy()
        T, Y, W = sol.t, sol.y, sol.w          # (sol's own arrays: not used elsewhere)
        if stick.any():
            si = np.flatnonzero(stick)
            pos = np.searchsorted(np.flatnonzero(cand), si)
            w_start[si] = np.nan
            w_end[si] = solc.w_end[pos]
            changes[si] = solc.sign_changes[pos]
            T[si], Y[si], W[si] = solc.t[pos], solc.y[pos], solc.w[pos]
        y_release = np.where(stick, y_rel, ys)
        traj = {"t": T, "y": Y, "w": W, "row": np.arange(nf)}
    t_release = np.where(stick, t_rel, ts)

    # ---- penetration of the reconstructed ball path through the walls
    pen = _penetration(t, x_f, ts, te, t_release, y_release, w_end, ss, b, traj, mu,
                       w_start, ys, shift)
    return {
        "i_start": i_s, "i_end": i_e, "t_start": ts, "t_end": te, "duration": dur,
        "side_start": np.where(ss > 0, "right", "left"),
        "side_end": np.where(se > 0, "right", "left"),
        "kind": np.where(stick, "stick", "free"),
        "t_release": t_release, "y_start": ys, "y_end": ye, "x_start": x_exit[:-1],
        "x_end": x_imp[1:], "v_start": v_start, "v_end": v_minus[1:],
        "w_start": w_start, "w_end": w_end, "w_mean": w_mean,
        "zd_start": w_start - v_start, "zd_end": w_end - v_minus[1:],
        "penetration": pen, "closure": closure, "sign_changes": changes,
        "y_release": y_release}, traj


def _penetration(t, x_f, ts, te, t_release, y_release, w_line, ss, b, traj, mu, w_start, ys,
                 shift=None):
    """Largest excursion (m) of the reconstructed ball beyond the walls, per flight."""
    nf = ts.size
    step = _PEN_STEP
    td = t[::step]
    k0 = np.searchsorted(td, ts, side="right")
    k1 = np.searchsorted(td, te, side="left")
    cnt = np.maximum(k1 - k0, 0)
    out = np.zeros(nf)
    if cnt.sum() == 0:
        return out
    # a few hundred thousand samples at a time (whole flights: each flight's maximum
    # is taken within one part)
    csum = np.cumsum(cnt)
    a = 0
    while a < nf:
        stop = max(a + 1, int(np.searchsorted(csum, csum[a] - cnt[a] + _PEN_PART,
                                              side="right")))
        sl = slice(a, stop)
        a = stop
        c, k = cnt[sl], k0[sl]
        fl = np.repeat(np.arange(nf)[sl], c)
        idx = (np.arange(c.sum()) - np.repeat(np.cumsum(c) - c, c) + np.repeat(k, c)) * step
        tt = t[idx]
        x_lo = x_f[idx] if shift is None else x_f[idx] + shift(tt - t[0])[0]
        if mu == 0.0:
            tr = t_release[fl]
            y = np.where(tt < tr, x_lo + ss[fl] * b, y_release[fl] + w_line[fl] * (tt - tr))
        else:
            T, Y = traj["t"], traj["y"]
            pos = (tt - T[fl, 0]) / (T[fl, -1] - T[fl, 0]) * (T.shape[1] - 1)
            pos = np.clip(pos, 0, T.shape[1] - 1 - 1e-9)
            i0 = pos.astype(int)
            f = pos - i0
            y = Y[fl, i0] * (1 - f) + Y[fl, i0 + 1] * f
        z = y - x_lo
        exc = np.maximum(np.abs(z) - b, 0.0)
        # each flight's samples are contiguous in ``exc``: its maximum by reduceat over
        # the flights that have samples (exact, as the scattered maximum.at was)
        has = np.flatnonzero(c > 0)
        if has.size:
            out[a - c.size + has] = np.maximum.reduceat(exc, (np.cumsum(c) - c)[has])
    return out
