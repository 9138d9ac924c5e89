"""Figures of the ``discover`` stage (matplotlib, Agg canvas; no screen needed).

* :func:`plot_impact_laws` -- per wall, r against the impact speed, one colour per
  recording, with the discovered law, its bootstrap band and the constant-r fit;
* :func:`plot_flight_residuals` -- the weak-form momentum residual at every impact
  (:meth:`~vidiscover.discovery.pipeline.DiscoveryResult.flight_residuals`) before
  and after the discovered flight law.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plotting import figure
from .pipeline import SIDES, DiscoveryResult

__all__ = ["plot_impact_laws", "plot_flight_residuals", "write_figures"]


def plot_impact_laws(result: DiscoveryResult, path: Path | None = None, *, truth=None):
    """Plot r against impact speed per wall, with the discovered law and its band.

    Parameters
    ----------
    result : DiscoveryResult
        Output of :func:`~vidiscover.discovery.discover`.
    path : Path, optional
        Write the figure there (PNG) when given.
    truth : Mapping[str, RestitutionLaw], optional
        True law per wall (simulated data), drawn dotted.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure(1, 2, figsize=(10, 3.8))
    for ax, side in zip(axes[0], SIDES, strict=True):
        law = result.impact_laws[side]
        data = result.impact_data[side]
        for k, (_, d) in enumerate(data.groupby("group", sort=True)):
            ax.plot(d["v"], d["r"], ".", ms=3, alpha=0.6, color=f"C{k % 10}",
                    label=str(d["recording"].iloc[0]))
        if law.n and law.terms and np.all(np.isfinite(law.speed_range)):
            grid = np.linspace(*law.speed_range, 200)
            lo, mid, hi = law.band(grid)
            if np.isfinite(lo).all():
                ax.fill_between(grid, lo, hi, color="k", alpha=0.2, lw=0,
                                label=f"{100 * law.level:.0f} % band")
            ax.plot(grid, mid, "k-", lw=1.5, label=law.formula)
            if law.velocity_dependent and len(data):
                w = 1.0 / np.maximum(data["sigma"].to_numpy(), 1e-12) ** 2
                r0 = float(np.sum(w * data["r"]) / np.sum(w))
                ax.plot(grid, np.full_like(grid, r0), "k--", lw=1,
                        label=f"constant r = {r0:.3g} (dAICc {law.delta_aicc_vs_constant:.3g})")
            if truth is not None and side in truth:
                ax.plot(grid, truth[side](grid), "r:", lw=1.5,
                        label=f"truth {truth[side].formula}")
        ax.set_title(f"{side} wall (n = {law.n})")
        ax.set_xlabel("impact speed |z'-| (m/s)")
        ax.set_ylabel("restitution r")
        ax.legend(fontsize=7, loc="best")
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def plot_flight_residuals(result: DiscoveryResult, path: Path | None = None):
    """Weak-form momentum residuals at the impacts, before and after the flight law.

    Parameters
    ----------
    result : DiscoveryResult
        Output of :func:`~vidiscover.discovery.discover`.
    path : Path, optional
        Write the figure there (PNG) when given.

    Returns
    -------
    matplotlib.figure.Figure
    """
    res = result.flight_residuals()
    fig, axes = figure(1, 2, figsize=(10, 3.4))
    ax_t, ax_h = axes[0]
    before, after = res["before"].to_numpy(), res["after"].to_numpy()

    def rms(x):
        return float(np.sqrt(np.mean(x ** 2))) if x.size else float("nan")

    label_after = ("after: " + result.flight.equation
                   if result.flight is not None and result.flight.identified
                   else "after: no flight law identified")
    ax_t.plot(res["t"], before, ".", ms=3, color="0.6", label=f"before (RMS {rms(before):.3g})")
    ax_t.plot(res["t"], after, ".", ms=3, color="C0", label=f"after (RMS {rms(after):.3g})")
    ax_t.set_xlabel("impact time (s)")
    ax_t.set_ylabel("momentum residual (m/s)")
    ax_t.set_title("Ball velocity change per impact not explained by the impact\n"
                   "pulse and the flight law (0 for an exact law)", fontsize=9)
    ax_t.legend(fontsize=7)
    if before.size:
        lim = float(np.max(np.abs(np.concatenate([before, after])))) or 1.0
        bins = np.linspace(-lim, lim, 41)
        ax_h.hist(before, bins=bins, color="0.6", alpha=0.7, label="before (y'' = 0)")
        ax_h.hist(after, bins=bins, color="C0", alpha=0.7, label=label_after)
    ax_h.set_xlabel("momentum residual (m/s)")
    ax_h.set_ylabel("impacts")
    ax_h.legend(fontsize=7)
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def write_figures(result: DiscoveryResult, out_dir: Path, *, truth=None) -> list[str]:
    """Write ``impact_laws.png`` and ``flight_residuals.png`` into ``out_dir``.

    Parameters
    ----------
    result : DiscoveryResult
        Output of :func:`~vidiscover.discovery.discover`.
    out_dir : Path
        Existing directory.
    truth : Mapping[str, RestitutionLaw], optional
        True law per wall, drawn on the impact-law figure.

    Returns
    -------
    list of str
        File names written (relative to ``out_dir``).
    """
    out_dir = Path(out_dir)
    plot_impact_laws(result, out_dir / "impact_laws.png", truth=truth)
    plot_flight_residuals(result, out_dir / "flight_residuals.png")
    return ["impact_laws.png", "flight_residuals.png"]
