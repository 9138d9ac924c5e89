"""Plots of recordings (simulated or measured), with matplotlib's Agg backend."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .recording import Recording
from .truth import GroundTruth

__all__ = ["figure", "plot_recording"]


def figure(nrows: int = 1, ncols: int = 1, **kw):
    """A new figure on the non-interactive Agg canvas (safe on machines with no screen)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=kw.pop("figsize", (9, 2.6 * nrows)), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=False, **kw)
    return fig, axes


def plot_recording(rec: Recording, truth: GroundTruth | None = None, path: Path | None = None,
                   window: float = 1.0):
    """Acceleration, LO displacement (and true ball motion if known) and base motion.

    Parameters
    ----------
    rec : Recording
    truth : GroundTruth, optional
        Ground truth of a simulated recording: true impacts are marked and the true
        ball displacement is drawn between the walls x +/- b.
    path : Path, optional
        Where to save the figure (PNG); the figure is returned either way.
    window : float
        Seconds shown from the start of the record.
    """
    fig, ax = figure(3, 1, sharex=True)
    sel = rec.t <= rec.t[0] + window
    t = rec.t[sel]
    ax[0, 0].plot(t, rec.a[sel], lw=0.7, color="C0")
    ax[0, 0].set_ylabel("a (m/s$^2$)")
    ax[1, 0].plot(t, rec.x[sel] * 1e3, lw=0.9, color="C0", label="LO x")
    ax[2, 0].plot(t, rec.xe[sel] * 1e3, lw=0.9, color="C2")
    ax[2, 0].set_ylabel("$x_e$ (mm)")
    ax[2, 0].set_xlabel("t (s)")
    if truth is not None:
        b = truth.b_true
        imps = truth.impacts.select(truth.impacts.t <= rec.t[0] + window)
        for side, marker, color in (("right", "x", "C3"), ("left", "+", "C1")):
            ti = imps.t[imps.side == side]
            if ti.size:
                # mark each impact at the pulse's extreme sample (sign of the wall)
                k = np.searchsorted(rec.t, ti)
                win = np.clip(k[:, None] + np.arange(-2, 3), 0, rec.n - 1)
                vals = rec.a[win]
                peak = vals.max(axis=1) if side == "right" else vals.min(axis=1)
                ax[0, 0].plot(ti, peak, marker, color=color, ms=6, label=f"{side} impacts")
        y = truth.motion.y[: sel.sum()]
        xt = truth.motion.x[: sel.sum()]
        ax[1, 0].plot(t, (xt + b) * 1e3, lw=0.5, color="0.6", label="walls x ± b")
        ax[1, 0].plot(t, (xt - b) * 1e3, lw=0.5, color="0.6")
        ax[1, 0].plot(t, y * 1e3, ":", lw=1.0, color="C3", label="ball y (truth)")
        ax[0, 0].legend(loc="upper right", fontsize=7)
        regime = truth.label
        fig.suptitle(f"{rec.name}: b = {rec.meta.b * 1e3:g} mm"
                     + (f", regime {regime}" if regime else ""), fontsize=10)
    ax[1, 0].set_ylabel("displacement (mm)")
    ax[1, 0].legend(loc="upper right", fontsize=7)
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig
