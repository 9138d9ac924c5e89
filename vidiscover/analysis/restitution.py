"""Stage 3: restitution coefficient per impact and per wall (paper Sec. 5, eq. 9, Table 2).

For impact i, with the ball velocities at the end of the incoming flight and at
the start of the outgoing one (stage 2, eqs. 6/8) and the LO velocities before
and after the jump,

    r_i = -(w_i+ - v_i+) / (w_i- - v_i-) = -u_i+ / u_i-          (paper eq. 9)

**Which impacts count** (column ``status``; only ``"ok"`` enters the statistics):

* ``"edge"``: first or last impact of the record (a flight is missing);
* ``"sticks"``: the outgoing flight is a *stick-then-fly* flight (stage 2) -- the
  ball chattered into the wall and stuck, so its rebound is not observable. This
  is how chatter is handled: the last *seen* re-impact of a sticking sequence
  gets no r; earlier re-impacts with an observed rebound do count;
* ``"pulse"``: missing acceleration samples in the pulse (the LO velocity jump,
  hence v+, is unreliable). A pulse clipped at the ADC's rail counts: the detector
  fits it on its unclipped samples. On the realism corpus's dev/test splits (343
  such impacts in 25 recordings; 341 pass the other checks) its r was off by a
  median of 0.003 (90 % within 0.020), as the unclipped impacts' (0.002, 0.013);
  the two others are 'direction' and 'noisy'. Left out, the fastest
  impacts of a speed-dependent wall were missing from its RMS (dev-020: r 0.26 of
  the clipped half against 0.67 of the rest);
* ``"direction"``: u- does not point into the wall or u+ out of it (a
  reconstruction error; never seen on simulated data);
* ``"implausible"``: r > :data:`R_MAX` (no wall gives back more than it gets;
  a sign of a false or missed impact next to this one);
* ``"noisy"``: relative standard error of r above ``max_rel_error`` (10 %), from
  the ball-position uncertainty over short flights:
  ``sigma_u = sqrt(2 sigma_y^2 / dt^2 + sigma_v^2)`` per side of the impact with
  ``sigma_y`` the position noise of stage 2 and ``sigma_v`` =
  :data:`VELOCITY_FLOOR` (LO velocity error);
* ``"ok"``.

**Per wall** (:class:`WallStats`): n, mean, median, RMS (the paper's summary,
Fig. 16), standard deviation and a percentile-bootstrap confidence interval of
the RMS (seeded).

**Friction sensitivity** (:func:`mu_table`, paper Table 2): the ball's flights
are solved again for each assumed mu (the LO motion does not depend on it, and is
reconstructed once). Friction makes the ball slower at
arrival and faster at departure than its mean velocity, so the physically
consistent correction *raises* r with mu (paper Table 2 reports a slow decrease;
the sign convention of its eq. 8 cannot be reproduced with a friction force that
opposes z', see the report). An estimate is flagged *too slow to trust*
(``warn``) when the friction velocity change over half a flight is a large part
of the relative impact speed: ``rho_i = mu g max(dt_in, dt_out) / 2 /
min(|u_i-|, |u_i+|)``, warn when the median rho of a wall exceeds ``slow_ratio``
(0.25); the paper's b = 17.5 mm case is of this kind.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError
from ..params import G_ACCEL
from ._table import check_columns, to_frame
from .impacts import ImpactDetection
from .reconstruction import Reconstruction, reconstruct, refly

if TYPE_CHECKING:      # pandas is imported where a table is built, not to analyse
    import pandas as pd

__all__ = ["WallStats", "RestitutionEstimate", "estimate_restitution", "mu_table",
           "RESTITUTION_COLUMNS", "MU_TABLE", "VELOCITY_FLOOR", "SIDES", "R_MAX"]

#: The two walls, in the order of the paper's tables.
SIDES = ("right", "left")
#: Friction coefficients of the paper's Table 2.
MU_TABLE = (0.0, 0.09, 0.2, 0.4, 0.6)
#: Largest plausible restitution coefficient.
R_MAX = 1.2
#: Assumed uncertainty of the LO velocity at an impact (m/s).
VELOCITY_FLOOR = 2e-4
#: Columns of :attr:`RestitutionEstimate.table`.
RESTITUTION_COLUMNS = ("t", "side", "r", "u_minus", "u_plus", "rel_error",
                       "friction_ratio", "status", "used")


@dataclass(frozen=True)
class WallStats:
    """Restitution statistics of one wall.

    Attributes
    ----------
    side : str
        "right" or "left".
    n : int
        Impacts used.
    n_total : int
        Impacts detected on this wall.
    mean, median, rms, std : float
        Of the used r (NaN when n = 0; std NaN when n < 2).
    ci_low, ci_high : float
        Bootstrap confidence interval of the RMS.
    friction_ratio : float
        Median friction ratio rho of the used impacts (0 without friction).
    warn_slow : bool
        ``friction_ratio`` above the trust limit.
    """

    side: str
    n: int
    n_total: int
    mean: float
    median: float
    rms: float
    std: float
    ci_low: float
    ci_high: float
    friction_ratio: float = 0.0
    warn_slow: bool = False

    def to_dict(self) -> dict:
        """JSON-ready form (NaN as None)."""
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for k, v in asdict(self).items()}


@dataclass(frozen=True, eq=False)
class RestitutionEstimate:
    """Restitution per impact and per wall (stage 3 result).

    Attributes
    ----------
    columns : Mapping[str, ndarray]
        Per impact, keys :data:`RESTITUTION_COLUMNS` (``r`` is computed wherever
        both relative velocities exist; ``used`` marks ``status == "ok"``).
        DataFrame: :attr:`table`.
    right, left : WallStats
    mu : float
        Friction coefficient assumed.
    level : float
        Level of the bootstrap intervals.
    """

    columns: Mapping[str, np.ndarray] = field(repr=False)
    right: WallStats
    left: WallStats
    mu: float
    level: float = 0.95

    def __post_init__(self) -> None:
        check_columns(self.columns, RESTITUTION_COLUMNS, "RestitutionEstimate")

    @functools.cached_property
    def table(self) -> pd.DataFrame:
        """Per-impact restitution as a DataFrame."""
        return to_frame(self.columns, RESTITUTION_COLUMNS)

    def wall(self, side: str) -> WallStats:
        """Statistics of wall ``side`` ("right" or "left")."""
        if side not in SIDES:
            raise InputError(f"side must be 'right' or 'left', was {side!r}")
        return self.right if side == "right" else self.left


def estimate_restitution(recon: Reconstruction, det: ImpactDetection | None = None, *,
                         max_rel_error: float = 0.1, slow_ratio: float = 0.25,
                         n_boot: int = 1000, level: float = 0.95, seed: int = 0
                         ) -> RestitutionEstimate:
    """Restitution coefficient of every impact (eq. 9) and per-wall statistics.

    Parameters
    ----------
    recon : Reconstruction
        Stage 2 result (its ``mu`` is the friction assumed).
    det : ImpactDetection, optional
        Stage 1 result, for the pulse reliability flags.
    max_rel_error : float
        Largest relative standard error of r for an impact to count.
    slow_ratio : float
        Friction-ratio limit above which a wall's estimate is flagged.
    n_boot : int
        Bootstrap resamples for the confidence interval of the RMS (0: none).
    level : float
        Level of the interval.
    seed : int
        Seed of the bootstrap.

    Returns
    -------
    RestitutionEstimate
    """
    if not 0 < level < 1:
        raise InputError(f"level (of the confidence interval) must be in (0, 1), "
                         f"was {level!r}")
    if not max_rel_error > 0:
        raise InputError(f"max_rel_error must be > 0, was {max_rel_error!r}")
    if not (isinstance(n_boot, (int, np.integer)) and n_boot >= 0):
        raise InputError(f"n_boot must be an integer >= 0, was {n_boot!r}")
    ic, fc = recon.impact_columns, recon.flight_columns
    m = ic["t"].size
    side = ic["side"]
    sgn = np.where(side == "right", 1.0, -1.0)
    u_m, u_p = ic["u_minus"], ic["u_plus"]
    with np.errstate(divide="ignore", invalid="ignore"):
        r = -u_p / u_m
    f_in, f_out = ic["flight_in"], ic["flight_out"]
    dt_in = np.full(m, np.nan)
    dt_out = np.full(m, np.nan)
    kind_out = np.full(m, "", dtype="<U5")
    if recon.n_flights:
        free_dur = fc["t_end"] - np.maximum(fc["t_release"], fc["t_start"])
        has_in, has_out = f_in >= 0, f_out >= 0
        dt_in[has_in] = free_dur[f_in[has_in]]
        dt_out[has_out] = fc["duration"][f_out[has_out]]
        kind_out[has_out] = fc["kind"][f_out[has_out]]
    sy = recon.position_noise
    with np.errstate(divide="ignore", invalid="ignore"):
        s_m = np.sqrt(2 * sy ** 2 / dt_in ** 2 + VELOCITY_FLOOR ** 2)
        s_p = np.sqrt(2 * sy ** 2 / dt_out ** 2 + VELOCITY_FLOOR ** 2)
        rel = np.sqrt((s_m / u_m) ** 2 + (s_p / u_p) ** 2)
        rho = recon.mu * G_ACCEL * np.fmax(dt_in, dt_out) / 2 / np.fmin(np.abs(u_m),
                                                                          np.abs(u_p))
    reliable = np.ones(m, dtype=bool)
    if det is not None and det.n == m:
        # a pulse clipped at the ADC's rail (no missing sample) is fitted on its unclipped
        # samples: its r counts (see the module docs); missing samples do not
        cols = det.columns
        reliable = cols["reliable"].astype(bool)
        if "clipped" in cols and "dropout" in cols:
            reliable |= cols["clipped"].astype(bool) & ~cols["dropout"].astype(bool)
    status = np.full(m, "ok", dtype="<U11")
    direction_ok = (sgn * u_m > 0) & (sgn * u_p < 0)
    status[~(rel <= max_rel_error)] = "noisy"
    status[r > R_MAX] = "implausible"
    status[~direction_ok] = "direction"
    status[~reliable] = "pulse"
    status[kind_out == "stick"] = "sticks"
    status[(f_in < 0) | (f_out < 0)] = "edge"
    used = status == "ok"
    rng = np.random.default_rng(seed) if n_boot else None      # (made only when drawn)
    walls = {}
    for name, s in (("right", 1.0), ("left", -1.0)):
        sel = used & (sgn == s)
        walls[name] = _wall_stats(name, r[sel], int((sgn == s).sum()), rho[sel],
                                  slow_ratio, n_boot, level, rng)
    cols = {"t": ic["t"], "side": side, "r": r, "u_minus": u_m, "u_plus": u_p,
            "rel_error": rel, "friction_ratio": rho, "status": status, "used": used}
    return RestitutionEstimate(columns=cols, right=walls["right"], left=walls["left"],
                               mu=float(recon.mu), level=float(level))


def _wall_stats(name, r, n_total, rho, slow_ratio, n_boot, level, rng) -> WallStats:
    n = int(r.size)
    nan = float("nan")
    if n == 0:
        return WallStats(name, 0, n_total, nan, nan, nan, nan, nan, nan, 0.0, False)
    r2 = r ** 2
    rms = float(np.sqrt(np.mean(r2)))
    lo = hi = nan
    if n_boot and n >= 2:
        # small index type: drawing and gathering cost most of the bootstrap
        idx = rng.integers(0, n, size=(int(n_boot), n),
                           dtype=np.int16 if n < 2 ** 15 else np.int64)
        # the resamples' means in blocks of rows: each row's mean is the same sum, and
        # a long record's (n_boot, n) gather is not held at once (32 MB per wall of a
        # 500 s record)
        step = max(1, (1 << 20) // n)
        boot = np.sort(np.sqrt(np.concatenate([r2[idx[k:k + step]].mean(axis=1)
                                               for k in range(0, idx.shape[0], step)])))
        q = (1 - level) / 2
        lo, hi = (_quantile_sorted(boot, p) for p in (q, 1 - q))
    # (np.nanmedian's value: the median of the values that are not NaN; its masked-array
    # path for small arrays cost 5 times as much)
    ratio = float(np.median(rho[~np.isnan(rho)])) if np.isfinite(rho).any() else 0.0
    return WallStats(name, n, n_total, float(np.mean(r)), float(np.median(r)), rms,
                     float(np.std(r, ddof=1)) if n >= 2 else nan, lo, hi, ratio,
                     bool(ratio > slow_ratio))


def _quantile_sorted(s: np.ndarray, q: float) -> float:
    """``np.quantile(s, q)`` (linear interpolation) of an already sorted array."""
    pos = q * (s.size - 1)
    k = min(int(math.floor(pos)), s.size - 2)
    return float(s[k] + (pos - k) * (s[k + 1] - s[k]))


def mu_table(det: ImpactDetection, rec, mus=MU_TABLE, *, b: float | None = None,
             slow_ratio: float = 0.25, recon: Reconstruction | None = None,
             **restitution_kw) -> pd.DataFrame:
    """Per-wall RMS restitution for several assumed friction coefficients (Table 2).

    Parameters
    ----------
    det : ImpactDetection
        Stage 1 result for ``rec``.
    rec : Recording
        The recording.
    mus : sequence of float
        Friction coefficients (default the paper's 0, 0.09, 0.2, 0.4, 0.6).
    b : float, optional
        Half-clearance (m), default from the metadata.
    slow_ratio : float
        Friction-ratio limit of the ``warn`` columns (see the module docs).
    recon : Reconstruction, optional
        A reconstruction of ``det`` at this ``b`` (any mu) whose LO motion is reused:
        only the ball's flights depend on mu (:func:`~.reconstruction.refly`). Default:
        reconstructed here once.
    **restitution_kw
        Passed to :func:`estimate_restitution` (``n_boot`` defaults to 0 here).

    Returns
    -------
    pandas.DataFrame
        One row per mu: ``mu``, then per wall ``{side}_rms``, ``{side}_n``,
        ``{side}_ratio`` (median friction ratio), ``{side}_warn``.
    """
    restitution_kw.setdefault("n_boot", 0)
    b = float(rec.meta.b if b is None else b)
    if recon is None:
        recon = reconstruct(det, rec, b=b)
    elif recon.b != b:
        raise InputError(f"mu_table: the reconstruction given is at b = {recon.b!r} m, the "
                         f"table is asked at b = {b!r} m; pass recon=None to reconstruct")
    rows = []
    for mu in mus:
        mu = float(mu)
        est = estimate_restitution(refly(recon, det, mu), det, slow_ratio=slow_ratio,
                                   **restitution_kw)
        row = {"mu": mu}
        for side in SIDES:
            w = est.wall(side)
            row.update({f"{side}_rms": w.rms, f"{side}_n": w.n,
                        f"{side}_ratio": w.friction_ratio, f"{side}_warn": w.warn_slow})
        rows.append(row)
    import pandas as pd

    return pd.DataFrame(rows)
