"""Pseudo-arclength continuation of periodic impacting orbits in one parameter.

Unknowns are the orbit's section coordinates ``q`` and the parameter, scaled to
comparable sizes; each step predicts along the branch tangent and corrects with
Newton's method on the orbit equations plus the arclength condition. Along the branch:

* **fold** (saddle-node): a multiplier crosses +1, test function ``det(DP - I)``;
* **period doubling**: a multiplier crosses -1, ``det(DP + I)``;
* **Neimark-Sacker**: a complex pair crosses the unit circle, ``|mu| - 1`` of the pair;
* **grazing**: an interior extremum of z reaches a wall (the impact sequence changes)
  or an impact speed goes to zero; the branch of this sequence ends there.

Fold, period doubling and Neimark-Sacker are located by regula falsi on the
arclength between the two points that bracket a sign change; the grazing point is
approached by step halving until the step is below ``ds_min``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..effects import Effects
from ..errors import InputError
from ..params import SystemParams
from .shooting import SIDE_NAME, ImpactMap, MapError, Orbit, orbit_kind, solve_orbit

__all__ = ["CONTINUATION_PARAMS", "with_value", "param_value", "Branch", "BranchPoint",
           "Bifurcation", "continue_orbit"]

_FIELDS = ("b", "amplitude", "frequency", "r", "c1", "k1", "m1", "m2")
#: Parameters that can be continued: rig fields and effect parameters.
CONTINUATION_PARAMS = _FIELDS + ("mu", "theta", "r_left", "r_right")


def param_value(params: SystemParams, effects: Effects, name: str) -> float:
    """Current value of continuation parameter ``name``."""
    if name in _FIELDS:
        return float(getattr(params, name))
    if name == "mu":
        return effects.mu
    if name == "theta":
        return effects.theta_deg
    if name in ("r_left", "r_right"):
        return float(effects.value("asymmetric_restitution", name, params.r))
    raise InputError(f"cannot continue in {name!r}; choose one of "
                     f"{', '.join(CONTINUATION_PARAMS)}")


def with_value(params: SystemParams, effects: Effects, name: str, value: float):
    """``(params, effects)`` with continuation parameter ``name`` set to ``value``."""
    if name in _FIELDS:
        return params.replace(**{name: float(value)}), effects
    if name == "mu":
        return params, effects.with_effect("coulomb_friction", mu=float(value))
    if name == "theta":
        return params, effects.with_effect("inclination", theta=float(value))
    if name in ("r_left", "r_right"):
        if "velocity_dependent_restitution" in effects:
            raise InputError(f"cannot continue in {name} with velocity_dependent_restitution "
                             "switched on (it overrides the wall coefficients)")
        cur = {"r_right": param_value(params, effects, "r_right"),
               "r_left": param_value(params, effects, "r_left")}
        cur[name] = float(value)
        return params, effects.with_effect("asymmetric_restitution", **cur)
    raise InputError(f"cannot continue in {name!r}; choose one of "
                     f"{', '.join(CONTINUATION_PARAMS)}")


@dataclass
class BranchPoint:
    """One orbit on a branch.

    ``kind`` is its regime label; it may change along a branch, e.g. ``2ipc_asym`` ->
    ``2ipc_sym`` as the asymmetry vanishes near a symmetry-breaking point.
    """

    value: float
    q: np.ndarray
    multipliers: np.ndarray
    margin: float
    min_speed: float
    dt_T: tuple = ()  # noqa: N815 - the sweep diagram's column name
    kind: str = ""

    @property
    def max_multiplier(self) -> float:
        """Largest multiplier modulus."""
        return float(np.max(np.abs(self.multipliers)))

    @property
    def stable(self) -> bool:
        """All multipliers inside the unit circle."""
        return self.max_multiplier < 1.0

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {"value": self.value, "stable": self.stable, "kind": self.kind,
                "max_multiplier": self.max_multiplier,
                "multipliers": [{"re": float(z.real), "im": float(z.imag)}
                                for z in self.multipliers],
                "t": float(self.q[0]), "x": float(self.q[1]), "dt_T": list(self.dt_T),
                "grazing_margin": self.margin, "min_impact_speed": self.min_speed}


@dataclass
class Bifurcation:
    """A bifurcation or branch end.

    ``type`` is fold, branch_point (a multiplier at +1 without a turning point, e.g.
    symmetry breaking), period_doubling, neimark_sacker, grazing or stick.
    """

    type: str
    value: float
    q: np.ndarray
    detail: str = ""

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {"type": self.type, "value": self.value, "detail": self.detail,
                "t": float(self.q[0]), "x": float(self.q[1])}


@dataclass
class Branch:
    """A continued branch of one orbit type."""

    param: str
    kind: str
    sides: tuple
    period_cycles: int
    points: list = field(default_factory=list)
    bifurcations: list = field(default_factory=list)
    end_reason: str = ""

    def to_dict(self) -> dict:
        """JSON-ready form (keys: docs page 'Periodic orbits and continuation', JSON)."""
        return {"param": self.param, "kind": self.kind,
                "sides": [SIDE_NAME[s] for s in self.sides],
                "period_cycles": self.period_cycles,
                "points": [p.to_dict() for p in self.points],
                "bifurcations": [b.to_dict() for b in self.bifurcations],
                "end_reason": self.end_reason}

    def arrays(self) -> dict:
        """Values, stability and the first impact's LO displacement as arrays."""
        return {"value": np.array([p.value for p in self.points]),
                "stable": np.array([p.stable for p in self.points]),
                "x": np.array([p.q[1] for p in self.points]),
                "max_multiplier": np.array([p.max_multiplier for p in self.points])}


class _Problem:
    """The scaled extended system ``F(q, lambda) = 0`` of one orbit type."""

    def __init__(self, params, effects, name, sides, p, sc, lam_scale):
        self.params, self.effects, self.name = params, effects, name
        self.sides, self.p = sides, p
        self.sc, self.ls = sc, lam_scale
        self._maps: dict = {}

    def imap(self, lam: float) -> ImpactMap:
        key = float(lam)
        if key not in self._maps:
            if len(self._maps) > 64:
                self._maps.clear()
            try:
                pr, fx = with_value(self.params, self.effects, self.name, key)
            except InputError as err:
                raise MapError(f"{self.name} = {key:.6g} is outside its valid range ({err})",
                               "range") from None
            self._maps[key] = ImpactMap(pr, fx)
        return self._maps[key]

    def eval(self, u, jac=True):
        """Scaled residual (4,), its Jacobian (4, 5), the map's Jacobian, pieces."""
        q, lam = u[:4] * self.sc, u[4] * self.ls
        F, JF, J, pieces = self.imap(lam).residual(q, self.sides, self.p, jac)
        Fs = F / self.sc
        if not jac:
            return Fs, None, None, pieces
        A = np.empty((4, 5))
        A[:, :4] = JF * self.sc[None, :] / self.sc[:, None]
        A[:, 4] = self._dlam(q, u[4], F) / self.sc
        return Fs, A, J, pieces

    def _dlam(self, q, lam, F):
        """dF/d(scaled parameter) by a forward difference (backward at a range limit).

        Only the corrector and the tangent use it; bifurcations are located with the
        exact map Jacobian.
        """
        h = 1e-8
        for sign in (1.0, -1.0):
            try:
                Fh = self.imap((lam + sign * h) * self.ls).residual(
                    q, self.sides, self.p, False)[0]
            except MapError:
                continue
            return (Fh - F) / (sign * h)
        raise MapError("the orbit is not defined on either side of this parameter value",
                       "sequence")


def _null(A: np.ndarray, ref: np.ndarray | None) -> np.ndarray:
    t = np.linalg.svd(A)[2][-1]
    if ref is not None and t @ ref < 0:
        t = -t
    return t


def _tests(J: np.ndarray) -> tuple[float, float, float]:
    """(fold, period doubling, Neimark-Sacker) test functions of a map Jacobian."""
    mu = np.linalg.eigvals(J)
    fold = float(np.real(np.prod(mu - 1.0)))
    pd = float(np.real(np.prod(mu + 1.0)))
    cplx = mu[np.abs(mu.imag) > 1e-9]
    ns = float(np.max(np.abs(cplx)) - 1.0) if cplx.size else math.nan
    return fold, pd, ns


def _correct(prob: _Problem, pred, tan, maxit=12, tol=1e-11):
    u = pred.copy()
    for it in range(1, maxit + 1):
        Fs, A, J, pieces = prob.eval(u)
        G = np.append(Fs, tan @ (u - pred))
        M = np.vstack([A, tan])
        du = np.linalg.solve(M, -G)
        u = u + du
        small = np.linalg.norm(du)
        if small < tol or (small < 1e-7 and np.linalg.norm(G) < 1e-13):
            Fs, A, J, pieces = prob.eval(u)
            return u, A, J, pieces, it
    raise MapError(f"corrector did not converge in {maxit} iterations", "other")


def continue_orbit(params: SystemParams, effects: Effects | None, orbit: Orbit, param: str,
                   to: float, *, ds: float = 0.02, ds_min: float = 1e-7,
                   ds_max: float = 0.05, max_points: int = 200,
                   locate_tol: float = 1e-9, graze_tol: float = 1e-3) -> Branch:
    """Follow ``orbit`` (found at ``params``/``effects``) in ``param`` towards ``to``.

    Parameters
    ----------
    params, effects
        Where ``orbit`` was found.
    orbit : Orbit
        A found orbit (its side sequence and period fix the branch).
    param : str
        One of :data:`CONTINUATION_PARAMS`.
    to : float
        The branch is followed while the parameter stays between its start and ``to``.
    ds, ds_min, ds_max : float
        Arclength steps in scaled units (parameter relative to its start value, section
        coordinates relative to T, b and b w).
    max_points : int
        Bound on the branch points.
    locate_tol : float
        Relative tolerance of the located bifurcation parameter values.
    graze_tol : float
        The branch ends as grazing when an interior extremum of z comes within
        ``graze_tol b`` of a wall or an impact speed falls below ``10 graze_tol b w``
        (near a low-velocity grazing impact the largest multiplier grows like 1/v and
        the branch can only be approached).

    Returns
    -------
    Branch
        Points, bifurcations and the reason the continuation stopped.
    """
    effects = effects if effects is not None else Effects()
    if not orbit.found:
        raise InputError(f"cannot continue an orbit that was not found ({orbit.reason})")
    lam0 = param_value(params, effects, param)
    if lam0 == to:
        raise InputError(f"--to equals the start value {lam0!r} of {param}; give another end")
    imap0 = ImpactMap(params, effects)
    sc = imap0.scale()
    ls = abs(lam0) if lam0 != 0 else max(abs(to), 1e-3)
    prob = _Problem(params, effects, param, orbit.sides, orbit.period_cycles, sc, ls)
    branch = Branch(param, orbit.kind, orbit.sides, orbit.period_cycles)
    lo, hi = sorted((lam0, to))
    u = np.append(orbit.q / sc, lam0 / ls)
    try:
        Fs, A, J, pieces = prob.eval(u)
    except MapError as err:
        branch.end_reason = f"cannot start: {err.reason}"
        return branch
    tan = _null(A, None)
    if tan[4] * (to - lam0) < 0:
        tan = -tan

    def add(u, J, pieces):
        imap = prob.imap(u[4] * ls)
        mu = np.linalg.eigvals(J)
        mu = mu[np.argsort(-np.abs(mu), kind="stable")]
        margin, speed = imap.flight_margin(pieces)
        times = [pc.t1 for pc in pieces if pc.event in ("right", "left")]
        dts = tuple(float(d) / imap.T for d in np.diff([u[0] * sc[0], *times]))
        kind = orbit_kind(Orbit(True, "", prob.sides, prob.p, u[:4] * sc, pieces=pieces,
                                T=imap.T))
        branch.points.append(BranchPoint(float(u[4] * ls), u[:4] * sc, mu, margin, speed, dts,
                                         kind))

    add(u, J, pieces)
    tests = _tests(J)
    vscale = imap0.vscale

    def last_pt_grazes(pt):
        return pt.margin < graze_tol or pt.min_speed < 10 * graze_tol * vscale

    step = ds
    last_err = None
    crawl = 0
    while len(branch.points) < max_points:
        try:
            un, An, Jn, pn, its = _correct(prob, u + step * tan, tan)
            if np.linalg.norm(un - u) > 3 * step:
                raise MapError("the corrector jumped to another branch", "other")
        except (MapError, np.linalg.LinAlgError) as err:
            last_err = err
            step *= 0.5
            if step < ds_min:
                break
            continue
        tn = _null(An, tan)
        new_tests = _tests(Jn)
        for kind, i in (("fold", 0), ("period_doubling", 1), ("neimark_sacker", 2)):
            a, b = tests[i], new_tests[i]
            if math.isfinite(a) and math.isfinite(b) and a * b < 0:
                lam_b, q_b, detail, _ = _locate(prob, u, tan, step, i, a, b, locate_tol)
                if kind == "fold" and tan[4] * tn[4] > 0:
                    kind = "branch_point"   # multiplier +1 without a turning point
                branch.bifurcations.append(Bifurcation(kind, lam_b, q_b, detail))
        u, tan, tests = un, tn, new_tests
        add(u, Jn, pn)
        lam = u[4] * ls
        if not lo - 1e-12 <= lam <= hi + 1e-12:
            branch.end_reason = f"reached the end of the range ({param} = {lam:.6g})"
            return branch
        if last_pt_grazes(branch.points[-1]):
            break
        crawl = crawl + 1 if step < 1e-5 else 0
        if crawl >= 10:   # steps stay tiny: a singular point (grazing) is approached
            last_err = MapError(f"steps below 1e-5 (largest multiplier "
                                f"{branch.points[-1].max_multiplier:.3g})", "crawl")
            break
        if its <= 4:
            step = min(step * 1.5, ds_max)
        elif its >= 8:
            step *= 0.5
    if len(branch.points) >= max_points:
        branch.end_reason = f"stopped after {max_points} points"
        return branch
    last = branch.points[-1]
    reason = getattr(last_err, "reason", str(last_err))
    kind = getattr(last_err, "kind", "other")
    if kind == "sequence" or last_pt_grazes(last) or (kind == "crawl" and (
            last.margin < 0.05 or last.min_speed < 0.05 * vscale)):
        what = ("a low-velocity grazing impact is approached" if kind == "crawl" else
                "the impact sequence changes beyond this point")
        branch.bifurcations.append(Bifurcation(
            "grazing", last.value, last.q,
            f"{what} ({reason}); wall margin {last.margin:.2g} b, slowest impact "
            f"{last.min_speed:.3g} m/s"))
        branch.end_reason = "grazing: " + reason
    elif kind == "stick":
        branch.bifurcations.append(Bifurcation("stick", last.value, last.q, reason))
        branch.end_reason = "stick: " + reason
    else:
        branch.end_reason = f"continuation failed: {reason}"
    return branch


def _locate(prob, u0, tan, step, idx, fa, fb, tol):
    """Regula falsi (Illinois) on the arclength for a zero of test function ``idx``.

    Returns ``(value, q, detail, located)``; ``located`` is False when the corrector
    failed before the tolerance was met (at a branch point the extended system is
    singular): the value is then the midpoint of the last bracket.
    """
    a, b = 0.0, step
    sa, sb = fa, fb
    side = 0
    ub = None
    J = None
    located = False
    for _ in range(60):
        s = b - sb * (b - a) / (sb - sa)
        try:
            u, A, J, pieces, _ = _correct(prob, u0 + s * tan, tan)
        except (MapError, np.linalg.LinAlgError):
            break
        fs = _tests(J)[idx]
        if fs * sb < 0:
            a, sa = b, sb
            if side == -1:
                sb *= 0.5
            side = -1
        else:
            sa *= 0.5 if side == 1 else 1.0
            side = 1
        b, sb, ub = s, fs, u
        if abs(b - a) * abs(tan[4]) <= tol or fs == 0.0:
            located = True
            break
    if ub is None:
        ub = u0 + 0.5 * step * tan
    lam = float(ub[4] * prob.ls)
    if not located:
        mid = u0 + 0.5 * (a + b) * tan
        lam = float(mid[4] * prob.ls)
    detail = ""
    if J is not None:
        mu = np.linalg.eigvals(J)
        detail = "multipliers " + ", ".join(f"{z:.4g}" for z in mu[np.argsort(-np.abs(mu))])
    if not located:
        detail = (f"located to {abs(b - a) * abs(tan[4]) * prob.ls:.2g} only "
                  f"(singular extended system: a branch point?); " + detail)
    return lam, ub[:4] * prob.sc, detail, located


def find_and_continue(params, effects, orbit_guess, param, to, **kw) -> Branch:
    """Solve the orbit from a guess ``(q, sides, p)`` and continue it (convenience)."""
    imap = ImpactMap(params, effects)
    orb = solve_orbit(imap, *orbit_guess)
    if not orb.found:
        raise InputError(f"no orbit to continue: {orb.reason}")
    return continue_orbit(params, effects, orb, param, to, **kw)
