"""Figures of continued branches, and the overlay on the sweep's bifurcation diagram.

The sweep's diagram (:func:`vidiscover.sweep.plot_bifurcation`) shows the impact time
differences ``Delta t_i / T`` against the parameter; :func:`overlay_branches` draws
the same quantity of each continued orbit, stable solid and unstable dashed, and marks
the bifurcations.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["overlay_branches", "plot_branches", "branches_for_sweep"]

_MARKERS = {"fold": "s", "branch_point": "D", "period_doubling": "o", "neimark_sacker": "^",
            "grazing": "x", "stick": "v"}


def _as_dict(branch) -> dict:
    return branch if isinstance(branch, dict) else branch.to_dict()


def _runs(mask: np.ndarray):
    """(start, stop) index ranges of equal values in ``mask``."""
    edges = np.flatnonzero(np.diff(mask.astype(int))) + 1
    bounds = np.concatenate([[0], edges, [mask.size]])
    return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]


def overlay_branches(ax, branches, *, quantity: str = "dt_T", color=None, label: bool = True,
                     scale: float = 1.0):
    """Draw continued branches on ``ax``: stable solid, unstable dashed.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Typically the top panel of the sweep's bifurcation diagram.
    branches : list of Branch or of their ``to_dict()`` documents
    quantity : {"dt_T", "x", "max_multiplier"}
        ``dt_T``: impact time differences over T (one line per impact of the orbit,
        the sweep diagram's quantity); ``x``: LO displacement at the first impact;
        ``max_multiplier``: largest multiplier modulus.
    color : optional
        One colour for all branches (default: one per branch).
    label : bool
        Add legend entries (one per branch, and the line styles).
    scale : float
        Multiplies the parameter values (e.g. 1e3 to draw b in mm).

    Returns
    -------
    list
        The matplotlib artists drawn.
    """
    artists = []
    for i, br in enumerate(branches):
        d = _as_dict(br)
        pts = d["points"]
        if not pts:
            continue
        col = color if color is not None else f"C{(i + 4) % 10}"
        val = np.array([p["value"] for p in pts]) * scale
        stable = np.array([p["stable"] for p in pts])
        if quantity == "dt_T":
            n = min(len(p["dt_T"]) for p in pts)
            ys = [np.array([p["dt_T"][k] for p in pts]) for k in range(n)]
        elif quantity in ("x", "max_multiplier"):
            ys = [np.array([p[quantity] for p in pts])]
        else:
            raise ValueError(f"quantity must be dt_T, x or max_multiplier, was {quantity!r}")
        for k, y in enumerate(ys):
            for a, b in _runs(stable):
                sl = slice(a, min(b + 1, val.size))   # join the runs
                st = bool(stable[a])
                lab = None
                if label and k == 0 and a == 0:
                    lab = f"{d['kind']} ({'+'.join(s[0].upper() for s in d['sides'])})"
                artists += ax.plot(val[sl], y[sl], ls="-" if st else "--", color=col, lw=1.4,
                                   label=lab)
        for bif in d["bifurcations"]:
            j = int(np.argmin(np.abs(val - bif["value"] * scale)))
            mk = _MARKERS.get(bif["type"], "*")
            style = {"color": col} if mk == "x" else {"facecolors": "none", "edgecolors": col}
            for y in ys:
                artists.append(ax.scatter([bif["value"] * scale], [y[j]], s=28, marker=mk,
                                          zorder=5, **style))
    if label and artists:
        ax.plot([], [], "k-", lw=1.2, label="stable orbit")
        ax.plot([], [], "k--", lw=1.2, label="unstable orbit")
    return artists


def plot_branches(branches, path: str | Path | None = None, *, param: str = "parameter",
                  scale: float | None = None):
    """Two panels: impact time differences and the largest multiplier, against ``param``.

    ``scale`` multiplies the parameter values; by default lengths are drawn in mm
    with the unit on the axis (:func:`vidiscover.sweep.axis_scale`), as in the sweep.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from ..plotting import figure
    from ..sweep import axis_scale

    unit_scale, xlabel = axis_scale(param)
    if scale is None:
        scale = unit_scale
    elif scale != unit_scale:
        xlabel = f"{param} (x {scale:g})"
    fig, ax = figure(2, 1, sharex=True, figsize=(8, 6), height_ratios=(3, 1.6))
    top, bottom = ax[0, 0], ax[1, 0]
    overlay_branches(top, branches, scale=scale)
    top.set_ylabel(r"$\Delta t_i / T$")
    top.set_title(f"Periodic impacting orbits against {param}")
    if branches:
        top.legend(fontsize=8, loc="best")
    overlay_branches(bottom, branches, quantity="max_multiplier", label=False, scale=scale)
    bottom.axhline(1.0, color="0.5", lw=0.8)
    bottom.set_yscale("log")
    bottom.set_ylabel(r"max $|\mu|$")
    bottom.set_xlabel(xlabel)
    if path is not None:
        fig.savefig(path, dpi=130)
    return fig


def branches_for_sweep(params, effects, param: str, start: float, stop: float, *,
                       n_seeds: int = 5, max_points: int = 200) -> list:
    """Branches to overlay on a sweep from ``start`` to ``stop`` in ``param``.

    Orbits are found at ``n_seeds`` values spread over the range (simulation seeds and
    the closed-form guesses) and continued both ways to the ends; an orbit that lies on
    a branch already continued is not continued again.

    Returns
    -------
    list of Branch
    """
    from .continuation import continue_orbit, with_value
    from .find import find_orbits

    out: list = []
    for a in np.linspace(start, stop, max(n_seeds, 2)):
        pr, fx = with_value(params, effects, param, float(a))
        orbs, _ = find_orbits(pr, fx)
        for o in orbs:
            if any(_on_branch(o, br, pr, fx, float(a)) for br in out):
                continue
            halves = [continue_orbit(pr, fx, o, param, end, max_points=max_points)
                      for end in (start, stop) if end != a]
            out.append(halves[0] if len(halves) == 1 else _merge(*halves))
    return out


def _merge(back, fwd):
    """One branch from two continuations of the same orbit in opposite directions."""
    from .continuation import Branch

    return Branch(fwd.param, fwd.kind, fwd.sides, fwd.period_cycles,
                  points=back.points[::-1] + fwd.points[1:],
                  bifurcations=back.bifurcations + fwd.bifurcations,
                  end_reason=f"{back.end_reason}; {fwd.end_reason}")


def _on_branch(orbit, branch, params, effects, value) -> bool:
    """``orbit`` (found at ``value``) lies on ``branch``: re-solved there from its nearest point."""
    from .find import _same
    from .shooting import ImpactMap, solve_orbit

    if branch.period_cycles != orbit.period_cycles or len(branch.sides) != orbit.n_impacts:
        return False
    vals = np.array([p.value for p in branch.points])
    if not vals.min() - 1e-12 <= value <= vals.max() + 1e-12:
        return False
    near = branch.points[int(np.argmin(np.abs(vals - value)))]
    other = solve_orbit(ImpactMap(params, effects), near.q, branch.sides, branch.period_cycles)
    return other.found and _same(orbit, other)
