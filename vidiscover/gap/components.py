"""Where the gap lies: distributional statistics of a recording and their differences.

A recording (real or simulated) is reduced by :func:`measure` to a
:class:`Signature`: a few dozen scalar statistics, each localised in one part of the
system (a wall at the impacts, the flights, the LO response, impact timing, the
sensors, the excitation), plus the point clouds the distributional comparisons need
(the first return map, r per impact). Both sides of a comparison go through the same
sensor model and the same analysis pipeline, so systematic analysis biases cancel.

:func:`compare` turns two signatures into :class:`GapComponents`: each statistic's
difference divided by its noise scale, squared. The noise scale of a statistic
combines its own standard error on both sides, its spread over replicates of the
nominal simulation (other initial conditions and sensor noise; this is what makes
chaotic and SMR regimes comparable, where trajectories cannot be compared point by
point) and a floor (the resolution below which a difference is not meaningful). A
component of about 1 is "at the noise level"; components add to the total gap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..analysis.signals import fill_gaps, robust_std

__all__ = ["STATS", "Signature", "GapComponents", "measure", "compare", "noise_scales",
           "energy_distance", "mirror", "GROUPS", "FORM_SCALE", "LO_STATS", "LO_FORM",
           "blunt_lo", "sharpen_lo"]

#: Statistic name -> (group, floor of its noise scale, description).
STATS: dict[str, tuple[str, float, str]] = {}


def _stat(name: str, group: str, floor: float, doc: str) -> None:
    STATS[name] = (group, floor, doc)


for _side in ("right", "left"):
    _stat(f"{_side}.r_level", f"impacts.{_side}", 0.01, "RMS of r on this wall")
    _stat(f"{_side}.r_speed", f"impacts.{_side}", 0.05,
          "slope of r against impact speed (s/m)")
    _stat(f"{_side}.r_trend", f"impacts.{_side}", 0.005,
          "drift of r: regression slope on time x half the record length")
    _stat(f"{_side}.rate", f"impacts.{_side}", 0.03, "impacts on this wall per cycle")
# the momentum residual at a wall (m/s: the ball's velocity change in the flights
# either side of it that the impact does not explain) is compared as the mean of the
# two walls, which a force along the axis (a tilt) makes, and their half difference,
# which symmetric wall losses outside the model (compliant contacts) make
# likewise the LO velocity jumps: their common level (which symmetric contact
# compliance and the instrument's gain shift) and their right-left difference
_stat("dv.common", "impacts.walls", 0.02,
      "mean over the walls of the log median LO velocity jump")
_stat("dv.opposite", "impacts.walls", 0.02,
      "half difference right - left of the log median LO velocity jumps")
_stat("momentum.common", "flights", 0.01,
      "mean of the two walls' momentum residuals (m/s): a steady force on the ball")
_stat("momentum.opposite", "flights", 0.01,
      "half difference of the right and left momentum residuals (m/s)")
_stat("momentum.laser", "flights", 0.005,
      "log of the ball's momentum change at an impact, read from the kink of the laser "
      "displacement, over the change of the flight speeds, mean of the two walls: the "
      "flight speeds assume the metadata clearance, so a clearance error shifts it")
_stat("momentum.laser_opposite", "flights", 0.005,
      "half difference right - left of the walls' laser momentum log ratios: a steady "
      "force on the ball along the axis (a tilt) moves the flight speeds apart from the "
      "impact speeds, the other way at each wall")
_stat("flights.direction", "flights", 0.01,
      "mean flight time towards the right minus towards the left (periods)")
_stat("flights.speed_ratio", "flights", 0.01,
      "log ratio of mean flight speeds towards the right and towards the left")
# floor 0.02: the independent simulator's recordings without friction read -0.015 to
# 0.003 against standard errors of 0.004 (unmodelled LO dynamics the fit leaves)
_stat("flights.drag", "flights", 0.02,
      "force on the LO along the ball's relative motion during free flights (units m2 g: "
      "a friction coefficient); the LO's own dynamics, fitted, leave 0")
# floors 0.003: the resolution of the LO's response. A model-form allowance brings
# them to 0.01 (LO_FORM, in the nominal model's replicate variances) except where the
# other statistics see no significant gap (diagnose.nominal_model's sharp look)
_stat("lo.amplitude", "lo", 0.003, "log LO amplitude at f relative to the base amplitude")
_stat("lo.phase", "lo", 0.003, "LO phase at f relative to the base (rad)")
_stat("lo.envelope", "lo", 0.02, "envelope modulation of the LO (label index M)")
_stat("excitation.h2", "excitation", 0.002, "base 2nd harmonic (relative, cos part)")
_stat("excitation.h2s", "excitation", 0.002, "base 2nd harmonic (relative, sin part)")
_stat("excitation.h3", "excitation", 0.002, "base 3rd harmonic (relative, cos part)")
_stat("excitation.h3s", "excitation", 0.002, "base 3rd harmonic (relative, sin part)")
_stat("sensors.pulse_width", "sensors", 0.03,
      "log median pulse width (area/peak of the acceleration pulses, samples)")
#: Bands (Hz) of the displacement vs integrated acceleration residual spectrum.
BANDS = (20.0, 40.0, 80.0, 160.0, 320.0, 640.0, 1280.0, 2560.0)
for _k in range(len(BANDS) - 1):
    _stat(f"sensors.residual_{int(BANDS[_k])}", "sensors", 0.1,
          f"log10 power of laser minus integrated acceleration, {BANDS[_k]:g}-"
          f"{BANDS[_k + 1]:g} Hz")
_stat("timing.returnmap", "timing", 0.01,
      "energy distance between return maps (dt_i, dt_i+1)/T (special: pairwise)")

#: Model-form scale of statistics (same units as the statistic): the spread of the
#: nominal model's difference from compliant-engine recordings with no catalogue
#: effect that noise does not explain (:mod:`.calibration`); added in quadrature to
#: every scale in :func:`compare`. Calibrated on 16 compliant no-effect recordings
#: (``calibration.none_cases("calibrate", 16)``, :data:`.calibration.FORM_QUANTILE`,
#: :data:`.calibration.FORM_FACTOR`); reproduce with ``benchmarks/bench_gap.py
#: --calibrate``. The laser-kink statistics (``momentum.laser``,
#: ``momentum.laser_opposite``) were added later and calibrated by the same rule on
#: the same cases, alone, while they still took part in choosing the nominal
#: attractor: 0.03 and 0.022. Re-run once they no longer did (as shipped), the rule
#: gives 0.032 and 0.015 (no-effect differences -0.040 to +0.026 and -0.029 to
#: +0.015); the shipped values keep every calibrate case and 15/16 quote cases below
#: the threshold, as without them. The others are kept as they were (a recalibration
#: today moves them by <= 30 %).
FORM_SCALE: dict[str, float] = {
    "dv.common": 0.26, "dv.opposite": 0.2, "flights.speed_ratio": 0.014,
    "momentum.common": 0.11, "momentum.laser": 0.03, "momentum.laser_opposite": 0.022,
    "momentum.opposite": 0.22, "sensors.pulse_width": 0.25,
    "sensors.residual_20": 1.4, "sensors.residual_40": 0.87, "sensors.residual_80": 0.3,
}

#: The LO response statistics and their model-form allowance (same units). Their
#: floors (0.003) are the LO response's resolution; the allowance (with it the scale
#: is 0.01, as these statistics' floors were before) enters the nominal model's
#: replicate variances (:func:`blunt_lo`) except in the sharp look of
#: :func:`~vidiscover.gap.diagnose.nominal_model`: where the other statistics see no
#: significant gap, a clearance error on a symmetric two-impact orbit shows only here
#: (both walls move alike; the impacts' momentum transfer moves the LO's log amplitude
#: and phase by 0.005-0.01 per mm: spent draws 25101 #6, 25103 #6 and #18, nominal
#: gaps 2.4-4.0 -> 10.6-14.7, the clearance fit leaves 0.3-1.1), while compliant
#: no-effect recordings differ from the nominal model by <= 0.0008 in both (31 of the
#: 32 cases of :func:`~vidiscover.gap.calibration.none_cases`, calibrate and quote;
#: the 32nd, quote 8009, is above the significance threshold with the allowance).
#: Sharp everywhere, effects the catalogue cannot fit exactly lean on them (seed-0
#: battery: a restitution drift named clearance_error, a 15 mm friction named
#: clearance_error instead of unexplained).
LO_STATS = ("lo.amplitude", "lo.phase")
LO_FORM = math.sqrt(0.01 ** 2 - 0.003 ** 2)


def blunt_lo(rep_var: dict[str, float]) -> dict[str, float]:
    """``rep_var`` with the LO statistics' model-form allowance (:data:`LO_FORM`) added."""
    out = dict(rep_var)
    for k in LO_STATS:
        out[k] = out.get(k, 0.0) + LO_FORM ** 2
    return out


def sharpen_lo(rep_var: dict[str, float]) -> dict[str, float]:
    """``rep_var`` without the allowance :func:`blunt_lo` added (inverse of it)."""
    out = dict(rep_var)
    for k in LO_STATS:
        out[k] = max(out.get(k, 0.0) - LO_FORM ** 2, 0.0)
    return out


#: Component groups in report order.
GROUPS = ("impacts.right", "impacts.left", "impacts.walls", "flights", "lo", "timing", "sensors",
          "excitation")


@dataclass(frozen=True, eq=False)
class Signature:
    """Statistics of one recording, as the gap diagnosis sees it.

    Attributes
    ----------
    values : dict
        Statistic name -> value (NaN when undefined, e.g. no impact on a wall).
    errors : dict
        Statistic name -> standard error from the record itself (0 if unknown).
    returnmap : ndarray
        Points (dt_i, dt_i+1) / T, shape (n, 2).
    impacts : dict
        Per impact arrays ``t``, ``side`` (+1/-1), ``r``, ``speed`` (used r only).
    r_pooled : float
        RMS of r over both walls (the nominal model's one constant r).
    forcing : tuple
        (frequency Hz, amplitude m, phase rad) of the fitted base sine.
    residual_psd : tuple
        (frequencies Hz, PSD) of laser minus integrated acceleration.
    flight_time : float
        Mean duration of the free flights between opposite walls (s).
    """

    values: dict
    errors: dict
    returnmap: np.ndarray = field(repr=False)
    impacts: dict = field(repr=False)
    r_pooled: float = math.nan
    forcing: tuple = (math.nan, math.nan, math.nan)
    residual_psd: tuple = field(default=(), repr=False)
    flight_time: float = math.nan


def _wrap(phi: float) -> float:
    return float((phi + math.pi) % (2 * math.pi) - math.pi)


def _slope(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """OLS slope and its standard error (NaN/inf when not identifiable)."""
    if x.size < 8 or np.std(x) < 0.05 * max(np.mean(np.abs(x)), 1e-9):
        return math.nan, math.inf
    A = np.column_stack([x - x.mean(), np.ones_like(x)])
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    res = y - A @ coef
    s2 = float(res @ res) / max(x.size - 2, 1)
    se = math.sqrt(s2 / float(((x - x.mean()) ** 2).sum()))
    return float(coef[0]), se


def _wall_stats(side_name: str, sgn: int, table, det_cols, vals: dict, errs: dict,
                n_cycles: float, momentum: np.ndarray, half: float) -> None:
    side = np.asarray(table["side"]) == side_name
    used = side & np.asarray(table["r_used"], dtype=bool) & np.isfinite(table["r"])
    r = np.asarray(table["r"], dtype=float)[used]
    speed = np.abs(np.asarray(table["u_minus"], dtype=float))[used]
    t = np.asarray(table["t"], dtype=float)[used]
    p = f"{side_name}."
    vals[p + "rate"] = float(side.sum()) / n_cycles
    errs[p + "rate"] = 0.0
    dv = np.abs(np.asarray(table["dv"], dtype=float)[side])
    if dv.size:
        vals[p + "dv"] = float(np.log(np.median(dv) + 1e-12))
        errs[p + "dv"] = float(1.25 * np.std(np.log(dv + 1e-12)) / math.sqrt(dv.size))
    else:
        vals[p + "dv"], errs[p + "dv"] = math.nan, 0.0
    if r.size >= 2:
        vals[p + "r_level"] = float(np.sqrt(np.mean(r ** 2)))
        errs[p + "r_level"] = float(np.std(r, ddof=1) / math.sqrt(r.size))
    else:
        vals[p + "r_level"], errs[p + "r_level"] = math.nan, 0.0
    vals[p + "r_speed"], errs[p + "r_speed"] = _slope(speed, r)
    if r.size >= 8 and np.ptp(t) > 0:
        # drift of r over the record: regression slope x half the duration, i.e. the
        # expected change of the mean r from the first to the second half
        A = np.column_stack([t - t.mean(), np.ones_like(t)])
        coef, *_ = np.linalg.lstsq(A, r, rcond=None)
        res = r - A @ coef
        se = math.sqrt(float(res @ res) / (r.size - 2) / float(((t - t.mean()) ** 2).sum()))
        vals[p + "r_trend"] = float(coef[0] * half)
        errs[p + "r_trend"] = float(se * half)
    else:
        vals[p + "r_trend"], errs[p + "r_trend"] = math.nan, 0.0
    m = momentum[np.asarray(det_cols["side"]) == side_name]
    m = m[np.isfinite(m)]
    if m.size >= 2:
        vals[p + "momentum"] = float(np.median(m))
        errs[p + "momentum"] = float(1.25 * np.std(m, ddof=1) / math.sqrt(m.size))
    else:
        vals[p + "momentum"], errs[p + "momentum"] = math.nan, 0.0


#: Time (s) left out at both ends of a flight by :func:`_flight_drag` (the impact
#: pulses, spread by contacts and the anti-alias filter).
DRAG_GUARD = 0.004


def _harmonic_of(y: np.ndarray, C: np.ndarray, n: int) -> complex:
    """Complex amplitude c with y ~ Im(c exp(i n w t)) + const (t spans whole cycles).

    ``C``: the :func:`_harmonic_columns` of the samples' times at w.
    """
    y = y - y.mean()
    # einsum, not BLAS: a BLAS dot's thread pool spins against busy cores (12 ms a call
    # measured under load instead of 0.05 ms)
    return complex(2.0 * float(np.einsum("i,i->", y, C[:, 2 * n - 1])) / y.size,
                   2.0 * float(np.einsum("i,i->", y, C[:, 2 * n])) / y.size)


def _harmonic_columns(t: np.ndarray, w: float) -> np.ndarray:
    """Columns 1, sin(w t), cos(w t), ..., sin(4 w t), cos(4 w t) (shape (n, 9)).

    The higher harmonics by the angle-addition formulas from the first (two of the
    eight sine/cosine evaluations instead of eight; the same values to ~1e-15).
    """
    C = np.empty((t.size, 9))
    C[:, 0] = 1.0
    ph = w * t
    s1, c1 = np.sin(ph), np.cos(ph)
    C[:, 1], C[:, 2] = s1, c1
    for k in (3, 5, 7):
        s_, c_ = C[:, k - 2], C[:, k - 1]
        C[:, k] = s_ * c1 + c_ * s1
        C[:, k + 1] = c_ * c1 - s_ * s1
    return C


def _least_squares(A: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least-squares coefficients of a well-conditioned tall ``A`` (normal equations).

    For the harmonic columns of :func:`_harmonic_columns` over whole recordings
    (nearly orthogonal): the same coefficients as ``np.linalg.lstsq`` to ~1e-15 at
    a tenth of its cost (an SVD of a 32768 x 9 matrix took 5-7 ms of every simulated
    signature).
    """
    return np.linalg.solve(A.T @ A, A.T @ y)


def _flight_drag(rec, an, w: float, C: np.ndarray | None = None) -> tuple[float, float]:
    """Force on the LO along the ball's relative motion in free flights (units m2 g).

    Between impacts the LO obeys m1 x'' = -k1 (x - xe) - c1 (x' - xe') plus whatever
    the ball exerts on it; sliding friction exerts mu m2 g along the ball's motion
    relative to the LO (its reaction on the ball opposes that motion). Over the
    samples of the free flights between opposite walls, away from the impacts
    (:data:`DRAG_GUARD`), the measured acceleration is regressed on the LO's own
    terms (the laser's displacement and the reconstructed velocity relative to the
    base motion, fitted as its first four harmonics), a constant and the flight
    direction (+1 towards the right wall, -1 towards the left); the direction's
    coefficient, in units of g m2 / m1, is the statistic. The LO's stiffness and
    damping are fitted with it, not taken from the metadata: a rig's LO never has its
    nominal damping exactly (the independent simulator's reads 1.1 N s/m against
    3.02), and the residual of the nominal equation read 1.0-1.4 on its recordings
    without friction. Contacts, a tilt (it pulls on the ball, not on the LO through
    the ball), the restitution, the clearance and the sensor effects give no such
    force, so the statistic separates friction from what trades against it
    elsewhere (a clearance error, a lower r). The standard error comes from the
    per-flight means of the regression's residual plus the direction term. Returns
    (value, standard error); NaN with fewer than four flights. ``C``: the recording's
    :func:`_harmonic_columns` at ``w``, if already computed.
    """
    meta = rec.meta
    fl = an.reconstruction.flight_columns
    recon = an.reconstruction
    if np.asarray(fl["t_start"]).size < 4 or not meta.m2 > 0:
        return math.nan, 0.0
    t = np.asarray(rec.t, dtype=float)
    xe = np.asarray(rec.xe, dtype=float)
    ok = np.isfinite(xe)
    C = _harmonic_columns(t, w) if C is None else C
    coef = _least_squares(C[ok] if not ok.all() else C, xe[ok])
    # the derivative of the fit: sin(n w t) -> n w cos(n w t), cos -> -n w sin
    nw = w * np.arange(1, 5)
    dcoef = np.zeros(9)
    dcoef[1::2], dcoef[2::2] = -nw * coef[2::2], nw * coef[1::2]
    xe_fit, ve_fit = C @ coef, C @ dcoef
    del C
    # the laser's displacement: the integrated acceleration lags with a causal
    # anti-alias filter (a Butterworth chain read 0.18 on no-effect compliant walls)
    x = np.asarray(rec.x, dtype=float)
    v = np.interp(t, recon.t, recon.v)
    a = np.asarray(rec.a, dtype=float)
    kind = np.asarray(fl["kind"])
    ss, se = np.asarray(fl["side_start"]), np.asarray(fl["side_end"])
    t0 = np.asarray(fl["t_start"], dtype=float) + DRAG_GUARD
    t1 = np.asarray(fl["t_end"], dtype=float) - DRAG_GUARD
    sign = np.where((ss == "left") & (se == "right"), 1.0,
                    np.where((ss == "right") & (se == "left"), -1.0, 0.0))
    i0, i1 = np.searchsorted(t, t0), np.searchsorted(t, t1)
    flights = [k for k in np.flatnonzero((kind == "free") & (sign != 0) & (i1 - i0 >= 4))]
    if len(flights) < 4 or len({sign[k] for k in flights}) < 2:
        return math.nan, 0.0
    s = np.zeros_like(t)
    label = np.full(t.size, -1)
    for k in flights:
        s[i0[k]:i1[k]] = sign[k]
        label[i0[k]:i1[k]] = k
    m = (label >= 0) & np.isfinite(x) & np.isfinite(v) & np.isfinite(a)
    A = np.column_stack([x - xe_fit, v - ve_fit, np.ones_like(t), s])[m]
    c, *_ = np.linalg.lstsq(A, a[m], rcond=None)
    # per flight: the mean of (residual + direction term) x direction
    part = (a[m] - A[:, :3] @ c[:3]) * s[m]
    lab = label[m]
    uniq, inv = np.unique(lab, return_inverse=True)
    per = np.bincount(inv, weights=part) / np.bincount(inv)
    if per.size < 4:
        return math.nan, 0.0
    unit = meta.m2 * 9.80665 / meta.m1
    return float(c[3] / unit), float(per.std(ddof=1) / math.sqrt(per.size) / unit)


#: Half-window (s) of the laser-kink fit at an impact (:func:`_laser_momentum`), at
#: most :data:`KINK_SHARE` of the flights either side, and its guard about the impact
#: (the accelerometer's pulse, spread by the anti-alias filter: a linear-phase kernel
#: reaches 3.75 ms at 6400 Hz).
KINK_WINDOW = 0.020
KINK_SHARE = 0.45
KINK_GUARD = 0.003


def _laser_momentum(rec, an, mr: float, *, quality: bool = False
                    ) -> dict[str, tuple[float, float]]:
    """Per wall: median log ratio of the laser's LO velocity jump to the flight speeds'.

    The LO's smooth motion is the double integral of the accelerometer with its impact
    pulses cut out (linear interpolation over +/- :data:`KINK_GUARD` about every
    impact); at every impact between two free flights to and from the opposite wall,
    the laser displacement minus that integral, over +/- a window
    (:data:`KINK_WINDOW`, at most :data:`KINK_SHARE` of either flight, without the
    guard), is fitted as a quadratic in time plus a kink ``dv max(t - t_i, 0)``: ``dv``
    is the LO's velocity jump, read from the laser instead of the pulse areas (behind
    a weak anti-alias chain those were off by -18 to +25 % on compliant no-effect
    recordings). The ball's momentum change is ``mr dv`` (``mr = m1/m2``); the flight
    speeds' change across the impact, ``w_mean`` after minus before, assumes the
    metadata clearance b, so their log ratio moves with a clearance error (by about
    ``db / b``) while the fit's own bias (about -0.1, from what the cut leaves of
    the pulses) is the same in the simulated recordings. Returns wall -> (median,
    standard error); walls with fewer than 3 such impacts are left out.
    """
    det = an.detection.columns
    fl = an.reconstruction.flight_columns
    ti = np.asarray(det["t"], dtype=float)
    n = ti.size
    if n < 4:
        return {}
    kind = np.asarray(fl["kind"])
    ss, se = np.asarray(fl["side_start"]), np.asarray(fl["side_end"])
    cross = (kind == "free") & (ss != se)
    i = np.flatnonzero(cross[:-1] & cross[1:]) + 1          # impacts between two such flights
    if i.size < 3:
        return {}
    wm = np.asarray(fl["w_mean"], dtype=float)
    dw = wm[i] - wm[i - 1]
    t = np.asarray(rec.t, dtype=float)
    fs = float(rec.sample_rate)
    half = np.minimum(np.minimum(ti[i] - ti[i - 1], ti[i + 1] - ti[i]) * KINK_SHARE,
                      KINK_WINDOW)
    keep = half >= KINK_GUARD + 0.002
    i, dw, half = i[keep], dw[keep], half[keep]
    if i.size < 3:
        return {}
    # the accelerometer without its pulses, integrated twice
    a = np.asarray(rec.a, dtype=float)
    cut = np.zeros(t.size + 1, dtype=np.int64)
    np.add.at(cut, np.searchsorted(t, ti - KINK_GUARD), 1)
    np.add.at(cut, np.searchsorted(t, ti + KINK_GUARD), -1)
    bad = (np.cumsum(cut)[:t.size] > 0) | ~np.isfinite(a)
    if bad.all():
        return {}
    a = fill_gaps(a, bad)
    y = np.asarray(rec.x, dtype=float) - np.cumsum(np.cumsum(a)) / (fs * fs)
    nmax = int(math.ceil(KINK_WINDOW * fs)) + 1
    c = np.searchsorted(t, ti[i])
    idx = c[:, None] + np.arange(-nmax, nmax + 1)
    inside = (idx >= 0) & (idx < t.size)
    idx = np.clip(idx, 0, t.size - 1)
    tau = t[idx] - ti[i][:, None]
    yy = y[idx]
    w = (inside & (np.abs(tau) >= KINK_GUARD) & (np.abs(tau) <= half[:, None])
         & np.isfinite(yy)).astype(float)
    ok = ((w * (tau < 0)).sum(1) >= 6) & ((w * (tau > 0)).sum(1) >= 6)
    if ok.sum() < 3:
        return {}
    tau, w, yy, half, dw, i = tau[ok], w[ok], yy[ok], half[ok], dw[ok], i[ok]
    u = tau / half[:, None]
    A = np.stack([np.ones_like(u), u, u * u, np.maximum(u, 0.0)], axis=-1)
    yy = np.where(w > 0, yy, 0.0)
    yy = yy - (yy * w).sum(1, keepdims=True) / w.sum(1, keepdims=True)
    Aw = A * w[..., None]
    # (6 samples either side at least, in a window scaled to [-1, 1]: well-conditioned)
    coef = np.linalg.solve(np.matmul(Aw.transpose(0, 2, 1), A),
                           np.matmul(Aw.transpose(0, 2, 1), yy[..., None]))[..., 0]
    dv = coef[:, 3] / half
    out = {}
    if quality:
        # median RMS residual of the kink fits over the laser's white noise (third
        # differences: 20 s^2 for white noise of standard deviation s)
        res = (yy[..., None] - A @ coef[..., None])[..., 0]
        rms = np.sqrt((w * res * res).sum(1) / np.maximum(w.sum(1) - 4.0, 1.0))
        x = np.asarray(rec.x, dtype=float)
        noise = float(robust_std(np.diff(x[np.isfinite(x)], 3)) / math.sqrt(20.0))
        out["fit"] = (float(np.median(rms) / noise) if noise > 0 else math.inf, 0.0)
    good = dv * dw < 0
    q = np.log(np.abs(mr * dv[good]) / np.abs(dw[good]))
    side = np.asarray(det["side"])[i[good]]
    for name in ("right", "left"):
        v = q[side == name]
        if v.size >= 3:
            out[name] = (float(np.median(v)), float(1.25 * v.std(ddof=1) / math.sqrt(v.size)))
    return out


#: The laser-kink statistics (:func:`_laser_momentum`).
LASER_STATS = ("momentum.laser", "momentum.laser_opposite")
#: Largest kink-fit quality (median RMS residual of the fits over the laser's white
#: noise) of a real recording whose laser statistics are compared: a clean laser reads
#: 1.0-1.75 (exact and compliant, 6-15 mm, with or without tilt), a ringing sensor
#: sheet 1.9-4.7 (sensor_resonance 180-290 Hz; a damped 250 Hz one at 9 mm
#: compliant 1.3), where the fit reads the ringing, not the kink.
LASER_FIT_MAX = 1.85


def without(sig: Signature, names) -> Signature:
    """``sig`` with the statistics ``names`` undefined (NaN: left out of :func:`compare`)."""
    import dataclasses

    vals = dict(sig.values)
    for k in names:
        vals[k] = math.nan
    return dataclasses.replace(sig, values=vals)


def laser_fit_quality(rec, an) -> float:
    """Median RMS residual of a recording's laser-kink fits over its laser noise.

    NaN when the recording has too few impacts between free flights to fit.
    """
    return _laser_momentum(rec, an, 1.0, quality=True).get("fit", (math.nan, 0.0))[0]


def gate_laser(real: Signature, quality: float) -> Signature:
    """The real recording's signature, without its laser statistics if the fits are poor.

    Poor: a kink-fit quality (:func:`laser_fit_quality`) above :data:`LASER_FIT_MAX`.
    Decided on the real recording alone, so the same statistics are compared for
    every candidate.
    """
    return real if quality <= LASER_FIT_MAX else without(real, LASER_STATS)


def measure(rec, an=None, *, mass_ratio: float | None = None) -> Signature:
    """Reduce a recording and its analysis to the gap statistics.

    Parameters
    ----------
    rec : Recording
        The recording.
    an : AnalysisResult, optional
        Its analysis (``vidiscover.analysis.analyze(rec, n_boot=0)`` when omitted).
    mass_ratio : float, optional
        m1 / m2 for the momentum residual (default from the metadata).

    Returns
    -------
    Signature
    """
    from ..analysis import analyze

    if an is None:
        an = analyze(rec, n_boot=0)
    fc = an.forcing
    T = fc.period
    w = 2 * math.pi * fc.frequency
    t = np.asarray(rec.t, dtype=float)
    duration = float(t[-1] - t[0]) + rec.dt
    n_cycles = duration / T
    vals: dict[str, float] = {}
    errs: dict[str, float] = {}
    table = an.impact_table
    det = an.detection.columns
    mr = mass_ratio if mass_ratio is not None else rec.meta.m1 / rec.meta.m2

    # --- flights and the momentum residual ---------------------------------------
    fl = an.reconstruction.flight_columns
    n_imp = int(np.asarray(det["t"]).size)
    momentum = np.full(n_imp, np.nan)
    wm = np.asarray(fl["w_mean"], dtype=float) if n_imp > 1 else np.zeros(0)
    kind = np.asarray(fl["kind"]) if n_imp > 1 else np.zeros(0, dtype=str)
    dv = np.asarray(det["dv"], dtype=float)
    if n_imp > 2:
        free = kind == "free"
        ok = free[:-1] & free[1:]
        i = np.arange(1, n_imp - 1)
        momentum[i] = np.where(ok, wm[1:] - wm[:-1] + mr * dv[i], np.nan)
    ss = np.asarray(fl["side_start"]) if n_imp > 1 else np.zeros(0, dtype=str)
    se_ = np.asarray(fl["side_end"]) if n_imp > 1 else np.zeros(0, dtype=str)
    dur = np.asarray(fl["duration"], dtype=float) if n_imp > 1 else np.zeros(0)
    to_r = (ss == "left") & (se_ == "right") & (kind == "free")
    to_l = (ss == "right") & (se_ == "left") & (kind == "free")
    if to_r.sum() >= 2 and to_l.sum() >= 2:
        vals["flights.direction"] = float((dur[to_r].mean() - dur[to_l].mean()) / T)
        errs["flights.direction"] = float(math.sqrt(dur[to_r].var() / to_r.sum()
                                                    + dur[to_l].var() / to_l.sum()) / T)
        sr, sl = np.abs(wm[to_r]), np.abs(wm[to_l])
        vals["flights.speed_ratio"] = float(np.log(sr.mean() / sl.mean()))
        errs["flights.speed_ratio"] = float(math.sqrt(sr.var() / sr.size / sr.mean() ** 2
                                                      + sl.var() / sl.size / sl.mean() ** 2))
    else:
        for k in ("flights.direction", "flights.speed_ratio"):
            vals[k], errs[k] = math.nan, 0.0

    # the base harmonics of the sample times, shared by the flight drag and the LO's
    # and the base motion's harmonics below
    C = _harmonic_columns(t, w)
    vals["flights.drag"], errs["flights.drag"] = _flight_drag(rec, an, w, C)

    for sgn, name in ((1, "right"), (-1, "left")):
        _wall_stats(name, sgn, table, det, vals, errs, n_cycles, momentum, 0.5 * duration)
    mr_, ml_ = vals["right.momentum"], vals["left.momentum"]
    e_m = 0.5 * math.hypot(errs["right.momentum"], errs["left.momentum"])
    vals["momentum.common"] = 0.5 * (mr_ + ml_)
    vals["momentum.opposite"] = 0.5 * (mr_ - ml_)
    errs["momentum.common"] = errs["momentum.opposite"] = e_m
    walls = _laser_momentum(rec, an, mr)
    if walls:
        vals["momentum.laser"] = float(np.mean([v for v, _ in walls.values()]))
        errs["momentum.laser"] = float(math.sqrt(sum(e * e for _, e in walls.values()))
                                       / len(walls))
    else:
        vals["momentum.laser"], errs["momentum.laser"] = math.nan, 0.0
    if len(walls) == 2:
        vals["momentum.laser_opposite"] = 0.5 * (walls["right"][0] - walls["left"][0])
        errs["momentum.laser_opposite"] = 0.5 * math.hypot(walls["right"][1],
                                                           walls["left"][1])
    else:
        vals["momentum.laser_opposite"], errs["momentum.laser_opposite"] = math.nan, 0.0
    dr_, dl_ = vals["right.dv"], vals["left.dv"]
    vals["dv.common"] = 0.5 * (dr_ + dl_)
    vals["dv.opposite"] = 0.5 * (dr_ - dl_)
    errs["dv.common"] = errs["dv.opposite"] = 0.5 * math.hypot(errs["right.dv"],
                                                              errs["left.dv"])

    # --- LO response at f and envelope -------------------------------------------
    k_end = int(math.floor(n_cycles)) * T
    K = int(np.count_nonzero(t - t[0] < k_end))          # whole cycles: a prefix
    cx = _harmonic_of(np.asarray(rec.x)[:K], C[:K], 1)
    vals["lo.amplitude"] = float(np.log(abs(cx) / fc.amplitude)) if fc.amplitude > 0 \
        else math.nan
    vals["lo.phase"] = _wrap(math.atan2(cx.imag, cx.real) - fc.phase)
    errs["lo.amplitude"] = errs["lo.phase"] = 0.0
    env = an.features.get("envelope_modulation", math.nan)
    vals["lo.envelope"], errs["lo.envelope"] = float(env), 0.0

    # --- excitation harmonics (relative to the fundamental, phase-referenced) ------
    xe = np.asarray(rec.xe)[:K]
    c1 = _harmonic_of(xe, C[:K], 1)
    ph1 = math.atan2(c1.imag, c1.real)
    for n in (2, 3):
        cn = _harmonic_of(xe, C[:K], n)
        rel = cn / abs(c1) * np.exp(-1j * n * ph1) if abs(c1) > 0 else 0j
        vals[f"excitation.h{n}"], vals[f"excitation.h{n}s"] = float(rel.real), float(rel.imag)
        errs[f"excitation.h{n}"] = errs[f"excitation.h{n}s"] = 0.0

    # --- pulse width -------------------------------------------------------------
    peak = np.abs(np.asarray(det["peak"], dtype=float))
    area = np.abs(dv)
    good = (peak > 0) & np.isfinite(peak) & (area > 0)
    if good.sum() >= 3:
        width = np.log(area[good] / peak[good] * rec.sample_rate)
        vals["sensors.pulse_width"] = float(np.median(width))
        errs["sensors.pulse_width"] = float(1.25 * width.std() / math.sqrt(width.size))
    else:
        vals["sensors.pulse_width"], errs["sensors.pulse_width"] = math.nan, 0.0

    # --- laser vs integrated acceleration residual spectrum -----------------------
    from scipy import signal

    recon = an.reconstruction
    res = np.asarray(rec.x, dtype=float) - np.interp(t, recon.t, recon.x)
    res = np.where(np.isfinite(res), res, 0.0)
    f, psd = signal.welch(res, fs=rec.sample_rate, nperseg=min(1024, res.size))
    for k in range(len(BANDS) - 1):
        band = (f >= BANDS[k]) & (f < BANDS[k + 1])
        name = f"sensors.residual_{int(BANDS[k])}"
        vals[name] = float(np.log10(psd[band].mean() + 1e-30)) if band.any() else math.nan
        errs[name] = 0.0

    # --- return map and r per impact -----------------------------------------------
    rm = an.returnmap
    pts = np.column_stack([rm.x, rm.y]) / T if rm.x.size else np.zeros((0, 2))
    used = np.asarray(table["r_used"], dtype=bool) & np.isfinite(table["r"])
    r_all = np.asarray(table["r"], dtype=float)[used]
    impacts = {"t": np.asarray(table["t"], dtype=float)[used],
               "side": np.where(np.asarray(table["side"])[used] == "right", 1, -1),
               "r": r_all,
               "speed": np.abs(np.asarray(table["u_minus"], dtype=float))[used]}
    r_pooled = float(np.sqrt(np.mean(r_all ** 2))) if r_all.size else math.nan
    vals["timing.returnmap"], errs["timing.returnmap"] = 0.0, 0.0
    return Signature(values=vals, errors=errs, returnmap=pts, impacts=impacts,
                     r_pooled=r_pooled, forcing=(fc.frequency, fc.amplitude, fc.phase),
                     residual_psd=(f, psd),
                     flight_time=float(dur[to_r | to_l].mean()) if (to_r | to_l).any()
                     else math.nan)


def energy_distance(p: np.ndarray, q: np.ndarray) -> float:
    """Energy distance 2E|P-Q| - E|P-P'| - E|Q-Q'| between two point clouds (>= 0).

    For two point masses at distance d it is 2 d; it is 0 for equal distributions.
    Returns NaN if either cloud is empty.
    """
    p, q = np.asarray(p, float), np.asarray(q, float)
    if p.shape[0] == 0 or q.shape[0] == 0:
        return math.nan

    def mean_dist(a, b):
        return float(np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1)).mean())

    return max(0.0, 2 * mean_dist(p, q) - mean_dist(p, p) - mean_dist(q, q))


def noise_scales(replicates: list[Signature]) -> dict[str, float]:
    """Spread of every statistic over replicates of one model (variance, 0 if < 2).

    ``timing.returnmap`` gets the mean squared energy distance between replicate
    pairs instead (its "noise" is the distance between two draws of the same model).
    """
    out: dict[str, float] = {}
    for name in STATS:
        if name == "timing.returnmap":
            d = [energy_distance(a.returnmap, b.returnmap)
                 for i, a in enumerate(replicates) for b in replicates[i + 1:]]
            d = [x for x in d if np.isfinite(x)]
            out[name] = float(np.mean(np.square(d))) if d else 0.0
            continue
        v = np.array([s.values.get(name, math.nan) for s in replicates], dtype=float)
        v = v[np.isfinite(v)]
        out[name] = float(v.var(ddof=1)) if v.size >= 2 else 0.0
    return out


@dataclass(frozen=True)
class GapComponents:
    """Normalised squared differences per statistic (a gap of ~1 is noise level).

    Attributes
    ----------
    per_stat : dict
        Statistic -> normalised squared difference.
    diff : dict
        Statistic -> raw difference (real minus sim).
    """

    per_stat: dict
    diff: dict

    @property
    def total(self) -> float:
        """Total gap score (sum over statistics)."""
        return float(sum(self.per_stat.values()))

    def by_group(self) -> dict[str, float]:
        """Sum per component group (:data:`GROUPS` order)."""
        out = {g: 0.0 for g in GROUPS}
        for k, v in self.per_stat.items():
            out[STATS[k][0]] += v
        return out

    def restricted(self, names) -> float:
        """Sum over the given statistics only."""
        return float(sum(self.per_stat[k] for k in names if k in self.per_stat))


_SIDED = ("r_level", "r_speed", "r_trend", "dv", "rate")


def mirror(sig: Signature) -> Signature:
    """The statistics of the mirror-image motion (z -> -z, x -> -x, half a period later).

    A model without inclination, with the same law on both walls and a base motion
    of odd harmonics only is symmetric under this map, so its attractors come in
    mirror pairs; which one a rig sits on is history, not physics.
    """
    import dataclasses

    vals, errs = dict(sig.values), dict(sig.errors)
    for src in (sig.values, sig.errors):
        dst = vals if src is sig.values else errs
        for k in _SIDED:
            dst[f"right.{k}"], dst[f"left.{k}"] = src[f"left.{k}"], src[f"right.{k}"]
        sgn = -1.0 if src is sig.values else 1.0
        dst["right.momentum"] = sgn * src["left.momentum"]
        dst["left.momentum"] = sgn * src["right.momentum"]
        dst["momentum.common"] = sgn * src["momentum.common"]
        dst["momentum.opposite"] = src["momentum.opposite"]
        dst["momentum.laser_opposite"] = sgn * src["momentum.laser_opposite"]
        dst["dv.common"] = src["dv.common"]
        dst["dv.opposite"] = sgn * src["dv.opposite"]
        for k in ("flights.direction", "flights.speed_ratio"):
            dst[k] = sgn * src[k]
    imp = dict(sig.impacts)
    imp["side"] = -np.asarray(imp["side"])
    return dataclasses.replace(sig, values=vals, errors=errs, impacts=imp)


def compare(real: Signature, sim: Signature, rep_var: dict[str, float], *,
            allow_mirror: bool = False) -> GapComponents:
    """Gap components of ``sim`` against ``real`` (see module docs).

    The noise scale of a statistic uses the real side's own standard error, the
    replicate variance of the nominal model and the floor -- never the simulated
    side's own scatter, so that a candidate cannot "explain" a gap by being noisy.
    With ``allow_mirror`` the better of ``sim`` and :func:`mirror` (``sim``) is used.
    """
    if allow_mirror:
        a = compare(real, sim, rep_var)
        b = compare(real, mirror(sim), rep_var)
        return b if b.total < a.total else a
    per, diff = {}, {}
    for name, (_g, floor, _d) in STATS.items():
        if name == "timing.returnmap":
            d = energy_distance(real.returnmap, sim.returnmap)
            if not np.isfinite(d):
                per[name], diff[name] = 0.0, math.nan
                continue
            s2 = rep_var.get(name, 0.0) + floor ** 2 + FORM_SCALE.get(name, 0.0) ** 2
            per[name], diff[name] = float(d ** 2 / s2), d
            continue
        a, b = real.values.get(name, math.nan), sim.values.get(name, math.nan)
        if not (np.isfinite(a) and np.isfinite(b)):
            per[name], diff[name] = 0.0, math.nan
            continue
        ea = real.errors.get(name, 0.0)
        s2 = ea ** 2 + rep_var.get(name, 0.0) + floor ** 2 + FORM_SCALE.get(name, 0.0) ** 2
        per[name], diff[name] = float((a - b) ** 2 / s2), float(a - b)
    return GapComponents(per_stat=per, diff=diff)
