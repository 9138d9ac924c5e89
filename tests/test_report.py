"""Figures, HTML report and written files of an analysis (vidiscover.report)."""

import base64
import json
import re
from html.parser import HTMLParser

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from vidiscover import preset
from vidiscover.analysis import analyze
from vidiscover.analysis.restitution import MU_TABLE
from vidiscover.report import (
    FIGURES,
    FigureSpec,
    compare_truth,
    register_figure,
    render_report,
    write_analysis,
    write_index,
)
from vidiscover.report import write as write_mod
from vidiscover.workflows import simulate_to_memory

R_RIGHT, R_LEFT = 0.8782, 0.2018
ASYM = (f"asymmetric_restitution={R_RIGHT},{R_LEFT}",)
#: Tolerance of the per-wall RMS restitution against simulated truth (brief: 0.02).
R_TOL = 0.02


@pytest.fixture(scope="module")
def case():
    """(AnalysisResult, truth) of the paper rig at b = 9 mm with asymmetric walls."""
    rec, truth, _ = simulate_to_memory(preset("paper", b=0.009), ASYM, seed=3, settle=4.0,
                                       duration=3.0, name="b9")
    return analyze(rec), truth


@pytest.fixture(scope="module")
def quiet():
    """A recording with no impact at all (friction holds the ball in a wide clearance)."""
    rec, truth, _ = simulate_to_memory(preset("paper", b=0.03), ["coulomb_friction=0.3"],
                                       seed=1, settle=3.0, duration=2.0, name="quiet")
    assert truth.impacts.n == 0
    return analyze(rec), truth


@pytest.fixture(scope="module")
def written(case, tmp_path_factory):
    result, truth = case
    out = tmp_path_factory.mktemp("report") / "b9"
    info = write_analysis(result, out, truth=truth)
    return out, info


def _n_lines(fig: Figure) -> int:
    return sum(len(ax.lines) for ax in fig.axes)


# ----------------------------------------------------------------------------- figures
def test_registry_covers_the_paper_figures():
    papers = " ".join(spec.paper for spec in FIGURES.values())
    for n in (4, 5, 6, 7, 12, 13, 14, 16):
        assert re.search(rf"\b{n}\b", papers), f"paper Fig. {n} has no registered figure"
    assert all(isinstance(s, FigureSpec) and s.caption for s in FIGURES.values())


def test_register_figure_refuses_a_duplicate_name():
    with pytest.raises(ValueError, match="already registered"):
        register_figure("restitution", "Fig. 16", "again")(lambda result, truth=None: None)


@pytest.mark.parametrize("name", list(FIGURES))
def test_every_figure_draws_data_and_overlays_truth(case, name):
    result, truth = case
    plain = FIGURES[name](result)
    over = FIGURES[name](result, truth)
    for fig in (plain, over):
        assert isinstance(fig, Figure)
        assert fig.canvas.__class__.__name__ == "FigureCanvasAgg"
        assert _n_lines(fig) > 0
        assert any("b9" in ax.get_title() for ax in fig.axes)
    assert _n_lines(over) > _n_lines(plain), "the ground truth is not drawn"


@pytest.mark.parametrize("name", list(FIGURES))
def test_every_figure_survives_a_record_without_impacts(quiet, name):
    result, truth = quiet
    fig = FIGURES[name](result, truth)
    fig.canvas.draw()                      # layout and rendering must not fail


def test_restitution_figure_draws_the_rms_lines(case):
    result, _ = case
    fig = FIGURES["restitution"](result)
    levels = {round(float(line.get_ydata()[0]), 6) for line in fig.axes[0].lines
              if line.get_linestyle() == ":"}
    for side in ("right", "left"):
        assert round(result.restitution.wall(side).rms, 6) in levels


# ----------------------------------------------------------------------------- files
DESIGN_KEYS = [("impacts", "n"), ("impacts", "t"), ("impacts", "side"),
               ("restitution", "right", "rms"), ("restitution", "left", "rms"),
               ("restitution", "right", "n"), ("restitution", "left", "n"),
               ("regime", "label")]


def _get(d, path):
    for k in path:
        d = d[k]
    return d


def test_summary_json_has_the_design_keys_and_matches_the_tables(written):
    out, info = written
    summary = json.loads((out / "summary.json").read_text())
    for path in DESIGN_KEYS:
        _get(summary, path)                # KeyError if missing
    impacts = pd.read_csv(out / "impacts.csv")
    flights = pd.read_csv(out / "flights.csv")
    assert summary["impacts"]["n"] == len(impacts) == len(summary["impacts"]["t"]) > 20
    np.testing.assert_allclose(impacts["t"], summary["impacts"]["t"], rtol=1e-12)
    assert list(impacts["side"]) == summary["impacts"]["side"]
    assert summary["flights"]["n"] == len(flights)
    for side in ("right", "left"):
        used = impacts[(impacts["side"] == side) & impacts["r_used"]]
        assert summary["restitution"][side]["n"] == len(used)
        rms = float(np.sqrt(np.mean(used["r"] ** 2)))
        assert summary["restitution"][side]["rms"] == pytest.approx(rms, rel=1e-9)
    assert summary == info["summary"]


def test_summary_restitution_matches_simulated_truth(written):
    out, _ = written
    s = json.loads((out / "summary.json").read_text())
    assert abs(s["restitution"]["right"]["rms"] - R_RIGHT) < R_TOL
    assert abs(s["restitution"]["left"]["rms"] - R_LEFT) < R_TOL
    for side in ("right", "left"):
        assert abs(s["truth"]["restitution"][side]["rms_error"]) < R_TOL
    assert s["truth"]["impacts"]["recall"] > 0.95
    assert s["truth"]["impacts"]["precision"] > 0.95


def test_summary_carries_the_mu_table(written, case):
    out, _ = written
    rows = json.loads((out / "summary.json").read_text())["mu_table"]
    assert [r["mu"] for r in rows] == list(MU_TABLE)
    result, _ = case
    assert rows[0]["right_rms"] == pytest.approx(result.restitution.right.rms, rel=1e-9)


def test_figure_files_are_the_png_embedded_in_the_report(written):
    out, info = written
    html = (out / "report.html").read_text(encoding="utf-8")
    for name in FIGURES:
        png = (out / "figures" / f"{name}.png").read_bytes()
        assert png.startswith(b"\x89PNG\r\n\x1a\n")
        assert f'id="fig-{name}"' in html
        assert base64.b64encode(png).decode() in html
    assert sorted(info["files"]) == sorted(
        ["summary.json", "impacts.csv", "flights.csv", "report.html",
         *[f"figures/{n}.png" for n in FIGURES]])


class _Refs(HTMLParser):
    def __init__(self):
        super().__init__()
        self.refs = []

    def handle_starttag(self, tag, attrs):
        self.refs += [v or "" for k, v in attrs if k in ("src", "href", "srcset", "data")]


def _external_refs(html: str) -> list[str]:
    """Every src/href of every tag that is not embedded data or an in-page anchor."""
    parser = _Refs()
    parser.feed(html)
    # a regex as second opinion: attribute-like text inside any tag
    raw = re.findall(r"<[^>]*\b(?:src|href)\s*=\s*[\"']?([^\"'\s>]+)", html, flags=re.I)
    return [r for r in parser.refs + raw if not r.startswith(("data:", "#"))]


def test_report_is_self_contained(written):
    out, _ = written
    html = (out / "report.html").read_text(encoding="utf-8")
    assert _external_refs(html) == []
    # the one <link> is the empty inline icon (no favicon.ico request)
    assert re.findall(r"<link[^>]*>", html, flags=re.I) == ['<link rel="icon" href="data:,">']
    assert not re.search(r"<script|<iframe|@import|url\(", html, flags=re.I)
    assert html.startswith("<!DOCTYPE html>") and html.rstrip().endswith("</html>")
    for text in ("Restitution per wall", "Friction sensitivity", "Ground truth", "Warnings",
                 "Recording"):
        assert text in html


def test_report_escapes_every_string(case):
    result, truth = case
    summary = result.summary()
    summary["recording"] = "<img src=http://x/y.png>&"
    summary["warnings"] = ["<script>alert(1)</script>"]
    html = render_report(summary, meta={"source": "<b>rig</b>"},
                         figures={"<x>": b"\x89PNG"}, captions={"<x>": ("Fig. <1>", "<i>")})
    assert "<script>alert" not in html and "<b>rig" not in html and "<x>" not in html
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in html
    assert _external_refs(html) == []


def test_write_is_all_or_nothing(case, tmp_path, monkeypatch):
    result, _ = case
    out = tmp_path / "deep" / "out"

    def boom(obj):
        raise RuntimeError("disk full")

    monkeypatch.setattr(write_mod, "_json_text", boom)
    with pytest.raises(RuntimeError, match="disk full"):
        write_analysis(result, out, figures=False)
    assert list(tmp_path.iterdir()) == []


def test_output_is_deterministic(case, tmp_path):
    result, truth = case
    a = write_analysis(result, tmp_path / "a", figures=False, truth=truth)
    b = write_analysis(result, tmp_path / "b", figures=False, truth=truth)
    for f in ("summary.json", "impacts.csv", "flights.csv", "report.html"):
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes()
    assert "figures" not in a["files"] and not (tmp_path / "a" / "figures").exists()
    assert "not rendered" in (tmp_path / "a" / "report.html").read_text(encoding="utf-8")
    assert a["summary"] == b["summary"]


def test_a_record_without_impacts_is_reported(quiet, tmp_path):
    result, truth = quiet
    info = write_analysis(result, tmp_path / "q", truth=truth, figures=False)
    s = info["summary"]
    assert s["impacts"]["n"] == 0 and s["restitution"]["right"]["rms"] is None
    assert s["truth"]["impacts"]["n"] == 0
    assert len(pd.read_csv(tmp_path / "q" / "impacts.csv")) == 0
    assert "0</b><span>impacts" in (tmp_path / "q" / "report.html").read_text(encoding="utf-8")


def test_compare_truth_counts_matches(case):
    result, truth = case
    c = compare_truth(result, truth)
    assert c["impacts"]["n"] == truth.impacts.n
    assert c["impacts"]["matched"] <= min(result.detection.n, c["impacts"]["n"])
    assert c["regime"]["label"] == truth.label
    assert c["restitution"]["right"]["rms"] == pytest.approx(R_RIGHT, abs=1e-9)


def test_index_links_every_report(case, tmp_path):
    result, truth = case
    s = result.summary()
    entries = [{"href": "b9/report.html", "summary": s},
               {"href": "other/report.html", "summary": {**s, "recording": "o<ther"}}]
    path = write_index(entries, tmp_path)
    html = path.read_text(encoding="utf-8")
    links = [h for h in re.findall(r'href="([^"]+)"', html) if not h.startswith("data:")]
    assert links == ["b9/report.html", "other/report.html"]
    assert "o&lt;ther" in html and f"{result.restitution.right.rms:.4g}" in html
    with pytest.raises(ValueError, match="relative path"):
        write_index([{"href": "http://example.org/r.html", "summary": s}], tmp_path)


# ------------------------------------------------------------- values read as a person reads
def test_restitution_above_one_is_flagged_in_the_friction_table(written):
    out, info = written
    html = (out / "report.html").read_text(encoding="utf-8")
    over = [(r["mu"], side) for r in info["summary"]["mu_table"] for side in ("right", "left")
            if r[f"{side}_rms"] is not None and r[f"{side}_rms"] > 1.0]
    assert over, "the b = 9 mm case was chosen for its r > 1 at a large mu"
    table = html.split("Friction sensitivity", 1)[1].split("<h2>", 1)[0]
    assert table.count('class="flag"') == len(over)
    assert "not physical" in table
    for mu, side in over:
        assert f"{side} wall r = " in table and f"at mu = {mu:g}" in table
    rows = info["summary"]["mu_table"]
    for side in ("right", "left"):      # a wall left with no estimate at a larger mu is named
        if rows[0][f"{side}_n"] and any(not r[f"{side}_n"] for r in rows[1:]):
            assert f"no {side}-wall estimate is usable" in table
    # a table with every r <= 1 raises no flag
    rows = [{"mu": 0.0, "right_rms": 0.9, "left_rms": 0.2}]
    calm = render_report(info["summary"], mu_rows=rows).split("Friction sensitivity", 1)[1]
    assert 'class="flag"' not in calm.split("<h2>", 1)[0]


def test_intervals_print_as_many_digits_as_they_carry(written):
    out, info = written
    html = (out / "report.html").read_text(encoding="utf-8")
    for side in ("right", "left"):
        w = info["summary"]["restitution"][side]
        m = re.search(rf'<td class="l">{side}</td>(?:<td>[^<]*</td>){{4}}'
                      r"<td>([-\d.]+) \[([-\d.]+), ([-\d.]+)\]</td>", html)
        assert m, f"no RMS [CI] cell for the {side} wall"
        v, lo, hi = m.groups()
        assert float(lo) < float(v) < float(hi)      # the interval is not rounded away
        half = 0.5 * (w["ci_high"] - w["ci_low"])
        decimals = len(v.split(".")[1]) if "." in v else 0
        assert 0.01 <= half * 10 ** decimals < 100   # two significant digits of the half-width
        assert abs(float(v) - w["rms"]) <= 0.5 * 10 ** -decimals * 1.0001


def test_large_numbers_print_without_exponent():
    from vidiscover.report.html import fmt

    assert fmt(9420.4, 3) == "9420" and fmt(0.000123, 3) == "0.000123"
    assert "e+" in fmt(3.2e9, 3)


def test_flight_residual_figure_title_is_words_not_code():
    from types import SimpleNamespace

    from vidiscover.discovery.figures import plot_flight_residuals

    res = pd.DataFrame({"recording": ["a"] * 3, "t": [0.1, 0.2, 0.3],
                        "before": [0.01, -0.02, 0.0], "after": [0.0, 0.001, -0.001]})
    fake = SimpleNamespace(flight=None, flight_residuals=lambda: res)
    fig = plot_flight_residuals(fake)
    title = fig.axes[0].get_title()
    assert title and not re.search(r"\w+_\w+|wbar|\bdw\b", title), title


def test_branch_figure_draws_lengths_in_mm_with_the_unit():
    from vidiscover.orbits.figures import plot_branches

    pts = [{"value": v, "stable": True, "dt_T": [0.5, 0.5], "max_multiplier": 0.5}
           for v in (0.008, 0.009)]
    branch = {"kind": "P1", "sides": ["right", "left"], "points": pts, "bifurcations": []}
    fig = plot_branches([branch], param="b")
    bottom = fig.axes[-1]
    assert bottom.get_xlabel() == "b (mm)"
    assert np.allclose(fig.axes[0].lines[0].get_xdata(), [8.0, 9.0])
    assert plot_branches([branch], param="coulomb_friction.mu").axes[-1].get_xlabel() == \
        "coulomb_friction.mu"
