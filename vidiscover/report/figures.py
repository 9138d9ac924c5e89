"""The paper's figures (Li et al. 2018, Figs. 4-18) drawn from an :class:`AnalysisResult`.

Every figure is a function ``fig(result, truth=None, *, window=...)`` registered in
:data:`FIGURES` (name -> function, in the paper's order) with a caption and the
paper figure it reproduces, so the report and the tests iterate over the registry.
Figures are built on matplotlib's Agg canvas (:func:`vidiscover.plotting.figure`),
never through pyplot, so they are safe in threads and on machines with no screen.

``truth`` is the ground truth of a simulated recording (``rec.truth.json``, see
:func:`vidiscover.io.read_truth`); when given, the true ball motion, the true LO
velocity, the true impact times and the true restitution coefficients are drawn
over the estimates (grey, thin), so a reader sees at a glance where they differ.

Colours: right wall (z = +b) red, left wall (z = -b) blue; estimates in colour,
truth in grey or black.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..plotting import figure
from ..truth import GroundTruth
from .truth import matched_true_r

__all__ = ["FIGURES", "FigureSpec", "register_figure", "render_all"]

RIGHT, LEFT = "C3", "C0"
COLOURS = {"right": RIGHT, "left": LEFT}
MARKERS = {"right": "o", "left": "x"}
TRUTH = "0.45"
#: Default time window (s) of the time-history figures that need detail.
DETAIL_WINDOW = 0.5


class FigureSpec:
    """A registered figure: the drawing function plus its caption.

    Parameters
    ----------
    name : str
        Registry key (also the PNG file stem).
    func : callable
        ``func(result, truth=None, **kw) -> matplotlib.figure.Figure``.
    paper : str
        The figure(s) of the paper it reproduces, e.g. "Fig. 4".
    caption : str
        One sentence for the report.
    """

    def __init__(self, name: str, func: Callable, paper: str, caption: str):
        self.name = name
        self.func = func
        self.paper = paper
        self.caption = caption

    def __call__(self, result, truth: GroundTruth | None = None, **kw):
        """Draw the figure: ``func(result, truth, **kw)``."""
        return self.func(result, truth, **kw)

    def __repr__(self) -> str:
        return f"FigureSpec({self.name!r}, paper={self.paper!r})"


#: Registered figures, name -> :class:`FigureSpec`, in the paper's order.
FIGURES: dict[str, FigureSpec] = {}


def register_figure(name: str, paper: str, caption: str):
    """Decorator adding a figure function to :data:`FIGURES`.

    Parameters
    ----------
    name : str
        Registry key; must be new.
    paper : str
        Paper figure(s) reproduced.
    caption : str
        Caption shown in the report.
    """

    def deco(func):
        if name in FIGURES:
            raise ValueError(f"figure {name!r} is already registered")
        FIGURES[name] = FigureSpec(name, func, paper, caption)
        return func

    return deco


def render_all(result, truth: GroundTruth | None = None, names=None) -> dict:
    """Draw every registered figure (or ``names``).

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth, optional
        Ground truth to overlay.
    names : iterable of str, optional
        Subset of :data:`FIGURES` (default all).

    Returns
    -------
    dict
        name -> matplotlib Figure.
    """
    names = list(FIGURES) if names is None else list(names)
    unknown = [n for n in names if n not in FIGURES]
    if unknown:
        raise ValueError(f"unknown figure(s) {unknown}; known: {', '.join(FIGURES)}")
    return {n: FIGURES[n](result, truth) for n in names}


# ------------------------------------------------------------------------------ helpers


def _span(result, window: float | None) -> tuple[float, float]:
    t = result.reconstruction.t
    t0 = float(t[0])
    t1 = float(t[-1]) if window is None else min(float(t[-1]), t0 + float(window))
    return t0, t1


def _impacts_in(result, t0: float, t1: float) -> np.ndarray:
    t = result.detection.t
    return (t >= t0) & (t <= t1)


def _true_impacts(truth: GroundTruth | None):
    """The true impacts, or None without truth or impacts."""
    return truth.impacts if truth is not None and truth.impacts.n else None


def _truth_motion(truth: GroundTruth | None, key: str, t0: float, t1: float):
    """(t, values) of a truth motion channel inside [t0, t1], or None."""
    if truth is None:
        return None
    vals = getattr(truth.motion, key)
    t = truth.motion.t
    sel = (t >= t0) & (t <= t1)
    return t[sel], vals[sel]


def _title(ax, result, text: str) -> None:
    ax.set_title(f"{text} — {result.name}, b = {result.b * 1e3:g} mm", fontsize=9)


def _legend(ax, outside: bool = True) -> None:
    handles, labels = ax.get_legend_handles_labels()
    if handles and outside:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    elif handles:
        ax.legend(loc="upper right", fontsize=7, framealpha=0.8)


def _no_data(ax, text: str) -> None:
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center",
            fontsize=9, color="0.4")


def _sel(t: np.ndarray, t0: float, t1: float) -> np.ndarray:
    return (t >= t0) & (t <= t1)


# ------------------------------------------------------------------------------ figures
@register_figure("acceleration", "Figs. 4, 8, 10",
                 "LO acceleration with the detected impacts (crosses at the pulse "
                 "extreme; red: right wall, blue: left wall).")
def fig_acceleration(result, truth: GroundTruth | None = None, *, window: float | None = None):
    """LO acceleration over the record with the detected impacts marked (Figs. 4, 8, 10).

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth, optional
        True impact times are drawn as grey ticks along the top of the axes.
    window : float, optional
        Seconds shown from the start (default the whole record).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure(1, 1, figsize=(9, 3.0))
    ax = axes[0, 0]
    rec = result.recording
    t0, t1 = _span(result, window)
    if rec is not None:
        s = _sel(rec.t, t0, t1)
        ax.plot(rec.t[s], rec.a[s], lw=0.5, color="0.2", label="measured a")
        a_at = rec.a
        t_rec = rec.t
    else:
        s = _sel(result.reconstruction.t, t0, t1)
        ax.plot(result.reconstruction.t[s], result.detection.a_smooth[s], lw=0.5,
                color="0.2", label="pulse-free a")
        a_at = result.detection.a_smooth
        t_rec = result.reconstruction.t
    det = result.detection
    inside = _impacts_in(result, t0, t1)
    for side in ("right", "left"):
        m = inside & (det.side == side)
        if m.any():
            k = np.clip(np.searchsorted(t_rec, det.t[m]), 0, t_rec.size - 1)
            win = np.clip(k[:, None] + np.arange(-3, 4), 0, t_rec.size - 1)
            vals = a_at[win]
            peak = vals.max(axis=1) if side == "right" else vals.min(axis=1)
            ax.plot(det.t[m], peak, "x", color=COLOURS[side], ms=5, mew=1.2,
                    label=f"{side} impacts ({int(m.sum())})")
    ti = _true_impacts(truth)
    if ti is not None:
        tt = ti.t[_sel(ti.t, t0, t1)]
        if tt.size:
            ax.plot(tt, np.full(tt.size, 0.97), "|", color=TRUTH, ms=6,
                    transform=ax.get_xaxis_transform(), label="true impacts")
    ax.set_xlim(t0, t1)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("a (m/s$^2$)")
    _title(ax, result, "LO acceleration")
    _legend(ax)
    return fig


@register_figure("return_map", "Fig. 5",
                 "First return map of impact time differences (Δt_i, Δt_i+1): a few "
                 "points mean periodic impacts, a line or a cloud irregular ones.")
def fig_return_map(result, truth: GroundTruth | None = None):
    """First return map of impact time differences (Fig. 5).

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth, optional
        The return map of the true impact times is drawn in grey.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure(1, 1, figsize=(4.8, 4.4))
    ax = axes[0, 0]
    rm = result.returnmap
    T = rm.period
    ti = _true_impacts(truth)
    if ti is not None and ti.n > 2:
        dt = np.diff(np.sort(ti.t))
        ax.plot(dt[:-1] / T, dt[1:] / T, ".", color=TRUTH, ms=7, alpha=0.5,
                label="truth")
    for side in ("right", "left"):
        m = rm.side == side
        if m.any():
            ax.plot(rm.x[m] / T, rm.y[m] / T, MARKERS[side], color=COLOURS[side], ms=4,
                    mfc="none" if side == "right" else None,
                    label=f"after a {side} impact ({int(m.sum())})")
    if rm.n_points == 0:
        _no_data(ax, "fewer than 3 impacts: no return map")
    hi = max(1.05, float(np.nanmax(np.r_[rm.x, rm.y] / T)) * 1.05) if rm.n_points else 1.05
    ax.plot([0, hi], [0, hi], ":", lw=0.7, color="0.6")
    ax.set_xlim(0, hi)
    ax.set_ylim(0, hi)
    ax.set_aspect("equal")
    ax.set_xlabel(r"$\Delta t_i$ / T")
    ax.set_ylabel(r"$\Delta t_{i+1}$ / T")
    ax.set_title(f"Return map — {result.name}\n{rm.n_points} points, "
                 f"{rm.n_clusters} clusters (T = {T * 1e3:.1f} ms)", fontsize=9)
    _legend(ax, outside=False)
    return fig


@register_figure("displacement", "Fig. 6",
                 "LO displacement (laser) with the impact moments as circles.")
def fig_displacement(result, truth: GroundTruth | None = None, *,
                     window: float | None = DETAIL_WINDOW):
    """Measured LO displacement with the impact moments (Fig. 6).

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth, optional
        The true LO displacement is drawn in grey.
    window : float, optional
        Seconds shown from the start (None: whole record).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure(1, 1, figsize=(9, 3.0))
    ax = axes[0, 0]
    rec = result.recording
    t0, t1 = _span(result, window)
    tx = _truth_motion(truth, "x", t0, t1)
    if tx is not None:
        ax.plot(tx[0], tx[1] * 1e3, lw=2.0, color="0.8", label="true x")
    if rec is not None:
        s = _sel(rec.t, t0, t1)
        ax.plot(rec.t[s], rec.x[s] * 1e3, lw=0.8, color="0.15", label="laser x")
    det = result.detection
    inside = _impacts_in(result, t0, t1)
    x_imp = np.asarray(result.reconstruction.impact_columns["x"])
    for side in ("right", "left"):
        m = inside & (det.side == side)
        if m.any():
            ax.plot(det.t[m], x_imp[m] * 1e3, "o", mfc="none", color=COLOURS[side], ms=6,
                    label=f"{side} impacts")
    ax.set_xlim(t0, t1)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("x (mm)")
    _title(ax, result, "LO displacement")
    _legend(ax)
    return fig


@register_figure("ball_displacement", "Figs. 7, 9, 11",
                 "Reconstructed ball displacement (dotted) between the walls x ± b; "
                 "circles: ball position at the impacts.")
def fig_ball_displacement(result, truth: GroundTruth | None = None, *,
                          window: float | None = DETAIL_WINDOW):
    """Reconstructed ball displacement between the walls ``x ± b`` (Figs. 7, 9, 11).

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth, optional
        The true ball displacement is drawn in grey.
    window : float, optional
        Seconds shown from the start (None: whole record).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure(1, 1, figsize=(9, 3.4))
    ax = axes[0, 0]
    rc = result.reconstruction
    t0, t1 = _span(result, window)
    s = _sel(rc.t, t0, t1)
    t = rc.t[s]
    ax.plot(t, (rc.x[s] + rc.b) * 1e3, lw=0.8, color=RIGHT, alpha=0.7, label="x + b (right)")
    ax.plot(t, (rc.x[s] - rc.b) * 1e3, lw=0.8, color=LEFT, alpha=0.7, label="x − b (left)")
    ty = _truth_motion(truth, "y", t0, t1)
    if ty is not None:
        ax.plot(ty[0], ty[1] * 1e3, lw=2.2, color="0.8", label="true ball y")
    y = rc.ball_position(t)
    ax.plot(t, y * 1e3, ":", lw=1.4, color="k", label="reconstructed ball y")
    det = result.detection
    inside = _impacts_in(result, t0, t1)
    y_imp = np.asarray(rc.impact_columns["y"])
    for side in ("right", "left"):
        m = inside & (det.side == side)
        if m.any():
            ax.plot(det.t[m], y_imp[m] * 1e3, "o", mfc="none", color=COLOURS[side], ms=6)
    if result.detection.n == 0:
        _no_data(ax, "no impact detected: the ball cannot be located")
    ax.set_xlim(t0, t1)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("displacement (mm)")
    _title(ax, result, "Ball reconstruction")
    _legend(ax)
    return fig


@register_figure("ball_velocity", "Fig. 12",
                 "Reconstructed ball velocity; circles: impact moments.")
def fig_ball_velocity(result, truth: GroundTruth | None = None, *,
                      window: float | None = DETAIL_WINDOW):
    """Reconstructed ball velocity (Fig. 12).

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth, optional
        The true ball velocity is drawn in grey.
    window : float, optional
        Seconds shown from the start (None: whole record).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure(1, 1, figsize=(9, 3.0))
    ax = axes[0, 0]
    rc = result.reconstruction
    t0, t1 = _span(result, window)
    s = _sel(rc.t, t0, t1)
    t = rc.t[s]
    tw = _truth_motion(truth, "yd", t0, t1)
    if tw is not None:
        ax.plot(tw[0], tw[1], lw=2.2, color="0.8", label="true ball velocity")
    ax.plot(t, rc.ball_velocity(t), lw=1.0, color="k", label="reconstructed")
    det = result.detection
    inside = _impacts_in(result, t0, t1)
    for side in ("right", "left"):
        m = inside & (det.side == side)
        if m.any():
            w = np.asarray(rc.impact_columns["w_minus"])[m]
            ax.plot(det.t[m], w, "o", mfc="none", color=COLOURS[side], ms=5,
                    label=f"{side} impacts")
    if det.n == 0:
        _no_data(ax, "no impact detected")
    ax.axhline(0, lw=0.5, color="0.6")
    ax.set_xlim(t0, t1)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("ball velocity (m/s)")
    _title(ax, result, "Ball velocity")
    _legend(ax)
    return fig


@register_figure("lo_velocity", "Fig. 13",
                 "LO velocity from the displacement (non-smooth, differentiated laser) "
                 "and from the acceleration (smooth, integrated, with jumps at impacts).")
def fig_lo_velocity(result, truth: GroundTruth | None = None, *,
                    window: float | None = DETAIL_WINDOW):
    """LO velocity estimated from displacement and from acceleration (Fig. 13).

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth, optional
        The true LO velocity is drawn in grey.
    window : float, optional
        Seconds shown from the start (None: whole record).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure(1, 1, figsize=(9, 3.0))
    ax = axes[0, 0]
    rc = result.reconstruction
    t0, t1 = _span(result, window)
    s = _sel(rc.t, t0, t1)
    ax.plot(rc.t[s], rc.v_disp[s], lw=0.6, color="C1", alpha=0.8,
            label="from displacement")
    tv = _truth_motion(truth, "xd", t0, t1)
    if tv is not None:
        ax.plot(tv[0], tv[1], lw=2.2, color="0.75", label="true LO velocity")
    ax.plot(rc.t[s], rc.v[s], lw=1.0, color="k", label="from acceleration")
    ax.set_xlim(t0, t1)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("LO velocity (m/s)")
    _title(ax, result, "LO velocity")
    _legend(ax)
    return fig


@register_figure("impact_velocities", "Fig. 14",
                 "LO velocity before (x'−, triangles) and after (x'+, crosses) each impact; "
                 "right: zoom on the strongest impact of the window.")
def fig_impact_velocities(result, truth: GroundTruth | None = None, *,
                          window: float | None = DETAIL_WINDOW / 2, zoom: float = 2e-3):
    """LO velocity before and after each impact (Fig. 14), with a zoom on one impact.

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth, optional
        True pre/post-impact LO velocities are drawn as grey dots.
    window : float, optional
        Seconds shown from the start (None: whole record).
    zoom : float
        Half-width (s) of the zoom around the impact with the largest velocity jump.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure(1, 2, figsize=(9, 3.0), width_ratios=(3, 1))
    rc = result.reconstruction
    det = result.detection
    t0, t1 = _span(result, window)
    inside = _impacts_in(result, t0, t1)
    cols = rc.impact_columns
    imps = truth.impacts.window(t0, t1) if truth is not None else None
    ranges = [(t0, t1)]
    if inside.any():
        k = np.flatnonzero(inside)[np.argmax(np.abs(det.dv[inside]))]
        ranges.append((det.t[k] - zoom, det.t[k] + zoom))
    for ax, (a, b) in zip(axes[0], ranges, strict=False):
        s = _sel(rc.t, a, b)
        ax.plot(rc.t[s], rc.v[s], lw=0.8, color="0.3", label="LO velocity")
        sel_t = imps.window(a, b) if imps is not None else None
        if sel_t is not None and sel_t.n:
            ax.plot(np.r_[sel_t.t, sel_t.t], np.r_[sel_t.v_minus, sel_t.v_plus],
                    ".", color="0.6", ms=9, label="truth")
        for side in ("right", "left"):
            m = inside & (det.side == side) & (det.t >= a) & (det.t <= b)
            if m.any():
                ax.plot(det.t[m], np.asarray(cols["v_minus"])[m], "v", mfc="none",
                        color=COLOURS[side], ms=5, label=f"x'− ({side})")
                ax.plot(det.t[m], np.asarray(cols["v_plus"])[m], "x", color=COLOURS[side],
                        ms=6, label=f"x'+ ({side})")
        ax.set_xlim(a, b)
        ax.set_xlabel("t (s)")
    axes[0, 0].set_ylabel("LO velocity (m/s)")
    _title(axes[0, 0], result, "LO velocity at the impacts")
    if len(ranges) > 1:
        axes[0, 1].set_title("zoom", fontsize=9)
        axes[0, 1].tick_params(axis="x", labelrotation=30, labelsize=7)
    else:
        _no_data(axes[0, 1], "no impact")
    _legend(axes[0, 0], outside=False)
    return fig


@register_figure("restitution", "Figs. 16-18",
                 "Restitution coefficient of every impact (eq. 9; circles: right wall, "
                 "crosses: left wall); dotted lines: RMS per wall.")
def fig_restitution(result, truth: GroundTruth | None = None):
    """Restitution coefficient per impact and wall with RMS lines (Figs. 16-18).

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth, optional
        The true r of the matched impacts is drawn as grey dots and the true RMS as
        dashed grey lines.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure(1, 1, figsize=(9, 3.4))
    ax = axes[0, 0]
    c = result.restitution.columns
    t = np.asarray(c["t"])
    r = np.asarray(c["r"], dtype=float)
    used = np.asarray(c["used"], dtype=bool)
    side = np.asarray(c["side"])
    r_true = matched_true_r(result, truth)
    ti = _true_impacts(truth)
    for sd in ("right", "left"):
        m = used & (side == sd)
        col = COLOURS[sd]
        if ti is not None and (m & np.isfinite(r_true)).any():
            mt = m & np.isfinite(r_true)
            ax.plot(t[mt], r_true[mt], ".", color=TRUTH, ms=4)
            rms_t = float(np.sqrt(np.mean(r_true[mt] ** 2)))
            ax.axhline(rms_t, ls="--", lw=0.8, color=TRUTH,
                       label=f"true RMS {sd} {rms_t:.3f}")
        if m.any():
            ax.plot(t[m], r[m], MARKERS[sd], color=col, ms=4,
                    mfc="none" if sd == "right" else None, label=f"{sd} ({int(m.sum())})")
            w = result.restitution.wall(sd)
            ax.axhline(w.rms, ls=":", lw=1.2, color=col, label=f"RMS {sd} {w.rms:.3f}")
    n_excl = int((~used & np.isfinite(r)).sum())
    if not used.any():
        _no_data(ax, "no impact with a usable restitution estimate")
    ax.set_xlim(float(result.reconstruction.t[0]), float(result.reconstruction.t[-1]))
    top = np.nanmax(np.r_[r[used], r_true, 1.0]) if used.any() else 1.0
    ax.set_ylim(0, max(1.05, 1.05 * float(top)))
    ax.set_xlabel("t (s)")
    ax.set_ylabel("r")
    _title(ax, result, f"Restitution, mu = {result.mu:g}"
           + (f" ({n_excl} estimates excluded)" if n_excl else ""))
    _legend(ax)
    return fig


@register_figure("pulse_response", "-",
                 "Accelerometer pulse response learned from the recording: the strongest "
                 "isolated pulses aligned at their fitted contact entry and scaled to unit "
                 "area (grey), their super-resolved average (black) and the fitted model "
                 "(red; kind, order, cut-off, contact duration and delay in the title).")
def fig_pulse_response(result, truth: GroundTruth | None = None):
    """The learned pulse response: aligned pulses, template and model.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure(1, 1, figsize=(9, 3.2))
    ax = axes[0, 0]
    det = result.detection
    resp = det.response
    fs = det.sample_rate
    model = det.pulse
    if resp is not None:
        for tp, p in zip(resp.pulses_t, resp.pulses):
            ax.plot(tp * 1e3, p, ".", color="0.75", ms=2)
        ax.plot(resp.template_t * 1e3, resp.template, "-", color="k", lw=1.0,
                label=f"average of {resp.n_pulses} pulses")
        t = np.linspace(min(resp.template_t[0], 0.0), resp.template_t[-1], 600)
    else:
        t = np.linspace(-model.span(fs) / fs, model.span(fs) / fs, 600)
    delay = resp.delay if resp is not None else model.delay(fs)
    shift = delay - model.delay(fs)           # the entry averaged over equally good models
    ax.plot(t * 1e3, model.response(t - shift, fs), "-", color=COLOURS["right"], lw=1.2,
            label="model" + ("" if resp is not None else " (given, not learned)"))
    true_model = _true_pulse(truth, fs)
    if true_model is not None:
        ax.plot(t * 1e3, true_model.response(t, fs), "--", color=TRUTH, lw=1.0,
                label="true response")
    ax.axvline(0.0, color="0.5", lw=0.8, ls=":")
    ax.axvline(delay * 1e3, color="0.5", lw=0.8, ls="--", label=f"delay {delay * 1e6:.0f} µs")
    order = f" order {model.order}" if model.causal else ""
    _title(ax, result, f"Pulse response: {model.kind}{order}, {model.cutoff * fs:.0f} Hz, "
           f"contact {model.tau * 1e6:.0f} µs")
    ax.set_xlabel("time from contact entry (ms)")
    ax.set_ylabel("pulse per unit area (1/s)")
    _legend(ax)
    return fig


def _true_pulse(truth: GroundTruth | None, fs: float):
    """The simulated recording's pulse response (a PulseModel), or None if unknown."""
    if truth is None:
        return None
    from ..analysis.pulse import PulseModel
    from ..errors import InputError

    sens = truth.sensors or {}
    kind = sens.get("anti_alias", "linear-phase")
    fc = sens.get("aa_cutoff")
    cutoff = fc / fs if fc else sens.get("cutoff", 0.45)
    try:
        tau = float(getattr(truth.effects, "tau", 0.0) or 0.0)
        return PulseModel(cutoff=float(cutoff), tau=tau, kind=kind,
                          order=int(sens.get("aa_order", 0)) if kind != "linear-phase" else 0)
    except (InputError, TypeError, ValueError):
        return None
