"""Write an analysis to disk: summary.json, impacts.csv, flights.csv, figures, report.html.

Everything of one analysis goes into one output directory through
:func:`vidiscover._atomic.atomic_directory`: either every file is written or the
directory is left as it was (no half-written report after an error).
"""

from __future__ import annotations

import io
import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from .._atomic import atomic_directory, to_jsonable, write_group
from ..truth import GroundTruth
from .figures import FIGURES
from .html import render_index, render_report
from .truth import compare_truth

__all__ = ["analysis_summary", "write_analysis", "write_index", "SUMMARY_FILE",
           "REPORT_FILE"]

SUMMARY_FILE = "summary.json"
REPORT_FILE = "report.html"
IMPACTS_FILE = "impacts.csv"
FLIGHTS_FILE = "flights.csv"
FIGURE_DIR = "figures"


def _mu_rows(result) -> list[dict] | None:
    """Rows of the friction-sensitivity table, or None without the recording."""
    if result.recording is None:
        return None
    return to_jsonable(result.mu_table().to_dict(orient="records"))


def analysis_summary(result, truth: GroundTruth | None = None, *, mu_table: bool = True,
                     regime: Mapping | None = None) -> dict:
    """The content of ``summary.json``.

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth, optional
        Ground truth of a simulated recording; adds the key ``truth``
        (:func:`vidiscover.report.truth.compare_truth`).
    mu_table : bool
        Add ``mu_table`` (paper Table 2 rows: ``mu``, ``{side}_rms``, ``{side}_n``,
        ``{side}_ratio``, ``{side}_warn``); it re-runs the reconstruction per mu.
    regime : Mapping, optional
        Extra regime information merged into ``regime`` (e.g. the classifier's
        ``proba`` and ``warnings``); the label itself is ``result.regime_label``.

    Returns
    -------
    dict
        :meth:`AnalysisResult.summary` (the README's command table keys ``impacts.n``,
        ``impacts.t``, ``impacts.side``, ``restitution.{side}.rms``/``n``,
        ``regime.label`` ...) plus ``mu_table`` and ``truth`` when asked; JSON-ready
        (NaN as None).
    """
    summary = result.summary()
    if regime:
        summary["regime"].update(to_jsonable(dict(regime)))
    if mu_table:
        rows = _mu_rows(result)
        if rows is not None:
            summary["mu_table"] = rows
    if truth is not None:
        summary["truth"] = to_jsonable(compare_truth(result, truth))
    return summary


def _meta_rows(result) -> dict:
    rec = result.recording
    if rec is None:
        return {}
    m = rec.meta
    exc = m.excitation or {}
    return {"source": m.source, "samples": int(rec.n), "sample rate (Hz)": m.sample_rate,
            "b, metadata (mm)": m.b * 1e3, "m1 (kg)": m.m1, "m2 (kg)": m.m2,
            "c1 (N s/m)": m.c1, "k1 (N/m)": m.k1,
            "base amplitude, metadata (mm)": None if exc.get("amplitude") is None
            else exc["amplitude"] * 1e3,
            "forcing frequency, metadata (Hz)": exc.get("frequency"),
            "file units": (m.extra or {}).get("units", "SI")}


def _status_counts(result) -> dict:
    c = result.restitution.columns
    side = np.asarray(c["side"])
    status = np.asarray(c["status"])
    out = {}
    for sd in ("right", "left"):
        vals, counts = np.unique(status[side == sd], return_counts=True)
        out[sd] = {str(v): int(k) for v, k in zip(vals, counts, strict=True)}
    return out


def _png(fig, dpi: int) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None})
    return buf.getvalue()


def write_analysis(result, out_dir: str | os.PathLike, *, figures: bool = True,
                   truth: GroundTruth | None = None, mu_table: bool = True,
                   regime: Mapping | None = None, dpi: int = 90) -> dict:
    """Write one analysis with its figures and self-contained report.

    Files: ``summary.json``, ``impacts.csv``, ``flights.csv``, ``figures/NAME.png``
    and ``report.html``.

    Parameters
    ----------
    result : AnalysisResult
        From :func:`vidiscover.analysis.analyze`.
    out_dir : str or path-like
        Output directory; created with its parents, complete or untouched.
    figures : bool
        Render every registered figure (:data:`vidiscover.report.figures.FIGURES`)
        into ``figures/NAME.png`` and the report.
    truth : GroundTruth, optional
        Ground truth of a simulated recording, overlaid in the figures and compared
        in the summary and report.
    mu_table : bool
        Compute the friction-sensitivity table (paper Table 2).
    regime : Mapping, optional
        Extra regime information for ``summary.json`` (see :func:`analysis_summary`).
    dpi : int
        Resolution of the PNG figures.

    Returns
    -------
    dict
        ``out`` (the directory), ``files`` (paths relative to it) and ``summary``
        (the content of ``summary.json``).
    """
    out = Path(out_dir)
    summary = analysis_summary(result, truth, mu_table=mu_table, regime=regime)
    files = [SUMMARY_FILE, IMPACTS_FILE, FLIGHTS_FILE]
    pngs: dict[str, bytes] = {}
    if figures:
        for name, spec in FIGURES.items():
            pngs[name] = _png(spec(result, truth), dpi)
        files += [f"{FIGURE_DIR}/{name}.png" for name in pngs]
    page = render_report(summary, figures=pngs,
                         captions={n: (s.paper, s.caption) for n, s in FIGURES.items()},
                         meta=_meta_rows(result), mu_rows=summary.get("mu_table"),
                         status_counts=_status_counts(result), files=files)
    with atomic_directory(out) as tmp:
        (tmp / SUMMARY_FILE).write_text(_json_text(summary), encoding="utf-8")
        result.impact_table.to_csv(tmp / IMPACTS_FILE, index=False)
        result.reconstruction.flights.to_csv(tmp / FLIGHTS_FILE, index=False)
        if pngs:
            (tmp / FIGURE_DIR).mkdir()
            for name, data in pngs.items():
                (tmp / FIGURE_DIR / f"{name}.png").write_bytes(data)
        (tmp / REPORT_FILE).write_text(page, encoding="utf-8")
    return {"out": str(out), "files": files + [REPORT_FILE], "summary": summary}


def _json_text(obj) -> str:
    return json.dumps(to_jsonable(obj), indent=2, allow_nan=False) + "\n"


def write_index(entries: Sequence[Mapping], out_dir: str | os.PathLike,
                title: str = "vidiscover reports", name: str = "index.html") -> Path:
    """Write an index page linking several reports.

    Parameters
    ----------
    entries : sequence of Mapping
        One per report: ``href`` (link relative to ``out_dir``, e.g.
        ``"rec1/report.html"``) and ``summary`` (its summary dict).
    out_dir : str or path-like
        Existing directory to write into.
    title : str
        Page title.
    name : str
        File name of the page.

    Returns
    -------
    Path
        The page written (atomically).
    """
    for e in entries:
        href = str(e["href"])
        if "://" in href or href.startswith(("/", "\\")):
            raise ValueError(f"index entry href must be a relative path, was {href!r}")
    path = Path(out_dir) / name
    text = render_index(entries, title)

    def write(tmp: Path) -> None:
        with open(tmp, "x", encoding="utf-8") as fh:
            fh.write(text)

    write_group([(path, write)])
    return path
