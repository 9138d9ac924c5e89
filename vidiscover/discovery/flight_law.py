"""Flight-law discovery: the ball's law of motion between impacts, by sparse regression.

The ball is never measured. What the data constrain, per recording analysed by
:func:`vidiscover.analysis.analyze`:

* its position at every impact, ``y(t_i) = x(t_i) + s_i b`` (s = +1 right wall);
* its velocity jump at every impact, from momentum conservation,
  ``dw_i = -(m1 / m2) dv_i`` with ``dv_i`` the LO velocity jump (pulse area);
* the LO motion inside every flight, hence the relative velocity ``z' = y' - x'``
  once the ball velocity is reconstructed.

**Weak form.** Multiply ``y'' = sum_j c_j f_j(z')`` by the tent function ``phi_i``
that rises linearly from 0 at the impact before ``t_i`` to 1 at ``t_i`` and falls
back to 0 at the impact after it, and integrate over the two whole flights around
``t_i``. The left side integrates by parts into the two mean flight velocities
(known from the impact positions) and the velocity jump at ``t_i`` (known from the
pulse area); the unknown launch velocities drop out::

    wbar_i - wbar_{i-1} - dw_i - int_stick phi_i x'' dt
        = sum_j c_j int_free phi_i f_j(z'(t)) dt          (one row per impact)

``wbar = (y_end - y_start) / (t_end - t_start)``. While the ball sticks to the LO
(z' = 0) it follows the LO (y'' = x''): those intervals are moved to the left side
and dropped from every library column. The candidate functions ``f_j`` (constant,
``sgn(z')`` and distractors, :data:`FLIGHT_TERMS`) are evaluated by a pysindy
``CustomLibrary`` on the reconstructed ``z'`` along every flight and integrated
against the tents; a pysindy ``STLSQ`` regresses the rows on the columns, each
column scaled by the RMS of its function over the free-flight samples, so the
threshold reads as an acceleration (m/s^2): a term is kept when its typical
contribution to y'' exceeds ``threshold`` (see **Selection**).

**Iteration with the reconstruction.** ``z'(t)`` depends on the law: starting from
straight flights (mu = 0, theta = 0), each pass reconstructs the ball in every
flight with the current ``mu = -c_sgn / g`` and ``theta = asin(c_1 / g)``
(:func:`vidiscover.analysis.friction.solve_flights` along the measured LO velocity;
a constant acceleration is absorbed by a change of frame, see
:func:`reconstruct_flights`), rebuilds the library integrals and regresses again,
until the support and the coefficients settle. The first passes fit only the
constant and ``sgn(z')`` (the law the reconstruction can integrate), from three
starting laws; the fixed point that closes the rows best with its own law wins,
and fixed points that close them about as well (AICc within ``window``) but lie
elsewhere are rivals: mu and theta are then confounded (not identified).

**What one recording can tell.** In a periodic orbit every tent sees the same
pair of flights, so the constant and ``sgn(z')`` columns are proportional and only
one combination of mu and theta is determined (the paper's b = 9 mm, two impacts
per cycle): the law is then not identified (:attr:`FlightLawResult.collinearity`).
Pooling clearances (or any recordings with different flight patterns, or flights
in which z' changes sign) separates the two.

**Selection.** A pysindy ``STLSQ`` threshold sweep proposes supports; they and
the nested physical forms (constant, friction, both, both plus one candidate) are
refitted by least squares and scored by AICc; the sparsest within ``window`` of
the best is kept, provided every kept term contributes at least ``threshold``.
Over the speeds of a flight the odd candidates (``z'``, ``z'|z'|``, ``z'^3``) are
nearly collinear with ``sgn(z')``, which is why supports are limited to
``max_terms`` terms.

**Uncertainty.** Tents (an impact with its two whole flights) are resampled with
``numpy.random.default_rng(seed)``; every resample re-runs the sparse regression
on the final library integrals. Percentiles of mu and theta over the resamples
(zero where a term is dropped) give the intervals; the share of resamples keeping
each term is reported as its inclusion probability.

**Contact geometry.** A compliant contact is not an impact at its entry: its
equivalent instantaneous impact (where the ball's approach and rebound lines meet)
lies at the centroid of the contact force, ``r tau / (1 + r)`` after the entry for a
contact that ends on the wall, about 0.5-1 % of a flight's length for the corpus's
walls, as much as friction's share of the jumps. The analysis gives the contact
entry; when the learned pulses have a duration, the tents are built between the
equivalent impacts at the learned force's centroid
(:meth:`FlightData.equivalent_impacts`, :func:`~vidiscover.analysis.flights.force_centroids`).
The centroids' times are right within a few us, but the depth beyond the wall,
``|u-|`` times the time from the learned entry to the centroid, is not: the learned
entry leads the true one (holdout6-009/-010: by 14-26 us, 35-120 um outward, which
reads as a wider clearance, less friction), and on holdout6 0-29 that time is off by
-150..+115 us, its own per case. With ``penetration="free"`` (off by default,
:data:`_PENETRATION`) one error of the penetration times per recording is taken out of
the rows (:meth:`_Tents.depth_columns`, projected off like the free jump gains). The
learned durations are not exact either (Hunt-Crossley walls' are learned 27-65 % too
long, once 3.6 times): the (constant, friction) fixed point is recomputed with them
:data:`_TAU_SCALE` times as long. Half that move (:data:`_PLACEMENT_SHARE`: the move with
the durations 1.54 times too long, the typical error) is the placement's standard
uncertainty; it joins the fit's standard errors (in quadrature), and the law is not
identified when the totals exceed :data:`MAX_MU_SE` or :data:`MAX_THETA_SE`.

**Admissibility.** Candidate laws with mu < 0 are not considered (the selection is
constrained to mu >= 0): where the free fit lands slightly below zero, the law
without friction is kept if it still closes the tents within their precision. A
free fit more than twice its standard error (and more than 0.005) below zero is not
identified (mu >= 0 does not close the tents).

**Pulse-area scale per wall.** The pulse areas' errors behind causal filters and
compliant walls are mostly a scale per wall, repeated at every impact, which the
standard errors do not cover. The (constant, friction) fit is redone with one free
scale of the jumps per wall. When that moves mu by more than :data:`MAX_MU_SE`,
significantly (Hausman chi2 with 2 degrees of freedom above its 99 % point), the law
is not identified (test-054: mu 0.147 for 0.183, moved by 0.034); a significant move
of theta alone by more than :data:`MAX_THETA_SE` only carries a warning (refusing
those too removed the independent simulator's pooled law, which is within
tolerance).

**Pulse-area gain per recording and wall** (``jump_gain_sd``, off by default). The
detected jumps carry a gain of their own per recording and wall (+0.03 to +0.6 % of
|dv| on the corpus: the learned pulse shape against the recorded one and a baseline
dip under the pulses), which moves mu by ~0.05 per 0.1 %. ``jump_gain_sd=math.inf``
frees one gain per recording and wall (the rows are projected off those columns, so
every fit, selection, refusal and standard error is that of the law whatever the
gains); a finite value weights the rows as if each gain were drawn with that spread
(random effects; the standard errors include the gains' uncertainty). Either way a
gain beyond :data:`_MAX_GAIN` is not a pulse-area error: not identified. Off by
default because the gains cost more than they give (:data:`_GAIN_SD`).

**Friction from the LO's reaction.** The LO feels the ball's friction directly
between impacts; :func:`~vidiscover.analysis.lo_reaction.lo_reaction` reads mu from the
measured acceleration without any pulse area (exact engine within 0.013, the independent
simulator's pool 0.102 +/- 0.004 for 0.1). Where it is identified, 3 or more recordings
are pooled, and the flights alone confound mu and theta (collinear columns, a standard
error of mu above :data:`MAX_MU_SE`, or rival fixed points: :func:`_confounded`), it joins
the regression as one more row (:meth:`_Tents.set_prior`, weighted by its standard error;
drawn from its normal distribution in every bootstrap resample): the collinearity refusal
is lifted, and a flights' mu more than 3 standard errors from it refuses the law (three
recordings at the paper's 9 mm, exact engine: (0.091, 0.85 deg) for (0.1, 1 deg), not
identified without it). Where the flights determine mu their law stands as it is: the
LO's reading can be off (0.258 +/- 0.006 for 0.3 on the exact engine's short records,
0.240 +/- 0.003 for 0.272 on holdout16-056). With fewer than 3 recordings the
leave-one-recording-out check cannot run, and a theta the confound used to hide passes
unseen (exact engine, 7.5 mm alone: 1.5 deg off), so the LO's mu is then only reported
(``lo_friction``).

**Leave one recording out.** The standard errors cover the rows' scatter, not a
model-form error that differs between recordings (walls of unequal stiffness seen at
other speeds; a placement or pulse-area error of each recording's own), which the law
absorbs with a small standard error (spent holdout10: theta 0.35-0.95 deg off, se
0.06-0.12 deg). The (constant, friction) fit is redone with each recording left out
(:func:`_jackknife`); when the fits spread theta by more than :data:`MAX_THETA_SE`, or
(friction kept) mu by more than twice :data:`MAX_MU_SE` (jackknife standard errors), the
law is not identified (with 3 recordings or more: one recording alone is often
confounded). A model-form error shared by all recordings does not move the
sub-fits and is not caught (holdout10-036).

**Standard errors of the law as selected.** When a distractor is kept beside friction
or the constant, mu and theta carry the standard errors of that support too (the
distractor is nearly collinear with ``sgn(z')``): a law whose friction is shared with
``z'`` is not identified on the (constant, friction) fit's precision.

Examples
--------
>>> from vidiscover import Effects, preset, record, simulate
>>> from vidiscover.analysis import analyze
>>> fx = Effects.parse(["coulomb_friction=0.3", "asymmetric_restitution=0.88,0.88"])
>>> outs = [analyze(record(simulate(preset("paper", b=b), fx, settle=10.0))[0], n_boot=10)
...         for b in (0.006, 0.0075, 0.009)]
>>> res = discover_flight_law(outs, n_boot=50)
>>> res.terms, abs(res.mu - 0.3) < 0.03
(["sgn(z')"], True)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..analysis.flights import STEPS, FlightData, reconstruct_flights, solve_free_flights
from ..analysis.lo_reaction import LoReaction, lo_reaction_of, pooled_lo_reaction
from ..errors import InputError
from ..params import G_ACCEL
from .sparse import (
    aicc,
    bootstrap_rows,
    inclusion,
    library_matrix,
    percentile_interval,
    threshold_sweep,
)

__all__ = ["FLIGHT_TERMS", "DEFAULT_LIBRARY", "MAX_TILT_DEG", "FlightLawResult",
           "discover_flight_law",
           "flight_law_mu_theta", "reconstruct_flights", "reconstruct_with_law"]

#: Candidate functions of the relative velocity z' (m/s), by name.
FLIGHT_TERMS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "1": lambda z: np.ones_like(z),
    "sgn(z')": lambda z: np.sign(z),
    "z'": lambda z: z,
    "z'|z'|": lambda z: z * np.abs(z),
    "z'^3": lambda z: z ** 3,
    "sgn(z')|z'|^0.5": lambda z: np.sign(z) * np.sqrt(np.abs(z)),
}
#: Library used by default: the physical terms and three distractors (drag laws).
DEFAULT_LIBRARY = ("1", "sgn(z')", "z'", "z'|z'|", "z'^3")

_FRICTION = "sgn(z')"
_CONSTANT = "1"
_MAX_ITER = 8
_N_THRESHOLDS = 12
_MAX_MISFIT = 0.01          # largest RMS residual / RMS ball velocity jump
#: Largest misfit the jumps' precision can excuse. The precision (area - fitted area) is
#: inflated behind steep filters (holdout6-006: 12.8 % for true jump errors of 0.8-3 %),
#: and a misfit of 2 % is half friction's share of the jumps (mu g T / jump ~ 4 % at
#: mu 0.15): test-023 (39 of 239 weak left-wall impacts missed in chatter) misfit 4.4 %,
#: precision 4.6 %, was identified at mu 0.010 for 0.153. The laws identified within
#: tolerance on dev/test/holdout6 misfit 0.6-1.4 %.
_MAX_MISFIT_EXCUSED = 0.02
_CONSTRAINED = True         # candidate laws with mu < 0 are not considered
_SCALE_TEST = False         # True: refuse laws that move with a free pulse-area scale per wall
#: Spread (sd, relative) of the pulse areas' gain per recording and wall that the rows
#: take out by default (:meth:`_Tents.basis`, ``jump_gain_sd``): 0, none (the areas taken
#: as they are, with :func:`_wall_scale_test` as the check). Measured on cached analyses
#: (test 0-59, dev 0-23; holdout6/holdout7 0-59 as a check), identified (all within):
#: 0 -> 3, 0, 4, 3; 0.25 % -> 3, 0, 3, 4; 0.4 % -> 3, 0, 3, 4; free -> 1 on test. The
#: cases change (test-020 lost, -054 or -048 won), the count does not. The gains cost
#: what the rows know about theta (its standard error
#: 2-5 times larger: the jumps grow with the flights' durations, nearly along the
#: constant's column), and at 0.4 % the exact engine's pooled laws go from 27/27 to 3/27
#: (theta se 0.05 -> 0.16 deg); free, test-020 lands at theta -1.67 deg for 0. One free
#: gain per recording (both walls, ``jump_gain_per="recording"``): 3, 0, 4, 3 (test-054
#: won at mu 0.179 for 0.183, test-020 lost to a misfit), the exact grid 27/27 with theta
#: se at most 0.056 deg (0.05 without): the candidate default, not yet taken.
_GAIN_SD = 0.0
#: Largest fitted gain of one recording's pulse areas at one wall (relative) that is
#: taken for a pulse-area error; beyond it the rows miss something else.
_MAX_GAIN = 0.02
#: Standard errors of mu and theta from the selected support too (:func:`_support_errors`).
_SUPPORT_SE = True
_HAUSMAN = 9.21             # chi2(2) at 99 %
#: Leave-one-recording-out check (:func:`_jackknife`): the law is not identified when the
#: (constant, friction) fits with one recording left out spread theta by more than
#: :data:`MAX_THETA_SE`, or (friction kept) mu by more than ``_JACKKNIFE_MU`` times
#: :data:`MAX_MU_SE` (jackknife standard errors). Spent holdout10 identified four wrong
#: laws with small standard errors (Hunt-Crossley walls of unequal stiffness; theta
#: 0.35-0.95 deg off, se 0.06-0.12 deg): three move between recordings (jackknife theta
#: se 0.18-0.30 deg) and are refused, the fourth (-036, 0.42 deg off) does not (0.05).
#: Cached analyses, identified / within / wrong, off -> on: test 3/3/0 -> 3/3/0, dev 0 ->
#: 0, holdout6 4/4/0 -> 3/3/0, holdout7 3/3/0, holdout8 7/7/0, holdout9 5/5/0 -> 4/4/0,
#: holdout10 9/5/4 -> 5/4/1; exact grid 27/27 -> 27/27 (jackknife theta se <= 0.10 deg);
#: independent P04-P06 identified (0.085 deg). Lost right laws: holdout6-026 (mu 0.115
#: for 0.101, jackknife 0.041 / 0.29 deg), holdout9-058, holdout10-033 (theta 0 for
#: 0.27, five of its se off). Friction's spread is looser (right laws up to 0.024 in mu,
#: holdout8-030, holdout9-044: two recordings left span fewer flight durations); with a
#: factor 1.5 two more right laws are lost and no wrong one.
_JACKKNIFE = True
_JACKKNIFE_MU = 2.0
_MU_NEGLIGIBLE = 0.005       # a free fit this little below mu = 0 is mu = 0
_MAX_DISTRACTORS = 1        # terms besides constant and friction in one candidate
#: Starting laws (mu, theta_deg) of the reconstruction fixed point.
_STARTS = ((0.0, 0.0), (0.3, 2.0), (0.3, -2.0))
#: Factor on the learned contact durations of the placement test: Hunt-Crossley walls'
#: durations are learned 27-65 % too long (holdout6-006/-010; one 3.6 times, -006 at
#: 0.67 b), Kelvin-Voigt ones within 7 % (-001/-009); the law must hold with them 0.3
#: times as long.
_TAU_SCALE = 0.3
#: Standard uncertainty of the contact placement, as a share of the law's move with the
#: durations ``_TAU_SCALE`` times as long (:func:`_geometry_shift`). The move is linear in
#: the durations' factor (median move at 0.65 over that at 0.3: 0.500 for mu, 10-90 %
#: 0.49-0.50, on 98 cached spent cases), so 0.5 is the move at 0.65: the durations
#: learned 1.54 times too long, the middle of the measured 1.27-1.65. It joins the fit's
#: standard errors, ``se_total = hypot(se, 0.5 |move|)``, which decide against
#: :data:`MAX_MU_SE` and :data:`MAX_THETA_SE` and are reported. Before, the move itself
#: had to be within those bounds (a 3-times error taken as a 1-sigma one). Spent splits
#: test, dev, holdout6-12 (cached analyses, flight23), identified right / wrong: 30 / 1
#: -> 35 / 1 (test-048, holdout10-017, holdout12-010, -023, -037 won; none lost; the wrong
#: law is holdout10-036 in both). All spent splits served for tuning: simple on purpose.
_PLACEMENT_SHARE = 0.5
#: With the penetration depths free (``penetration="free"``) the same factor: the test
#: then probes the centroids' times. Measured with the depths free on cached analyses
#: (identified / wrong): 0.3 -> test 3/0; 0.5 -> test 4/0, dev 0/0, holdout6 4/0,
#: holdout7 4/0, holdout8 6/0, but the unit test's instantaneous impacts told of 1 ms
#: contacts give a wrong law (mu 0.132 for 0.1); 0.7 -> test 5/0, holdout6 1 wrong (-008,
#: theta 1.04 for 0.70); none -> test 8/0, dev 1 wrong (-021), holdout6 1 wrong (-008).
#: Where the equivalent impacts lie beyond the walls (``penetration``): "free" takes one
#: error of the learned penetration time per recording out of the rows
#: (:meth:`_Tents.depth_columns`), "learned" takes the learned force centroids as they are.
#: The learned points lie 35-120 um beyond the true ones on holdout6-009/-010 (the learned
#: entry leads the true one by 14-26 us and ``|u-|`` times it is counted as depth; on
#: holdout6 0-29 the error is -150..+115 us, its own per case), which reads as a clearance
#: too wide: with the true jumps at those points -010 (mu 0.112, theta 0.43) fits 0 / 0
#: with se 0.03; free, 0.112 / 0.45 deg with se 0.003 (still refused by the placement
#: test), -009 (0 / 2.49) 0 / 2.26 -> 0 / 2.37. Off by default: on cached analyses it moves
#: more fits within tolerance (identified or not: test 21 -> 25 of 60, dev 7 -> 10 of 24,
#: holdout7 20 -> 25) but identifies no more (test 3/0 -> 3/0: 054 won, 020 lost to
#: a sparse step drifting to z'|z'|) unless the placement test is eased (see _TAU_SCALE).
#: Do not make "free" the default: one free depth per recording acts like a free
#: clearance, which trades against friction and tilt. On spent holdout9 it identified two
#: wrong laws with small standard errors that "learned" refuses (holdout9-040: theta 0.97
#: for 1.31 deg; -052: mu 0.126 for 0.289), with or without the placement test, and a
#: placement test that moves only the impact times separates right from wrong no better
#: (test/dev/holdout6-8: 17 identified, 17 within, either way; flight19).
_PENETRATION = "learned"
_AMBIGUOUS = (0.02, 0.2)    # fixed points further apart than this (mu, deg) are rivals
_COLLINEAR = 0.99           # cosine above which mu and theta are confounded
_TOL_MU, _TOL_THETA = 5e-4, 5e-3   # fixed point reached (mu, deg)
#: Largest admissible |theta| (deg) unless the caller widens it.
MAX_TILT_DEG = 10.0
#: Largest standard error of mu / theta (deg) of an identified law: the accuracy the
#: law is meant to have (beyond it the flights do not determine the parameter, e.g.
#: friction in flights of equal duration, whose tent integrals cancel).
MAX_MU_SE, MAX_THETA_SE = 0.015, 0.15


# ------------------------------------------------------------------------ result
@dataclass(frozen=True)
class FlightLawResult:
    """Flight law ``y'' = sum_k coefficients[k] * terms[k]`` (m/s^2), or "not identified".

    Only an identified law carries numbers as results. When the weak form misfits,
    mu and theta are confounded, or a value is physically inadmissible (mu < 0,
    |theta| above the admissible tilt), ``identified`` is False, ``reason`` says why
    in one line, ``mu``/``theta_deg`` and the intervals are NaN, ``terms`` and
    ``coefficients`` are empty, and the raw fit is kept in ``diagnostic`` only.

    Attributes
    ----------
    mu : float
        Friction coefficient, ``-c_sgn / g`` (0 when ``sgn(z')`` is not kept; NaN
        when not identified).
    theta_deg : float
        Inclination (deg), ``asin(c_1 / g)`` (0 when the constant is not kept; NaN
        when not identified).
    terms : list of str
        Names of the kept terms (:data:`FLIGHT_TERMS`).
    coefficients : list of float
        Their coefficients (SI units: y'' in m/s^2, z' in m/s).
    mu_ci, theta_ci : tuple of float
        Bootstrap percentile intervals (``level``), widened to include rival fixed
        points; NaN when not identified or no bootstrap was asked for.
    equation : str
        The law as text, e.g. ``"y'' = -2.94 sgn(z') + 0.171"``, or
        ``"not identified"``.
    n_flights : int
        Flights used (in at least one tent).
    n_equations : int
        Tents (rows of the regression).
    library : tuple of str
        Candidate terms.
    inclusion : dict
        Share of bootstrap resamples keeping each candidate.
    threshold : float
        STLSQ threshold (m/s^2 of typical contribution).
    level : float
        Level of the intervals.
    iterations : int
        Passes of reconstruction + regression done.
    residual_rms : float
        RMS residual of the final regression (m/s).
    collinearity : float
        Cosine between the constant and the ``sgn(z')`` columns. In a periodic
        orbit every tent sees the same flights, the two columns are proportional
        and only one combination of mu and theta is determined (close to 1: the
        recording cannot tell friction from inclination; pool clearances).
    misfit : float
        RMS residual over RMS ball velocity jump ``(m1/m2) |dv|`` of the tents.
        Above ``max(1 %, min(precision, 2 %))`` the weak form does not hold (e.g. unseen
        re-impacts when the ball chatters on a weak wall).
    precision : float
        Relative precision of the jumps, measured in the recordings: RMS of the
        data the fitted pulse model leaves in the pulse windows (pulse area less
        model area) over RMS jump. ~0.5 % through the default sensors, 1-3 % behind
        causal anti-alias filters and compliant walls.
    mu_se, theta_se : float
        Standard errors of mu and theta (deg) from the (constant, friction) fit,
        with the residual scale at least the jumps' precision, and (compliant
        contacts) the contact placement's uncertainty in quadrature
        (``diagnostic["placement"]``: the move with the learned durations
        :data:`_TAU_SCALE` times as long, and half of it as a standard error). Above
        :data:`MAX_MU_SE` or :data:`MAX_THETA_SE` the flights do not determine
        that parameter: not identified.
    warnings : tuple of str
    identified : bool
        Whether the law is a result (admissible, not confounded, weak form holds).
    reason : str or None
        Why not identified (one line), else None.
    max_tilt_deg : float
        Largest admissible |theta| (deg).
    diagnostic : dict
        The raw fit (``mu``, ``theta_deg``, ``terms``, ``coefficients``,
        ``equation``, ``mu_ci``, ``theta_ci``) whether identified or not; not a
        result when ``identified`` is False.
    lo_friction : LoReaction or None
        Friction read from the LO's own acceleration between impacts (the reaction of
        the ball's friction, :mod:`vidiscover.analysis.lo_reaction`), pooled over the
        recordings: a measurement independent of the pulse areas, reported beside the
        law (its own ``identified`` and ``reason``); None when the inputs carry no
        recording (FlightData given).
    """

    mu: float
    theta_deg: float
    terms: list
    coefficients: list
    mu_ci: tuple
    theta_ci: tuple
    equation: str
    n_flights: int
    n_equations: int
    library: tuple
    inclusion: dict = field(default_factory=dict)
    threshold: float = 0.0
    level: float = 0.95
    iterations: int = 0
    residual_rms: float = float("nan")
    collinearity: float = float("nan")
    misfit: float = float("nan")
    precision: float = float("nan")
    mu_se: float = float("nan")
    theta_se: float = float("nan")
    warnings: tuple = ()
    identified: bool = True
    reason: str | None = None
    max_tilt_deg: float = MAX_TILT_DEG
    diagnostic: dict = field(default_factory=dict)
    lo_friction: LoReaction | None = None

    def __post_init__(self) -> None:
        if len(self.terms) != len(self.coefficients):
            raise ValueError(f"terms and coefficients must have the same length, were "
                             f"{len(self.terms)} and {len(self.coefficients)}")
        for name in ("mu_ci", "theta_ci"):
            if len(getattr(self, name)) != 2:
                raise ValueError(f"{name} must be a (low, high) pair, was "
                                 f"{getattr(self, name)!r}")
        if self.identified == bool(self.reason):
            raise ValueError("a law is identified without a reason, or not identified "
                             "with one")
        if not self.identified and (self.terms or math.isfinite(self.mu)
                                    or math.isfinite(self.theta_deg)):
            raise ValueError("a law that is not identified carries no mu, theta or terms")

    @property
    def friction(self) -> bool:
        """Whether the friction term ``sgn(z')`` is kept."""
        return _FRICTION in self.terms

    @property
    def inclination(self) -> bool:
        """Whether the constant term (inclination) is kept."""
        return _CONSTANT in self.terms

    def mu_theta(self) -> tuple[float, float]:
        """``(mu, theta_deg)`` of the identified law, for the reconstruction.

        Raises
        ------
        InputError
            When the law was not identified.
        """
        if not self.identified:
            raise InputError(f"flight law not identified ({self.reason}); analyse with an "
                             "assumed mu instead, or pool recordings at several clearances")
        return max(float(self.mu), 0.0), float(self.theta_deg)

    def to_dict(self) -> dict:
        """JSON-ready dict.

        Keys ``identified``, ``reason``, ``mu``, ``theta_deg``, ``terms``,
        ``coefficients``, ``equation``, ``mu_ci``, ``theta_ci``, ``n_flights``,
        ``diagnostic_fit`` (the raw fit, not a result when not identified), ``lo_friction``
        (the LO's reading of mu, :class:`LoReaction`) and ``lo_friction_used`` (whether it
        joined the fit), ``jackknife``
        (the leave-one-recording-out spread, ``n_recordings``, ``mu_se``, ``theta_se``;
        None when fewer than 3 recordings were pooled) and the diagnostics.
        ``mu``/``theta_deg`` are None when not identified.
        """
        diag = self.diagnostic
        jk = diag.get("jackknife")
        jk = None if not jk or jk.get("G", 0) < 3 else {
            "n_recordings": int(jk["G"]), "mu_se": _num(jk["mu_se"]),
            "theta_se": _num(jk["theta_se"])}
        place = diag.get("placement")
        return {"identified": bool(self.identified), "reason": self.reason,
                "mu": _num(self.mu), "theta_deg": _num(self.theta_deg),
                "terms": list(self.terms),
                "coefficients": [float(c) for c in self.coefficients],
                "equation": self.equation, "mu_ci": [_num(v) for v in self.mu_ci],
                "theta_ci": [_num(v) for v in self.theta_ci],
                "n_flights": int(self.n_flights), "n_equations": int(self.n_equations),
                "library": list(self.library),
                "inclusion": {k: float(v) for k, v in self.inclusion.items()},
                "threshold": float(self.threshold), "level": float(self.level),
                "max_tilt_deg": float(self.max_tilt_deg),
                "iterations": int(self.iterations),
                "residual_rms": _num(self.residual_rms),
                "collinearity": _num(self.collinearity),
                "misfit": _num(self.misfit),
                "precision": _num(self.precision),
                "mu_se": _num(self.mu_se), "theta_se": _num(self.theta_se),
                "warnings": list(self.warnings), "jackknife": jk,
                "placement": None if place is None else {
                    k: _num(place[k]) for k in ("mu", "theta_deg", "mu_se", "theta_se")},
                "diagnostic_fit": {
                    "mu": _num(diag.get("mu", math.nan)),
                    "theta_deg": _num(diag.get("theta_deg", math.nan)),
                    "terms": list(diag.get("terms", [])),
                    "coefficients": [float(c) for c in diag.get("coefficients", [])],
                    "equation": diag.get("equation", ""),
                    "mu_ci": [_num(v) for v in diag.get("mu_ci", (math.nan, math.nan))],
                    "theta_ci": [_num(v) for v in diag.get("theta_ci",
                                                           (math.nan, math.nan))]},
                "lo_friction": (None if self.lo_friction is None
                                else self.lo_friction.to_dict()),
                "lo_friction_used": "lo_prior" in diag}


def _num(v):
    """Float, or None when not finite (JSON)."""
    v = float(v)
    return v if math.isfinite(v) else None


def flight_law_mu_theta(result: FlightLawResult) -> tuple[float, float]:
    """``(mu, theta_deg)`` of an identified law, for the reconstruction.

    Parameters
    ----------
    result : FlightLawResult

    Returns
    -------
    mu : float
        Friction coefficient (>= 0).
    theta_deg : float
        Inclination (deg).

    Raises
    ------
    InputError
        When ``result`` is not a FlightLawResult or the law was not identified.
    """
    if not isinstance(result, FlightLawResult):
        raise InputError(f"flight_law must be a FlightLawResult from discover_flight_law, "
                         f"was {type(result).__name__}")
    return result.mu_theta()


#: The fix most reasons of a flight law that is not identified share.
_POOL = "; pool recordings at several clearances"


def _join_reasons(reasons: list[str]) -> str:
    """The reasons in one line, their shared fix said once, at the end.

    Examples
    --------
    >>> _join_reasons(["a; pool recordings at several clearances", "b",
    ...                "c; pool recordings at several clearances"])
    'a; b; c; pool recordings at several clearances'
    """
    pooled = any(r.endswith(_POOL) for r in reasons)
    return "; ".join(r.removesuffix(_POOL) for r in reasons) + (_POOL if pooled else "")


def _equation(terms, coefs) -> str:
    if not terms:
        return "y'' = 0"
    parts = []
    for k, (t, c) in enumerate(zip(terms, coefs, strict=True)):
        mag = f"{abs(c):.3g}"
        body = mag if t == _CONSTANT else f"{mag} {t}"
        sign = "-" if c < 0 else ("" if k == 0 else "+")
        parts.append(f"{sign} {body}".strip() if k else f"{sign}{body}")
    return "y'' = " + " ".join(parts)


# ----------------------------------------------------------------- per recording
def reconstruct_with_law(analysis, law) -> dict:
    """Ball launch/arrival velocities of every free flight of ``analysis`` under ``law``.

    The feedback of an identified flight law into the reconstruction
    (:func:`vidiscover.analysis.flights.solve_free_flights` on the analysis's flights).

    Parameters
    ----------
    analysis : AnalysisResult
    law : FlightLawResult or tuple of float
        An identified law, or ``(mu, theta_deg)``.

    Returns
    -------
    dict
        As :func:`~vidiscover.analysis.flights.solve_free_flights`.
    """
    mu, theta = flight_law_mu_theta(law) if isinstance(law, FlightLawResult) else (
        max(float(law[0]), 0.0), float(law[1]))
    return solve_free_flights(FlightData.of(analysis), mu, theta)


# ------------------------------------------------------------------ regression
class _Tents:
    """Rows of the weak form, one per usable impact, across recordings."""

    def __init__(self, records, library: tuple[str, ...], steps: int = STEPS,
                 gain_sd: float | None = None, gain_per: str = "wall",
                 depth_free: bool = False) -> None:
        self.records = records
        self.depth_free = bool(depth_free)      # one free penetration time per recording
        self.steps = int(steps)
        self.library = library
        self.gain_sd = _GAIN_SD if gain_sd is None else float(gain_sd)
        self.gain_per = gain_per                  # "wall": per recording and wall
        rows = []
        for r, rec in enumerate(records):
            free = rec.kind == "free"
            i = np.arange(1, rec.n_flights)           # tent at impact rec.i_e[i - 1]
            imp = rec.i_e[i - 1]
            ok = free[i - 1] & free[i] & (rec.i_s[i] == imp)
            ok &= rec.reliable[imp] & rec.reliable[rec.i_s[i - 1]] & rec.reliable[rec.i_e[i]]
            ok &= np.isfinite(rec.dv[imp])
            for k in i[ok]:
                rows.append((r, k - 1, k))
        self.rows = np.array(rows, dtype=np.int64).reshape(-1, 3)
        self._assembled: dict = {}
        self._basis = None                        # rows -> rows free of the jump gains
        self.prior = None                         # (row weight, mu): see set_prior

    def set_prior(self, mu: float, mu_se: float) -> None:
        """Append a measurement of mu (e.g. the LO's reaction) as one more row.

        The row reads ``w c_sgn = -w mu g`` (``c_sgn`` the friction column's coefficient)
        with ``w = s / (g mu_se)``, ``s`` the rows' residual scale (the jumps' precision
        times their RMS), so that its residual has the tents' variance: least squares
        then weighs it as the independent measurement it is. Not with free jump gains
        (the transformed rows have another scale).
        """
        if self.transformed:
            raise ValueError("a prior on mu needs the tents untransformed (no free gains)")
        scale = max(self.precision(), 1e-6) * float(np.sqrt(np.mean(self.jumps() ** 2)))
        self.prior = (scale / (G_ACCEL * max(mu_se, 1e-9)), float(mu))
        self._assembled.clear()

    @property
    def n_prior(self) -> int:
        """Rows appended after the tents (1 with a prior on mu, else 0)."""
        return 0 if self.prior is None else 1

    def groups(self) -> np.ndarray:
        """Recording of every assembled row (-1 for the prior's, never left out alone)."""
        return np.concatenate([self.rows[:, 0], np.full(self.n_prior, -1)])

    @property
    def n_rows(self) -> int:
        """Tents (impacts with their two flights)."""
        return int(self.rows.shape[0])

    @property
    def n(self) -> int:
        """Rows of the regression: the tents less one per free jump gain or depth."""
        return int(self.basis().shape[0]) if self.transformed else self.n_rows

    @property
    def transformed(self) -> bool:
        """Whether the rows are transformed (:meth:`basis`): gains or depths taken out."""
        return self.gain_sd > 0 or self.depth_free

    def depth_columns(self) -> np.ndarray:
        """The rows' change per second of error of the penetration times, per recording.

        An equivalent impact lies ``|u-| dt`` beyond its wall, ``dt`` the learned time
        from the contact's entry to its force's centroid. An error ``d`` of ``dt`` (the
        learned entry leading the true one, the learned shape's centroid off) moves the
        impact by ``sign |u-| d`` and a row (the difference of its two flights' mean
        velocities) by ``d`` times this column. One column per recording with at least
        3 tents (an outward error reads as a wider clearance: less friction).
        """
        cols = []
        for r, rec in enumerate(self.records):
            sel = self.rows[:, 0] == r
            if sel.sum() < 3:
                continue
            p = rec.sign * np.nan_to_num(np.abs(rec.u_minus))
            a, b = self.rows[sel, 1], self.rows[sel, 2]
            i0, i1, i2 = rec.i_s[a], rec.i_e[a], rec.i_e[b]
            col = np.zeros(self.n_rows)
            col[sel] = ((p[i2] - p[i1]) / (rec.te[b] - rec.ts[b])
                        - (p[i1] - p[i0]) / (rec.te[a] - rec.ts[a]))
            cols.append(col)
        return np.array(cols).T.reshape(self.n_rows, len(cols))

    def _depth_basis(self) -> np.ndarray:
        """Orthonormal basis (rows) of the complement of the depth columns (or I)."""
        D = self.depth_columns() if self.depth_free else np.zeros((self.n_rows, 0))
        D = D[:, np.linalg.norm(D, axis=0) > 0]
        if D.shape[1] == 0:
            return np.eye(self.n_rows)
        q = np.linalg.qr(D, mode="complete")[0]
        return q[:, D.shape[1]:].T

    def sides(self) -> np.ndarray:
        """The wall of each row's impact (+1 right, -1 left)."""
        return np.array([self.records[r].sign[self.records[r].i_e[a]]
                         for r, a, _ in self.rows], dtype=float).reshape(-1)

    def wall_jumps(self) -> np.ndarray:
        """The ball velocity jumps of the rows, one column per wall (zero elsewhere).

        A scale error of one wall's pulse areas (the filter and that wall's contact
        duration) adds ``eps * column`` to the rows: see :func:`_wall_scale_test`.
        """
        jumps = self.jumps()
        side = self.sides()
        cols = [np.where(side == s, jumps, 0.0) for s in (1.0, -1.0)
                if (side == s).any()]
        return np.array(cols).T.reshape(self.n_rows, len(cols))

    def gain_columns(self) -> np.ndarray:
        """The jumps per recording and wall, one column each (zero elsewhere).

        With ``gain_per`` "recording": one column per recording (both walls).

        A gain ``g`` of one recording's pulse areas at one wall (the learned pulse shape
        against the recorded one, the baseline under the pulses: +0.03 to +0.6 % of |dv|
        on the corpus, its own per recording and wall) adds ``g * column`` to the rows.
        Columns with fewer than 3 tents are merged into none (their tents stay tied).
        """
        jumps = self.jumps()
        side = self.sides()
        cols = []
        for r in np.unique(self.rows[:, 0]) if self.n_rows else []:
            for s in ((1.0, -1.0),) if self.gain_per == "recording" else ((1.0,), (-1.0,)):
                sel = (self.rows[:, 0] == r) & np.isin(side, s)
                if sel.sum() >= 3:
                    cols.append(np.where(sel, jumps, 0.0))
        return np.array(cols).T.reshape(self.n_rows, len(cols))

    def basis(self) -> np.ndarray:
        """Transform of the rows that takes the jump gains and depths out (rows x tents).

        The free penetration depths (``depth_free``, :meth:`depth_columns`) first: the
        rows are projected onto an orthonormal basis of their complement (one row less
        per recording). Then the gains (in those rows): ``gain_sd`` infinite, an
        orthonormal basis of the complement of the gain columns (one row less per gain:
        the gains are free and the law is what the rows say whatever their values).
        Finite: the random-effects weighting ``W^(1/2)``, ``W = (I + N N' sigma_g^2 /
        s^2)^-1`` with ``s`` the jumps' precision, whose least squares and standard
        errors are those with every gain drawn with sd ``gain_sd``.
        """
        if self._basis is None:
            P = self._depth_basis()
            N = (P @ self.gain_columns() if self.gain_sd > 0
                 else np.zeros((P.shape[0], 0)))
            if N.shape[1] == 0:
                T = P
            elif math.isinf(self.gain_sd):
                q = np.linalg.qr(N, mode="complete")[0]
                T = q[:, N.shape[1]:].T @ P
            else:
                # W^(1/2) = I - U (I - (I + S^2 / lam2)^(-1/2)) U' (N = U S V'; the
                # product of the per-column updates when the columns are orthogonal)
                lam2 = self._lam2()
                U, S, _ = np.linalg.svd(N, full_matrices=False)
                shrink = 1.0 - np.sqrt(lam2 / (S ** 2 + lam2))
                T = (np.eye(P.shape[0]) - (U * shrink) @ U.T) @ P
            self._basis = np.array(T)
            self._basis.setflags(write=False)
        return self._basis

    def gains(self, resid: np.ndarray) -> np.ndarray:
        """Jump gains of the tents' residuals ``resid`` (untransformed rows).

        Relative errors of the pulse areas, one per recording and wall (+0.003: 0.3 % too
        large): least squares when the gains are free, else shrunk to 0 as their spread
        ``gain_sd`` says (the random effects' best linear prediction).
        """
        N = self.gain_columns()
        if N.shape[1] == 0:
            return np.zeros(0)
        if not self.depth_free:
            nn = np.einsum("ij,ij->j", N, N)
            return (N.T @ resid) / (nn + self._lam2())
        P = self._depth_basis()          # the gains with the free depths taken out
        N, r = P @ N, P @ resid
        return np.linalg.solve(N.T @ N + self._lam2() * np.eye(N.shape[1]), N.T @ r)

    def _lam2(self) -> float:
        """Ridge of the gains: the jumps' variance (their precision) over ``gain_sd**2``."""
        if math.isinf(self.gain_sd):
            return 0.0
        s = self.precision() * float(np.sqrt(np.mean(self.jumps() ** 2)))
        return max(s, 1e-12) ** 2 / self.gain_sd ** 2

    def jumps(self) -> np.ndarray:
        """Ball velocity jump (m/s) at the impact of every tent."""
        return np.array([self.records[r].ratio * self.records[r].dv[self.records[r].i_e[a]]
                         for r, a, _ in self.rows])

    def precision(self) -> float:
        """Relative precision of the jumps: RMS (area - dv) over RMS dv at the tents.

        ``area`` integrates the data over the pulse window, ``dv`` is the fitted
        model's area: their difference is what the pulse model misses there.
        """
        e = np.array([self.records[r].area[self.records[r].i_e[a]]
                      - self.records[r].dv[self.records[r].i_e[a]] for r, a, _ in self.rows])
        d = np.array([self.records[r].dv[self.records[r].i_e[a]] for r, a, _ in self.rows])
        ok = np.isfinite(e)
        if not ok.any():
            return 0.0
        return float(np.sqrt(np.mean(e[ok] ** 2)) / max(np.sqrt(np.mean(d[ok] ** 2)), 1e-300))

    def flights_used(self) -> int:
        keys = {(int(r), int(k)) for r, a, b in self.rows for k in (a, b)}
        return len(keys)

    def assemble(self, mu: float, theta_deg: float):
        """Reconstruct with (mu, theta) and return (Theta, Y, scales, n_sign_changes).

        Kept per law (the fixed points and the selection come back to the same laws:
        a fixed point's last law is rebuilt to score it, the selection starts from the
        best one); the arrays are read-only.
        """
        return self._cached(mu, theta_deg)[:4]

    def assemble_raw(self, mu: float, theta_deg: float):
        """``(Theta, Y)`` of the tents themselves (the jump gains not taken out)."""
        return self._cached(mu, theta_deg)[4]

    def _cached(self, mu, theta_deg):
        key = (mu, theta_deg, math.copysign(1.0, mu), math.copysign(1.0, theta_deg))
        out = self._assembled.get(key)
        if out is None:
            out = self._assembled[key] = self._assemble(mu, theta_deg)
            for a in (*out[:3], *out[4]):
                a.setflags(write=False)
        return out

    def _assemble(self, mu: float, theta_deg: float):
        J = len(self.library)
        Theta = np.zeros((self.n_rows, J))
        Y = np.zeros(self.n_rows)
        sq, cnt = np.zeros(J), 0
        changes = 0
        for r, rec in enumerate(self.records):
            sel = self.rows[:, 0] == r
            if not sel.any():
                continue
            ks = np.unique(self.rows[sel, 1:])
            fl = reconstruct_flights(rec.ts[ks], rec.te[ks], rec.y_imp[rec.i_s[ks]],
                                     rec.y_imp[rec.i_e[ks]], rec.v_plus[rec.i_s[ks]],
                                     rec.v_minus[rec.i_e[ks]], rec.lo_velocity,
                                     rec.lo_acceleration, mu, theta_deg, steps=self.steps)
            zd = fl["zd"]
            F, M1 = zd.shape
            moving = zd != 0.0
            changes += int((np.diff(np.sign(zd), axis=1) != 0).any(axis=1).sum())
            L = library_matrix(zd.reshape(-1), self.library, FLIGHT_TERMS,
                               variable="z'").reshape(F, M1, J)
            L = L * moving[:, :, None]
            frac = np.linspace(0.0, 1.0, M1)
            h = (rec.te[ks] - rec.ts[ks]) / (M1 - 1)
            trap = np.ones(M1)
            trap[[0, -1]] = 0.5
            w_in = h[:, None] * trap * frac             # tent rising to the end impact
            w_out = h[:, None] * trap * (1.0 - frac)    # tent falling from the start impact
            I_in = np.einsum("fm,fmj->fj", w_in, L)
            I_out = np.einsum("fm,fmj->fj", w_out, L)
            stick_acc = fl["acc"] * ~moving
            S_in = (w_in * stick_acc).sum(axis=1)
            S_out = (w_out * stick_acc).sum(axis=1)
            sq += (L ** 2).sum(axis=(0, 1))
            cnt += int(moving.sum())
            pos = {int(k): j for j, k in enumerate(ks)}
            a = np.array([pos[int(k)] for k in self.rows[sel, 1]])
            b = np.array([pos[int(k)] for k in self.rows[sel, 2]])
            imp = rec.i_e[self.rows[sel, 1]]
            wbar = (rec.y_imp[rec.i_e[ks]] - rec.y_imp[rec.i_s[ks]]) / (rec.te[ks] - rec.ts[ks])
            Theta[sel] = I_in[a] + I_out[b]
            Y[sel] = wbar[b] - wbar[a] + rec.ratio * rec.dv[imp] - S_in[a] - S_out[b]
        scales = np.sqrt(sq / max(cnt, 1))
        scales[scales == 0] = 1.0
        raw = (Theta, Y)
        if self.transformed:
            T = self.basis()
            Theta, Y = T @ Theta, T @ Y
        if self.prior is not None:
            w, mu0 = self.prior
            row = np.zeros((1, J))
            row[0, self.library.index(_FRICTION)] = w
            Theta = np.vstack([Theta, row])
            Y = np.concatenate([Y, [-w * mu0 * G_ACCEL]])
        return Theta, Y, scales, changes, raw


def _sweep_supports(Theta, Y, scales, threshold, n_thresholds=_N_THRESHOLDS):
    """Supports visited by a pysindy STLSQ threshold sweep (columns scaled to m/s^2)."""
    X = Theta / scales[None, :]
    full = np.linalg.lstsq(X, Y, rcond=None)[0]
    top = max(float(np.max(np.abs(full))), threshold) * 1.01
    return threshold_sweep(X, Y, np.geomspace(threshold, top, n_thresholds))


def _candidates(library, sweep, max_terms):
    """Candidate supports, as sorted index tuples.

    Sweep supports of at most ``max_terms`` terms with at most one term besides the
    constant and friction, plus the nested physical forms (every subset of constant
    and friction, and both with one extra term).
    """
    jc, jf = library.index(_CONSTANT), library.index(_FRICTION)
    cands = {c for c in sweep if len(c) <= max_terms
             and len(set(c) - {jc, jf}) <= _MAX_DISTRACTORS}
    cands |= {(), (jc,), (jf,), tuple(sorted((jc, jf)))}
    if max_terms >= 3:
        for j in range(len(library)):
            if j not in (jc, jf):
                cands.add(tuple(sorted((jc, jf, j))))
    return sorted(cands, key=lambda c: (len(c), c))


def _select(Theta, Y, scales, cands, threshold, window, floor: float = 0.0,
            friction: int | None = None):
    """Refit every candidate by least squares and pick one by AICc.

    The sparsest within ``window`` of the best AICc among the candidates whose
    every term contributes >= ``threshold``. With a ``floor`` (m/s, the jumps'
    precision) the criterion takes the residual variance as known, the largest
    candidate's or ``floor**2`` whichever is larger (Mallows' Cp, small-sample
    corrected): a term must explain more than the pulse areas' systematic errors.

    Returns (coefficients over the library, index of the chosen candidate).
    """
    n, J = Theta.shape
    s2 = 0.0
    if floor > 0:
        big = max(cands, key=len)
        if big and n - len(big) > 0:
            c = np.linalg.lstsq(Theta[:, list(big)], Y, rcond=None)[0]
            s2 = float(np.sum((Y - Theta[:, list(big)] @ c) ** 2)) / (n - len(big))
        s2 = max(s2, floor ** 2)
    best = []
    for ci, c in enumerate(cands):
        k = len(c)
        if n - k - 2 <= 0:
            continue
        coef = np.zeros(J)
        if k:
            coef[list(c)] = np.linalg.lstsq(Theta[:, list(c)], Y, rcond=None)[0]
            if np.any(np.abs(coef[list(c)]) * scales[list(c)] < threshold):
                continue                      # a negligible term: the sparser form covers it
            if friction is not None and coef[friction] > 0:
                continue                      # mu < 0: inadmissible (the fit is constrained)
        rss = float(np.sum((Y - Theta @ coef) ** 2))
        score = (rss / s2 + 2 * k + 2 * k * (k + 1) / (n - k - 1)) if s2 > 0 else aicc(rss, n, k)
        best.append((score, k, ci, coef))
    low = min(b[0] for b in best)
    ok = [b for b in best if b[0] <= low + window]
    _, _, ci, coef = min(ok, key=lambda b: (b[1], b[0]))
    return coef, ci


def _fixed_point(tents, jc, jf, start, max_iter):
    """Iterate reconstruct -> least squares on (constant, friction) from ``start``.

    Returns ``(mu, theta_deg, rss, iterations)``; ``rss`` is the self-consistent
    misfit: the rows rebuilt with the final law, predicted by that same law.
    """
    mu, theta = start
    k = 0
    while k < max_iter:
        k += 1
        Theta, Y, _, _ = tents.assemble(max(mu, 0.0), theta)
        c = np.linalg.lstsq(Theta[:, [jc, jf]], Y, rcond=None)[0]
        new = _mu_theta((_CONSTANT, _FRICTION), c)
        done = abs(new[0] - mu) < _TOL_MU and abs(new[1] - theta) < _TOL_THETA
        mu, theta = new
        if done:
            break
    Theta, Y, _, _ = tents.assemble(max(mu, 0.0), theta)
    tied = np.array([G_ACCEL * math.sin(math.radians(theta)), -max(mu, 0.0) * G_ACCEL])
    rss = max(float(np.sum((Y - Theta[:, [jc, jf]] @ tied) ** 2)), 1e-300)
    return mu, theta, rss, k + 1


def _ols_variances(X: np.ndarray, Y: np.ndarray, floor: float):
    """(coefficients, their variances) of the least-squares fit ``Y ~ X``, or None.

    The residual scale is the fit's own or ``floor``, whichever is larger; None when
    the fit has no residual degree of freedom or ``X`` is singular.
    """
    n, k = X.shape
    if n <= k:
        return None
    coef = np.linalg.lstsq(X, Y, rcond=None)[0]
    s2 = max(float(np.sum((Y - X @ coef) ** 2)) / (n - k), floor ** 2)
    try:
        return coef, s2 * np.diag(np.linalg.inv(X.T @ X))
    except np.linalg.LinAlgError:
        return None


def _theta_se(const: float, se_c: float) -> float:
    """Standard error (deg) of theta from its constant's coefficient and standard error.

    The constant is ``g sin(theta)``: its error divided by ``g cos(theta)``.
    """
    s = float(np.clip(const / G_ACCEL, -0.99, 0.99))
    return float(np.degrees(se_c / G_ACCEL / math.sqrt(1 - s * s)))


def _standard_errors(X: np.ndarray, Y: np.ndarray, floor: float) -> tuple[float, float]:
    """Standard errors of mu and theta (deg) of the (constant, friction) fit ``X``.

    The residual scale is the fit's own or ``floor`` (the jumps' precision, m/s),
    whichever is larger: systematic errors of the pulse areas do not average out.
    """
    fit = _ols_variances(X, Y, floor)
    if fit is None:
        return math.inf, math.inf
    coef, var = fit
    se_c, se_f = np.sqrt(np.clip(var, 0.0, None))
    return float(se_f / G_ACCEL), _theta_se(coef[0], se_c)


def _support_errors(Theta: np.ndarray, Y: np.ndarray, support: Sequence[int], jc: int,
                    jf: int, floor: float) -> tuple[float, float]:
    """Standard errors of mu and theta (deg) in the law as selected (``support``).

    A kept distractor (``z'``, ...) is nearly collinear with ``sgn(z')`` over a flight's
    speeds: friction's coefficient is then far less certain than in the (constant,
    friction) fit. Zeros for a parameter not in the support (its se is the (constant,
    friction) fit's, :func:`_standard_errors`).
    """
    support = list(support)
    if not set(support) - {jc, jf} or not {jc, jf} & set(support):
        return 0.0, 0.0
    fit = _ols_variances(Theta[:, support], Y, floor)
    if fit is None:
        return math.inf, math.inf
    coef, var = fit
    se = dict(zip(support, np.sqrt(np.clip(var, 0.0, None)), strict=True))
    mu_se = float(se[jf] / G_ACCEL) if jf in se else 0.0
    theta_se = _theta_se(coef[support.index(jc)], se[jc]) if jc in se else 0.0
    return mu_se, theta_se


def _wall_scale_test(X: np.ndarray, Y: np.ndarray, scale_cols: np.ndarray, floor: float,
                     cx: np.ndarray | None = None) -> tuple[float, float, float]:
    """How the (constant, friction) fit moves when each wall's pulse areas get a scale.

    ``cx``: the least-squares fit of ``X`` alone (the tied fit), when the caller has
    it. ``scale_cols`` are the jumps per wall (:meth:`_Tents.wall_jumps`): the fit with
    them free is the law that holds whatever scale error a wall's pulse areas carry
    (the filter, that wall's contact duration). Without such an error both fits
    estimate the same law and their difference is noise of covariance (free fit's
    less tied fit's): its Hausman statistic is chi2 with 2 degrees of freedom.

    Returns
    -------
    (statistic, |mu shift|, |theta shift| in deg); zeros when not computable.
    """
    n, k = X.shape
    Z = np.hstack([X, scale_cols])
    if n <= Z.shape[1] + 1:
        return 0.0, 0.0, 0.0
    cz = np.linalg.lstsq(Z, Y, rcond=None)[0]
    if cx is None:
        cx = np.linalg.lstsq(X, Y, rcond=None)[0]
    s2 = max(float(np.sum((Y - Z @ cz) ** 2)) / (n - Z.shape[1]), floor ** 2)
    try:
        Vz = s2 * np.linalg.inv(Z.T @ Z)[:k, :k]
        Vx = s2 * np.linalg.inv(X.T @ X)
    except np.linalg.LinAlgError:
        return 0.0, 0.0, 0.0
    d = cz[:k] - cx
    free, tied = (_mu_theta((_CONSTANT, _FRICTION), c) for c in (cz[:k], cx))
    w, U = np.linalg.eigh(Vz - Vx)
    keep = w > max(float(w.max()), 0.0) * 1e-9
    if not keep.any():
        return 0.0, 0.0, 0.0
    proj = U[:, keep].T @ d
    return (float(np.sum(proj ** 2 / w[keep])), abs(free[0] - tied[0]),
            abs(free[1] - tied[1]))


def _jackknife(X: np.ndarray, Y: np.ndarray, groups: np.ndarray, min_rows: int = 3) -> dict:
    """How the (constant, friction) fit moves when one group of tents is left out.

    For every group ``g`` with at least ``min_rows`` tents, the fit of the other tents;
    nothing (zeros) with fewer than 3 such groups: with 2 recordings the one left is often
    confounded alone (a periodic orbit) and its fit moves by its own imprecision (exact
    engine, mu 0.1 / theta 1 deg at 6 and 9 mm: 0.26 deg).
    ``se``: the jackknife standard errors of mu and theta (deg),
    ``sqrt((G - 1) / G sum (p_(g) - mean)^2)``, which include whatever makes the
    groups disagree (a model-form error that differs between walls or recordings), not
    only the rows' scatter.
    """
    k = X.shape[1]
    labels = [g for g in np.unique(groups) if (groups == g).sum() >= min_rows]
    out = {"G": len(labels), "mu_se": 0.0, "theta_se": 0.0}
    if len(labels) < 3:
        return out      # one recording left alone is often confounded (periodic orbit)
    try:                # (a design singular as a whole tells no spread)
        np.linalg.inv(X.T @ X)
    except np.linalg.LinAlgError:
        return out
    subs = []
    for g in labels:
        keep = groups != g
        if keep.sum() <= k + 1:
            continue
        cg = np.linalg.lstsq(X[keep], Y[keep], rcond=None)[0]
        subs.append(np.array(_mu_theta((_CONSTANT, _FRICTION), cg)))
    if len(subs) >= 2:
        P = np.array(subs)
        G = len(subs)
        se = np.sqrt((G - 1) / G * np.sum((P - P.mean(axis=0)) ** 2, axis=0))
        out["mu_se"], out["theta_se"] = float(se[0]), float(se[1])
    return out


def _compliant(records) -> bool:
    """Whether any learned contact of ``records`` has a duration (a compliant wall)."""
    return any(np.any(np.nan_to_num(rec.centroid) > 0) for rec in records)


def _geometry_shift(records, library, law, jc, jf, max_iter, scale: float | None = None,
                    gain_sd: float = 0.0, gain_per: str = "wall", depth_free: bool = False,
                    prior=None):
    """How the (constant, friction) fixed point moves with the learned contact durations.

    ``records`` (the analysed contact entries) with every impact moved to the equivalent
    instantaneous impact of its contact (:meth:`FlightData.equivalent_impacts`) with the
    learned contact durations times ``scale``; the fixed point is started from ``law``
    (mu, theta, fitted at the durations as learned). Returns ``(d mu, d theta deg)``, or
    None when no contact has a duration (instantaneous impacts: nothing moves).
    ``prior``: the measurement of mu the law was fitted with (:meth:`_Tents.set_prior`).
    """
    if not _compliant(records):
        return None
    scale = _TAU_SCALE if scale is None else scale
    moved = _Tents([rec.equivalent_impacts(scale) for rec in records], library,
                   gain_sd=gain_sd, gain_per=gain_per, depth_free=depth_free)
    if moved.n < len(library) + 5:
        return None
    if prior is not None:
        moved.set_prior(prior.mu, prior.mu_se)
    mu, theta, _, _ = _fixed_point(moved, jc, jf, law, max_iter)
    return mu - law[0], theta - law[1]


def _confounded(tents, points, jc, jf, floor: float, window: float) -> bool:
    """Whether the flights alone leave mu and theta confounded at their best fixed point.

    Collinear (constant, friction) columns, a standard error of mu above
    :data:`MAX_MU_SE`, or rival fixed points that close the tents about as well: the
    refusals the LO's friction can lift.
    """
    best = min(points, key=lambda p: p[2])
    Theta, Y, _, _ = tents.assemble(max(best[0], 0.0), best[1])
    mu_se = _standard_errors(Theta[:, [jc, jf]], Y, floor)[0]
    return (_cosine(Theta[:, jc], Theta[:, jf]) > _COLLINEAR or mu_se > MAX_MU_SE
            or bool(_rivals(points, best, tents.n, window)))


def _cosine(a: np.ndarray, b: np.ndarray) -> float:
    """|cos| of the angle between two columns (1: collinear)."""
    return float(abs(a @ b) / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-300))


def _rivals(points, best, n: int, window: float) -> list:
    """Fixed points that close the ``n`` tents about as well as ``best``, elsewhere.

    Within ``window`` of its AICc, beyond :data:`_AMBIGUOUS` from it in mu or theta.
    """
    return [p for p in points if n * math.log(p[2] / best[2]) <= window
            and (abs(p[0] - best[0]) > _AMBIGUOUS[0] or abs(p[1] - best[1]) > _AMBIGUOUS[1])]


def _negative_friction(mu_free: float, mu_se: float) -> bool:
    """Whether the free fit's ``mu_free`` lies below 0 beyond its precision.

    More than twice its standard error and more than :data:`_MU_NEGLIGIBLE` below
    zero: exact jumps make the standard error ~0, and a fit a hair below 0 is then
    mu = 0, not a refusal.

    Examples
    --------
    >>> _negative_friction(-5e-5, 0.0), _negative_friction(-0.02, 0.001)
    (False, True)
    """
    return mu_free < -max(2.0 * mu_se, _MU_NEGLIGIBLE)


def _mu_theta(names, coef):
    d = dict(zip(names, coef, strict=True))
    mu = -d.get(_FRICTION, 0.0) / G_ACCEL
    s = np.clip(d.get(_CONSTANT, 0.0) / G_ACCEL, -1.0, 1.0)
    return float(mu), float(np.degrees(np.arcsin(s)))


def discover_flight_law(analyses: Sequence, *, seed: int = 0, n_boot: int = 200,
                        library: Sequence[str] = DEFAULT_LIBRARY, threshold: float = 0.06,
                        window: float = 4.0, max_terms: int = 3, level: float = 0.95,
                        max_iter: int = _MAX_ITER,
                        max_tilt_deg: float = MAX_TILT_DEG,
                        jump_gain_sd: float | None = None,
                        jump_gain_per: str = "wall",
                        penetration: str | None = None,
                        lo_friction: bool | LoReaction = True) -> FlightLawResult:
    """Identify the ball's law between impacts from analysed recordings.

    Parameters
    ----------
    analyses : sequence of AnalysisResult or FlightData
        Results of :func:`vidiscover.analysis.analyze` (any ``mu``), one or more
        recordings of the same rig (their tents are pooled); or their
        :class:`~vidiscover.analysis.flights.FlightData` (e.g. with other impacts,
        :meth:`~vidiscover.analysis.flights.FlightData.with_impacts`).
    seed : int
        Seed of the bootstrap.
    n_boot : int
        Resamples of the tents for the intervals (0: no intervals).
    library : sequence of str
        Candidate terms, names of :data:`FLIGHT_TERMS`; must contain ``"1"`` and
        ``"sgn(z')"``.
    threshold : float
        Smallest RMS contribution of a kept term (m/s^2); the lower end of the
        STLSQ threshold sweep.
    window : float
        AICc window: the sparsest candidate within ``window`` of the best is taken.
    max_terms : int
        Largest number of terms of a candidate law (>= 2). Over the speeds of a
        flight the odd candidates are nearly collinear with ``sgn(z')``; dense
        supports with cancelling coefficients fit noise and are not considered.
    level : float
        Level of the bootstrap intervals.
    max_iter : int
        Largest number of reconstruction + regression passes.
    max_tilt_deg : float
        Largest admissible |theta| (deg, default 10); a larger fitted tilt makes
        the law "not identified".
    jump_gain_sd : float, optional
        Spread (relative sd) of a gain of the pulse areas of its own per recording and
        wall, taken out of the rows (:meth:`_Tents.basis`): 0 takes the areas as they
        are (the default, :data:`_GAIN_SD`), ``math.inf`` frees every gain (the law then
        holds whatever they are), a value between weights the rows as if each gain were
        drawn with that spread; the standard errors include the gains' uncertainty.
    jump_gain_per : {"wall", "recording"}
        One gain per recording and wall, or one per recording shared by its two walls
        (3 columns for 3 recordings instead of 6: theta's standard error barely grows;
        free, it identified test-054 at mu 0.179 for 0.183 and lost test-020).
    penetration : {"free", "learned"}, optional
        How far beyond the walls the equivalent impacts lie: "learned" (the default,
        :data:`_PENETRATION`) takes the learned force centroids' depths as they are,
        "free" takes one error of the learned penetration times per recording out of the
        rows (:meth:`_Tents.depth_columns`); a research option: it has identified wrong
        laws that "learned" refuses (see :data:`_PENETRATION`).
    lo_friction : bool or LoReaction
        Use the friction read from the LO's acceleration
        (:func:`~vidiscover.analysis.lo_reaction.lo_reaction`), when it is identified,
        as one more measurement of mu (a row of the regression weighted by its standard
        error, :meth:`_Tents.set_prior`): it separates friction from the inclination
        where the flights confound them. Default True; it is reported either way. A
        :class:`~vidiscover.analysis.lo_reaction.LoReaction` is used as given (e.g.
        with FlightData, which carry no recording to read it from).

    Returns
    -------
    FlightLawResult
        ``identified`` False, with a one-line ``reason`` and no numbers as results,
        when the weak form misfits (> max(1 %, min(precision, 2 %)) of the jumps), friction and
        inclination are confounded (collinear columns, or rival fixed points that
        close the tents about as well), or the fit is inadmissible (the free fit's mu more than two
        standard errors below 0, |theta| > ``max_tilt_deg``); the selection itself
        is constrained to mu >= 0.

    Raises
    ------
    InputError
        On an empty input, an unknown term, or too few usable flights.

    Notes
    -----
    Validated (``tests/test_flight_law.py``, ``benchmarks/bench_flight_law.py``) on
    simulated recordings with constant r = 0.88 and the three clearances 6, 7.5 and
    9 mm pooled. One recording alone is often confounded (periodic orbit: not
    identified) or, at b = 7.5 mm, biased without a warning; walls on which the
    ball chatters with undetectable re-impacts break the weak form (not identified).
    """
    if isinstance(analyses, (str, bytes)) or not isinstance(analyses, Sequence):
        analyses = [analyses]
    if len(analyses) == 0:
        raise InputError("discover_flight_law needs at least one AnalysisResult, got none")
    library = tuple(library)
    unknown = [nm for nm in library if nm not in FLIGHT_TERMS]
    if unknown:
        raise InputError(f"unknown flight-law term(s) {unknown}; choose from "
                         f"{sorted(FLIGHT_TERMS)}")
    for need in (_CONSTANT, _FRICTION):
        if need not in library:
            raise InputError(f"library must contain {need!r} (inclination / friction), "
                             f"was {list(library)}")
    if len(set(library)) != len(library):
        raise InputError(f"library has repeated terms: {list(library)}")
    if not (isinstance(n_boot, int) and n_boot >= 0):
        raise InputError(f"n_boot must be an integer >= 0, was {n_boot!r}")
    if not (math.isfinite(threshold) and threshold > 0):
        raise InputError(f"threshold must be > 0 m/s^2, was {threshold!r}")
    if not (isinstance(max_terms, int) and max_terms >= 2):
        raise InputError(f"max_terms must be an integer >= 2, was {max_terms!r}")
    if not (math.isfinite(window) and window >= 0):
        raise InputError(f"window must be >= 0 (AICc units), was {window!r}")
    if not (0 < level < 1):
        raise InputError(f"level must be in (0, 1), was {level!r}")
    if not (isinstance(max_iter, int) and max_iter >= 1):
        raise InputError(f"max_iter must be an integer >= 1, was {max_iter!r}")
    if not (isinstance(max_tilt_deg, (int, float)) and 0 < max_tilt_deg < 90):
        raise InputError(f"max_tilt_deg must be in (0, 90) degrees, was {max_tilt_deg!r}")
    gain_sd = _GAIN_SD if jump_gain_sd is None else jump_gain_sd
    if not (isinstance(gain_sd, (int, float)) and gain_sd >= 0 and not math.isnan(gain_sd)):
        raise InputError(f"jump_gain_sd must be >= 0 (relative; 0: none, inf: free), was "
                         f"{jump_gain_sd!r}")
    if jump_gain_per not in ("wall", "recording"):
        raise InputError(f"jump_gain_per must be 'wall' or 'recording', was "
                         f"{jump_gain_per!r}")
    penetration = _PENETRATION if penetration is None else penetration
    if penetration not in ("free", "learned"):
        raise InputError(f"penetration must be 'free' or 'learned', was {penetration!r}")
    depth_free = penetration == "free"
    entries = [a if isinstance(a, FlightData) else FlightData.of(a) for a in analyses]
    if isinstance(lo_friction, LoReaction):
        lo = lo_friction
    elif not any(isinstance(a, FlightData) for a in analyses):
        lo = pooled_lo_reaction([lo_reaction_of(a) for a in analyses])
    else:
        lo = None
    # compliant contacts: the tents between the equivalent instantaneous impacts
    records = ([rec.equivalent_impacts() for rec in entries] if _compliant(entries)
               else entries)
    tents = _Tents(records, library, gain_sd=gain_sd, gain_per=jump_gain_per,
                   depth_free=depth_free)
    if tents.n < len(library) + 5:
        taken = (f"; {tents.n_rows - tents.n} go to the free gains and penetration depths"
                 if tents.transformed else "")
        raise InputError(f"only {tents.n_rows} usable impacts (tents{taken}) for "
                         f"{len(library)} candidate terms; analyse longer or more recordings")

    jc, jf = library.index(_CONSTANT), library.index(_FRICTION)
    # the LO's mu may join the fit only where the leave-one-recording-out check can see
    # a bias the flights' confound hid: 3 recordings or more (the exact engine's 7.5 mm
    # alone gives theta 1.5 deg off with the LO's mu, within its standard errors)
    _, counts = np.unique(tents.rows[:, 0], return_counts=True)
    candidate = (lo if lo_friction and lo is not None and lo.identified
                 and not tents.transformed and int(np.sum(counts >= 3)) >= 3 else None)
    prior = None
    nt = tents.n                                  # the tents' rows (the prior's follow)
    jrms = float(np.sqrt(np.mean(tents.jumps() ** 2)))
    precision = tents.precision()
    floor = precision * jrms
    # 1. the reconstruction-compatible law (constant + friction) to a fixed point,
    #    from several starts; the best self-consistent fit wins, rivals are reported
    points = [_fixed_point(tents, jc, jf, st, max_iter) for st in _STARTS]
    if candidate is not None and _confounded(tents, points, jc, jf, floor, window):
        # ... and only where the flights alone confound mu and theta: where they determine
        # mu, their law stands as it is (the LO's reading can be off: 0.258 +/- 0.006 for
        # 0.3 on the exact engine at mu 0.3, 0.240 +/- 0.003 for 0.272 on holdout16-056)
        prior = candidate
        tents.set_prior(prior.mu, prior.mu_se)
        points = [_fixed_point(tents, jc, jf, st, max_iter) for st in _STARTS]
    it = sum(p[3] for p in points)
    n = tents.n
    best = min(points, key=lambda p: p[2])
    mu, theta = best[0], best[1]
    rivals = _rivals(points, best, n, window)
    # 2. sparse regression over the library at that z'; reconstruct again if the
    #    selected law changes mu or theta
    prev = None
    for _ in range(max_iter):
        at = (max(mu, 0.0), theta)
        Theta, Y, scales, _ = tents.assemble(*at)
        cands = _candidates(library, _sweep_supports(Theta, Y, scales, threshold),
                            max_terms)
        coef, ci = _select(Theta, Y, scales, cands, threshold, window, floor,
                           jf if _CONSTRAINED else None)
        new = _mu_theta(library, coef)
        it += 1
        if (prev == cands[ci] and abs(new[0] - mu) < _TOL_MU
                and abs(new[1] - theta) < _TOL_THETA):
            break
        prev = cands[ci]
        mu, theta = new
    mu, theta = new
    resid = Y - Theta @ coef
    kept = [nm for nm, c in zip(library, coef, strict=True) if c != 0]
    kc = [float(c) for c in coef if c != 0]
    mu = mu if _FRICTION in kept else 0.0
    theta = theta if _CONSTANT in kept else 0.0

    mu_ci = theta_ci = (math.nan, math.nan)
    incl = {}
    if n_boot > 0:
        # the tents resampled; the prior's row kept in every resample, its measurement
        # drawn from its own normal distribution (a parametric bootstrap of mu_LO)
        draws = (np.random.default_rng([seed, 1]).standard_normal(n_boot)
                 if prior is not None else np.zeros(n_boot))
        boots = []
        for i, z in zip(bootstrap_rows(nt, n_boot, seed), draws, strict=True):
            idx = np.concatenate([i, np.arange(nt, nt + tents.n_prior)])
            Yb = Y[idx].copy()
            if prior is not None:
                Yb[-1] -= tents.prior[0] * prior.mu_se * G_ACCEL * z
            boots.append(_select(Theta[idx], Yb, scales, cands, threshold, window, floor,
                                 jf if _CONSTRAINED else None)[0])
        boots = np.array(boots)
        mus = -boots[:, jf] / G_ACCEL
        ths = np.degrees(np.arcsin(np.clip(boots[:, jc] / G_ACCEL, -1, 1)))
        mu_ci = tuple(float(v) for v in percentile_interval(mus, level))
        theta_ci = tuple(float(v) for v in percentile_interval(ths, level))
        incl = inclusion(boots, library)
    cos = _cosine(Theta[:nt, jc], Theta[:nt, jf])
    misfit = float(np.sqrt(np.mean(resid[:nt] ** 2)) / jrms)
    mu_se, theta_se = _standard_errors(Theta[:, [jc, jf]], Y, floor)
    if _SUPPORT_SE:
        sup = _support_errors(Theta, Y, np.flatnonzero(coef), jc, jf, floor)
        mu_se, theta_se = max(mu_se, sup[0]), max(theta_se, sup[1])
    # the law left one recording out at a time: its spread is what the rows' own
    # scatter does not show (a model-form error of each recording's own)
    jk = (_jackknife(Theta[:, [jc, jf]], Y, tents.groups())
          if _JACKKNIFE and not tents.transformed else None)
    if rivals and math.isfinite(mu_ci[0]):
        mus_all = [mu_ci[0], mu_ci[1]] + [max(p[0], 0.0) for p in rivals]
        ths_all = [theta_ci[0], theta_ci[1]] + [p[1] for p in rivals]
        mu_ci = (min(mus_all), max(mus_all))
        theta_ci = (min(ths_all), max(ths_all))
    equation = _equation(kept, kc)
    diagnostic = {"mu": mu, "theta_deg": theta, "terms": kept, "coefficients": kc,
                  "equation": equation, "mu_ci": mu_ci, "theta_ci": theta_ci}
    if jk is not None:
        diagnostic["jackknife"] = jk
    reasons = []
    if misfit > max(_MAX_MISFIT, min(precision, _MAX_MISFIT_EXCUSED)):
        reasons.append(f"the weak form does not hold: the fit misses the tents by "
                       f"{misfit:.1%} of the ball velocity jumps (their precision here: "
                       f"{precision:.1%}; unseen re-impacts in wall chatter, the ball riding "
                       "a wall, missed or double-counted impacts)")
    if mu_se > MAX_MU_SE:
        reasons.append(f"these flights do not determine the friction (standard error of mu "
                       f"{mu_se:.2g} > {MAX_MU_SE:g}; e.g. flights of equal duration, whose "
                       "friction integrals cancel); pool recordings at several clearances")
    if theta_se > MAX_THETA_SE:
        reasons.append(f"these flights do not determine the inclination (standard error "
                       f"{theta_se:.2g} deg > {MAX_THETA_SE:g} deg); pool recordings at "
                       "several clearances")
    if jk is not None and (jk["theta_se"] > MAX_THETA_SE
                           or (_FRICTION in kept and jk["mu_se"] > _JACKKNIFE_MU * MAX_MU_SE)):
        reasons.append(f"the law moves between recordings: fitted with one recording left "
                       f"out at a time it spreads by {jk['mu_se']:.2g} in mu and "
                       f"{jk['theta_se']:.2g} deg in theta (jackknife standard errors; its own "
                       f"{mu_se:.2g} and {theta_se:.2g} deg): the recordings carry a model-form "
                       "error of their own (e.g. walls of unequal stiffness) that the fit's "
                       "precision does not cover")
    lifted = prior is not None and jk is not None     # (the prior implies 3 groups)
    if cos > _COLLINEAR and not lifted:
        reasons.append(f"friction and inclination are confounded in these flights (cosine "
                       f"{cos:.4f} between their columns); pool recordings at several "
                       "clearances")
    if prior is not None:
        # the LO's mu against the flights': a residual of the prior's row beyond 3 of its
        # standard errors means the two measurements disagree (a model-form error)
        mu_fit = -float(coef[jf]) / G_ACCEL
        z = (mu_fit - prior.mu) / prior.mu_se
        diagnostic["lo_prior"] = {"mu": prior.mu, "mu_se": prior.mu_se, "z": z}
        if abs(z) > 3.0:
            reasons.append(f"the flights and the LO's reaction disagree on the friction: "
                           f"mu {mu_fit:.3g} against {prior.mu:.3g} +/- {prior.mu_se:.2g} "
                           f"({z:+.1f} standard errors)")
    if cos > _COLLINEAR and kept and not lifted:
        # the combination the flights determine: the (constant, friction) fixed point,
        # not a sparse form (one nearly collinear column stands in for both within the
        # precision, but not as well); nothing when no term explains the tents
        fm, ft = best[0], best[1]
        names = [_CONSTANT, _FRICTION]
        coefs = [G_ACCEL * math.sin(math.radians(ft)), -fm * G_ACCEL]
        diagnostic.update(mu=fm, theta_deg=ft, terms=names, coefficients=coefs,
                          equation=_equation(names, coefs))
    if rivals:
        alt = ", ".join(f"(mu={p[0]:.3f}, theta={p[1]:.2f} deg)" for p in rivals)
        reasons.append(f"friction and inclination are confounded: the reconstruction also "
                       f"closes with {alt} about as well; pool recordings at several "
                       "clearances")
    # the (constant, friction) least squares, mu not constrained
    unconstrained = np.linalg.lstsq(Theta[:, [jc, jf]], Y, rcond=None)[0]
    notes = []
    hausman = dmu = dth = 0.0
    if tents.gain_sd > 0:
        # the pulse areas' gains (per recording and wall) of the law: what they take out
        Traw, Yraw = tents.assemble_raw(*at)
        gains = tents.gains(Yraw - Traw @ coef)
        diagnostic["jump_gains"] = [float(g) for g in gains]
        if gains.size and float(np.max(np.abs(gains))) > _MAX_GAIN:
            reasons.append(f"the pulse areas of one recording at one wall would be "
                           f"{float(gains[np.argmax(np.abs(gains))]):+.1%} off for the law "
                           f"to hold (more than {_MAX_GAIN:.0%}: missed or split impacts, "
                           "not a pulse-area error)")
    else:
        wj = tents.basis() @ tents.wall_jumps() if tents.transformed else tents.wall_jumps()
        wj = np.vstack([wj, np.zeros((tents.n_prior, wj.shape[1]))])
        hausman, dmu, dth = _wall_scale_test(Theta[:, [jc, jf]], Y, wj,
                                             floor, cx=unconstrained)
    if hausman > _HAUSMAN and (dmu > MAX_MU_SE or dth > MAX_THETA_SE):
        # a significant move of mu itself refuses the law (test-054: 0.034, the law's own
        # error, 0.147 for 0.183); a move of theta alone is a warning (test-020: 0.43 deg
        # with the law right at 0.00)
        (reasons if _SCALE_TEST or dmu > MAX_MU_SE else notes).append(
            f"the pulse areas of the walls disagree in scale: with one free scale per wall "
            f"the fit moves by {dmu:.2g} in mu and {dth:.2g} deg in theta (significant: "
            f"chi2 {hausman:.3g} > {_HAUSMAN:g})")
    shift = _geometry_shift(entries, library, (best[0], best[1]), jc, jf, max_iter,
                            gain_sd=gain_sd, gain_per=jump_gain_per, depth_free=depth_free,
                            prior=prior)
    # the placement's own uncertainty joins the fit's: the law is identified when the
    # total standard errors are within MAX_MU_SE / MAX_THETA_SE (:data:`_PLACEMENT_SHARE`);
    # with the depths free the move itself is bounded, as before (the fold identified the
    # unit test's instantaneous impacts told of 1 ms contacts at mu 0.132 for 0.1)
    fit_se = (mu_se, theta_se)
    if shift is not None:
        share = 1.0 if depth_free else _PLACEMENT_SHARE
        place = (share * abs(shift[0]), share * abs(shift[1]))
        total = ((max(mu_se, place[0]), max(theta_se, place[1])) if depth_free
                 else (math.hypot(mu_se, place[0]), math.hypot(theta_se, place[1])))
        diagnostic["placement"] = {"mu": float(shift[0]), "theta_deg": float(shift[1]),
                                   "mu_se": place[0], "theta_se": place[1]}
        # refused here where the fit's own errors pass (else said above)
        if ((place[0] > MAX_MU_SE or total[0] > MAX_MU_SE >= mu_se)
                or (place[1] > MAX_THETA_SE or total[1] > MAX_THETA_SE >= theta_se)):
            taus = sorted({round(float(t) * 1e6) for rec in entries
                           for t in np.unique(rec.tau)})
            reasons.append(
                f"the law depends on where in the contact the impact is placed: with the "
                f"learned contact durations ({'/'.join(map(str, taus))} us) "
                f"{1 - _TAU_SCALE:.0%} shorter it moves by {shift[0]:+.2g} in mu and "
                f"{shift[1]:+.2g} deg in theta, standard errors with the placement "
                f"{total[0]:.2g} and {total[1]:.2g} deg > {MAX_MU_SE:g} or {MAX_THETA_SE:g} "
                "deg (compliant walls; the analysis does not place the impacts that "
                "precisely)")
        if not depth_free:
            mu_se, theta_se = total
    mu_free = _mu_theta((_CONSTANT, _FRICTION), unconstrained)[0]
    # the fit's own error: the placement moves mu one way (shorter contacts, less
    # friction), it does not excuse a fit below zero
    if _CONSTRAINED and _negative_friction(mu_free, fit_se[0]):
        reasons.append(f"the fit wants a negative friction, mu = {mu_free:.3g} (beyond twice "
                       f"its standard error {fit_se[0]:.2g}): mu >= 0 does not close the "
                       "tents")
    if mu < 0:
        reasons.append(f"inadmissible friction mu = {mu:.3g} < 0 (the friction term has "
                       "the wrong sign)")
    if abs(theta) > max_tilt_deg:
        reasons.append(f"inadmissible inclination theta = {theta:.3g} deg beyond "
                       f"+/-{max_tilt_deg:g} deg (widen with max_tilt_deg / --max-tilt if "
                       "the rig is tilted that much)")
    common = dict(n_flights=tents.flights_used(), n_equations=tents.n_rows, library=library,
                  inclusion=incl, threshold=float(threshold), level=float(level),
                  iterations=it, residual_rms=float(np.sqrt(np.mean(resid ** 2))),
                  collinearity=cos, misfit=misfit, precision=precision, mu_se=mu_se,
                  theta_se=theta_se, max_tilt_deg=float(max_tilt_deg),
                  diagnostic=diagnostic, lo_friction=lo)
    if reasons:
        return FlightLawResult(mu=math.nan, theta_deg=math.nan, terms=[], coefficients=[],
                               mu_ci=(math.nan, math.nan), theta_ci=(math.nan, math.nan),
                               equation="not identified", identified=False,
                               reason=_join_reasons(reasons), warnings=tuple(reasons),
                               **common)
    return FlightLawResult(mu=mu, theta_deg=theta, terms=kept, coefficients=kc, mu_ci=mu_ci,
                           theta_ci=theta_ci, equation=equation, warnings=tuple(notes),
                           **common)
