"""Figures of a gap diagnosis: waterfall of the components, sim vs real overlays."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .components import GROUPS

__all__ = ["plot_waterfall", "plot_returnmap", "plot_restitution", "write_figures"]


def _fig(figsize=(6.4, 4.0)):
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=figsize, constrained_layout=True)


def plot_waterfall(report, ax=None):
    """Waterfall: gap components of the nominal model, then what the selection removes.

    Bars: one per component group (before), stacked to the total; then one bar per
    selected effect (negative, the gap it removed); the last bar is what remains.
    The axis is linear (a log axis makes a small component look as big as a large
    one); every bar is labelled with its value, so components too small to see are
    still read.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = _fig((7.5, 4.0))
    before = report.nominal.gap.by_group()
    labels, bottoms, heights, colors = [], [], [], []
    level = 0.0
    for g in GROUPS:
        v = before[g]
        labels.append(g)
        bottoms.append(level)
        heights.append(v)
        colors.append("tab:red")
        level += v
    prev = report.gap_before
    for c in report.selected:
        removed = prev - c.gap.total
        labels.append(f"- {c.name}")
        bottoms.append(c.gap.total)
        heights.append(removed)
        colors.append("tab:green")
        prev = c.gap.total
    labels.append("remaining")
    bottoms.append(0.0)
    heights.append(report.gap_after)
    colors.append("tab:gray")
    x = np.arange(len(labels))
    ax.bar(x, heights, bottom=bottoms, color=colors)
    top = max(report.gap_before, 1e-9)
    for xi, b0, h in zip(x, bottoms, heights):
        ax.text(xi, b0 + h + 0.01 * top, f"{h:.3g}", ha="center", va="bottom", fontsize=7)
    ax.set_xticks(x, labels, rotation=40, ha="right", fontsize=8)
    ax.set_ylabel("gap (sum of normalised squared differences)")
    ax.set_ylim(0, 1.1 * top)
    ax.axhline(report.gap_before, color="k", lw=0.5, ls=":")
    ax.set_title(f"{report.name}: gap {report.gap_before:.3g} -> {report.gap_after:.3g} "
                 f"({report.verdict})", fontsize=9)
    plt.setp(ax.get_xticklabels(), fontsize=8)
    return ax


def plot_returnmap(report, ax=None):
    """Return map (dt_i, dt_i+1)/T of the recording, the nominal and the selected model."""
    if ax is None:
        _, ax = _fig((4.6, 4.2))
    real = report.model.real.returnmap
    nom = report.nominal.signature.returnmap
    ax.plot(nom[:, 0], nom[:, 1], "s", mfc="none", color="tab:blue", ms=7, label="nominal sim")
    if report.selected:
        fit = report.final.signature.returnmap
        ax.plot(fit[:, 0], fit[:, 1], "^", mfc="none", color="tab:green", ms=7,
                label=" + ".join(c.name for c in report.selected))
    ax.plot(real[:, 0], real[:, 1], ".", color="k", ms=4, label="recording")
    ax.set_xlabel("dt_i / T")
    ax.set_ylabel("dt_(i+1) / T")
    ax.legend(fontsize=7)
    ax.set_title("first return map", fontsize=9)
    return ax


def plot_restitution(report, ax=None):
    """Restitution per impact against time: recording vs nominal vs selected model, per wall."""
    if ax is None:
        _, ax = _fig((6.4, 3.8))
    sets = [("recording", report.model.real.impacts, "k", "o")]
    sets.append(("nominal sim", report.nominal.signature.impacts, "tab:blue", "s"))
    if report.selected:
        sets.append(("fitted", report.final.signature.impacts, "tab:green", "^"))
    for label, imp, color, marker in sets:
        for sgn, fill in ((1, color), (-1, "none")):
            sel = imp["side"] == sgn
            ax.plot(imp["t"][sel], imp["r"][sel], marker, color=color, mfc=fill, ms=4,
                    ls="none", label=f"{label} ({'right' if sgn == 1 else 'left'})")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("r per impact")
    ax.legend(fontsize=6, ncol=3)
    ax.set_title("restitution per impact (filled: right wall)", fontsize=9)
    return ax


def write_figures(report, directory: Path) -> list[str]:
    """Write waterfall.png, returnmap.png, restitution.png; return their names."""
    import matplotlib.pyplot as plt

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    names = []
    for name, func in (("waterfall.png", plot_waterfall), ("returnmap.png", plot_returnmap),
                       ("restitution.png", plot_restitution)):
        fig, ax = _fig((7.5, 4.2) if name == "waterfall.png" else (6.0, 4.2))
        func(report, ax)
        fig.savefig(directory / name, dpi=90)
        plt.close(fig)
        names.append(name)
    return names
