"""Figures (the paper's Figs. 4-18), the self-contained HTML report and its files.

* :mod:`.figures` -- one function per paper figure, registered in :data:`FIGURES`;
* :mod:`.html` -- the report page and the index page (no external assets);
* :mod:`.regime` -- the regime label from the classifier, when a model is installed;
* :mod:`.truth` -- comparison with the ground truth of simulated recordings;
* :mod:`.write` -- :func:`write_analysis` (summary.json, impacts.csv, flights.csv,
  figures, report.html, all or nothing) and :func:`write_index`.
"""

from .figures import FIGURES, FigureSpec, register_figure, render_all
from .html import render_index, render_report
from .regime import attach_regime, default_regime_model
from .truth import compare_truth
from .write import analysis_summary, write_analysis, write_index

__all__ = ["FIGURES", "FigureSpec", "analysis_summary", "attach_regime", "compare_truth",
           "default_regime_model", "register_figure", "render_all", "render_index",
           "render_report", "write_analysis", "write_index"]
