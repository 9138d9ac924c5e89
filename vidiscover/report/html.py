"""Self-contained HTML pages: the analysis report and an index of several reports.

The report is one file: figures are embedded as base64 PNG (``data:`` URIs), the
style is inline CSS, and nothing is fetched from elsewhere (no script, no external
stylesheet, font or image), so it can be mailed or archived as is. Every string
coming from data (recording names, warnings, metadata) is HTML-escaped.
"""

from __future__ import annotations

import base64
import html
import math
from collections.abc import Mapping, Sequence

__all__ = ["render_report", "render_index"]

_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;margin:0;
 color:#222;background:#fafafa}
main{max-width:1000px;margin:0 auto;padding:1.2em 1.5em 3em}
h1{font-size:1.5em;margin:.3em 0}h2{font-size:1.15em;margin-top:1.8em;
 border-bottom:1px solid #ccc;padding-bottom:.2em}
table{border-collapse:collapse;margin:.6em 0;font-size:.9em;background:#fff}
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:right}
th{background:#eee}td.l,th.l{text-align:left}
td.flag{background:#fde2e1;color:#8a1111;font-weight:600}
.cards{display:flex;flex-wrap:wrap;gap:.8em;margin:1em 0}
.card{background:#fff;border:1px solid #ccc;border-radius:6px;padding:.6em 1em;
 min-width:10em}.card b{display:block;font-size:1.3em}.card span{color:#666;font-size:.85em}
.warn{background:#fff4e0;border-left:4px solid #e69500;padding:.4em .8em;margin:.3em 0}
.ok{color:#2a7a2a}.muted{color:#777}
figure{margin:1.2em 0;background:#fff;border:1px solid #ddd;padding:.5em}
figure img{max-width:100%;height:auto;display:block;margin:auto}
figcaption{font-size:.88em;color:#444;margin-top:.4em}
nav a{margin-right:.8em}
"""

_NA = "—"
_LEFT = ' class="l"'


def esc(value) -> str:
    """HTML-escaped ``str(value)`` (quotes included)."""
    return html.escape(str(value), quote=True)


def fmt(value, digits: int = 4) -> str:
    """A number for a table cell: ``digits`` significant digits, "—" when missing."""
    if value is None:
        return _NA
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    try:
        v = float(value)
    except (TypeError, ValueError):
        return esc(value)
    if not math.isfinite(v):
        return _NA
    if 10 ** digits <= abs(v) < 1e7:
        return f"{v:.0f}"                   # 9420, not 9.42e+03
    return f"{v:.{digits}g}"


def interval_text(value, low, high) -> str:
    """``value [low, high]`` with as many decimals as the interval carries.

    Two significant digits of the interval's half-width set the decimals of all
    three numbers; without a usable interval, the value alone with :func:`fmt`.

    Examples
    --------
    >>> interval_text(0.87816, 0.87811, 0.87821)
    '0.878160 [0.878110, 0.878210]'
    >>> interval_text(2.0445, 1.012, 3.077)
    '2.0 [1.0, 3.1]'
    """
    try:
        v, lo, hi = float(value), float(low), float(high)
    except (TypeError, ValueError):
        return fmt(value)
    half = 0.5 * abs(hi - lo)
    if not (math.isfinite(v) and math.isfinite(half) and half > 0):
        return fmt(value)
    d = min(12, max(0, 1 - math.floor(math.log10(half))))
    return f"{v:.{d}f} [{lo:.{d}f}, {hi:.{d}f}]"


class Flagged(str):
    """Cell text shown highlighted (a value physics forbids, such as r > 1)."""


#: Restitution above this is not physical: the wall would give back more than it got.
R_PHYSICAL = 1.0


def r_cell(value) -> str:
    """An r value for a table cell, flagged when it exceeds :data:`R_PHYSICAL`."""
    text = fmt(value)
    if value is not None and isinstance(value, (int, float)) and value > R_PHYSICAL:
        return Flagged(f"{text} (> 1, not physical)")
    return text


def _table(header: Sequence[str], rows: Sequence[Sequence], left: int = 1) -> str:
    """An HTML table; cells are escaped (numbers go through :func:`fmt` first).

    A :class:`Flagged` cell is drawn highlighted (class ``flag``).
    """
    def cell(tag, k, v):
        classes = (["l"] if k < left else []) + (["flag"] if isinstance(v, Flagged) else [])
        cls = f' class="{" ".join(classes)}"' if classes else ""
        text = v if isinstance(v, str) else fmt(v)
        return f"<{tag}{cls}>{esc(text)}</{tag}>"

    head = "".join(cell("th", k, h) for k, h in enumerate(header))
    body = "".join("<tr>" + "".join(cell("td", k, v) for k, v in enumerate(r)) + "</tr>"
                   for r in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


#: An empty inline icon: a browser serving the folder over http asks for no favicon.ico
#: (whose 404 would be the page's only console error).
_ICON = '<link rel="icon" href="data:,">'


def _page(title: str, body: str) -> str:
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"{_ICON}"
            f"<title>{esc(title)}</title><style>{_CSS}</style></head>"
            f"<body><main>{body}</main></body></html>\n")


def _card(value: str, label: str) -> str:
    return f'<div class="card"><b>{esc(value)}</b><span>{esc(label)}</span></div>'


def _rms_ci(w: Mapping) -> str:
    if w.get("rms") is None:
        return _NA
    text = interval_text(w["rms"], w.get("ci_low"), w.get("ci_high"))
    return Flagged(text + " (> 1, not physical)") if w["rms"] > R_PHYSICAL else text


def _r_over_one(mu_rows: Sequence[Mapping]) -> str:
    """A warning naming the friction values at which a wall's RMS r exceeds 1."""
    bad = [(r.get("mu"), side, r.get(f"{side}_rms")) for r in mu_rows
           for side in ("right", "left")
           if isinstance(r.get(f"{side}_rms"), (int, float)) and r[f"{side}_rms"] > R_PHYSICAL]
    # a wall whose every estimate was rejected (r beyond the plausible bound) at larger mu
    lost = {side: [r.get("mu") for r in mu_rows[1:] if not r.get(f"{side}_n")]
            for side in ("right", "left") if mu_rows[0].get(f"{side}_n")}
    lost_text = "; ".join(f"at mu = {', '.join(fmt(m) for m in mus)} no {side}-wall estimate "
                          "is usable"
                          for side, mus in lost.items() if mus)
    if not bad:
        return ""
    where = "; ".join(f"{side} wall r = {fmt(v)} at mu = {fmt(mu)}" for mu, side, v in bad)
    return ('<div class="warn">r &gt; 1 is not physical (a wall cannot give back more '
            f"energy than it receives): {esc(where)}"
            + (f"; {esc(lost_text)}" if lost_text else "")
            + ". The friction correction over-corrects there: the ball-LO friction is "
            "likely below those values of mu.</div>")


def render_report(summary: Mapping, *, figures: Mapping[str, bytes] | None = None,
                  captions: Mapping[str, tuple[str, str]] | None = None,
                  meta: Mapping | None = None, mu_rows: Sequence[Mapping] | None = None,
                  status_counts: Mapping[str, Mapping[str, int]] | None = None,
                  files: Sequence[str] = ()) -> str:
    """The analysis report of one recording as a self-contained HTML string.

    Parameters
    ----------
    summary : Mapping
        :meth:`AnalysisResult.summary` (plus ``truth`` from
        :func:`vidiscover.report.truth.compare_truth` when known).
    figures : Mapping of str to bytes, optional
        PNG bytes per figure name, embedded in this order.
    captions : Mapping of str to (str, str), optional
        Per figure name, (paper figure, caption).
    meta : Mapping, optional
        Recording metadata (b, masses, stiffness, excitation, source ...).
    mu_rows : sequence of Mapping, optional
        Rows of the friction-sensitivity table (:meth:`AnalysisResult.mu_table`).
    status_counts : Mapping, optional
        Per wall, the number of impacts per restitution status.
    files : sequence of str
        Other files written with the report (named, not linked).

    Returns
    -------
    str
        The HTML document.
    """
    figures = dict(figures or {})
    captions = dict(captions or {})
    name = summary.get("recording", "recording")
    imp = summary.get("impacts", {})
    rest = summary.get("restitution", {})
    truth = summary.get("truth")
    regime = (summary.get("regime") or {}).get("label")
    parts = [f"<h1>Vibro-impact analysis: {esc(name)}</h1>",
             f'<p class="muted">b = {fmt(summary.get("b", math.nan) * 1e3)} mm, '
             f'assumed friction mu = {fmt(summary.get("mu"))}, '
             f'{fmt(summary.get("duration"))} s at {fmt(summary.get("sample_rate"))} Hz. '
             "Method: Li, Seguy, Lamarque, Berlioz, J. Comput. Nonlinear Dynam. 2018.</p>"]
    if figures:
        parts.append("<nav>" + "".join(f'<a href="#fig-{esc(n)}">{esc(n)}</a>'
                                       for n in figures) + "</nav>")
    # --- key numbers
    cards = [_card(str(imp.get("n", _NA)),
                   f"impacts ({imp.get('right', 0)} right, {imp.get('left', 0)} left)")]
    for side in ("right", "left"):
        w = rest.get(side) or {}
        cards.append(_card(fmt(w.get("rms"), 3), f"r {side} (RMS, n = {w.get('n', 0)})"))
    cards.append(_card(regime or "not classified", "regime"))
    if truth:
        cards.append(_card((truth.get("regime") or {}).get("label") or _NA, "true regime"))
    parts.append('<div class="cards">' + "".join(cards) + "</div>")
    # --- warnings
    parts.append("<h2>Warnings</h2>")
    warnings = summary.get("warnings") or []
    if warnings:
        parts.extend(f'<div class="warn">{esc(w)}</div>' for w in warnings)
    else:
        parts.append('<p class="ok">None.</p>')
    # --- restitution
    parts.append("<h2>Restitution per wall (eq. 9, RMS with "
                 f"{fmt(100 * (rest.get('level') or 0.95), 3)} % bootstrap CI)</h2>")
    header = ["wall", "used", "detected", "mean", "median", "RMS [CI]", "std",
              "friction ratio", "too slow"]
    if truth:
        header += ["true RMS", "RMS error"]
    rows = []
    for side in ("right", "left"):
        w = rest.get(side) or {}
        row = [side, w.get("n"), w.get("n_total"), w.get("mean"), w.get("median"),
               _rms_ci(w), w.get("std"), w.get("friction_ratio"), w.get("warn_slow")]
        if truth:
            tw = (truth.get("restitution") or {}).get(side) or {}
            row += [tw.get("rms"), tw.get("rms_error")]
        rows.append(row)
    parts.append(_table(header, rows))
    if status_counts:
        statuses = sorted({s for c in status_counts.values() for s in c})
        parts.append("<p>Impacts per restitution status (only <i>ok</i> enters the "
                     "statistics):</p>")
        parts.append(_table(["wall", *statuses],
                            [[side, *[int(status_counts[side].get(s, 0)) for s in statuses]]
                             for side in status_counts]))
    if mu_rows:
        parts.append("<h2>Friction sensitivity (paper Table 2)</h2>")
        parts.append(_table(
            ["mu", "r right RMS", "n right", "right too slow", "r left RMS", "n left",
             "left too slow"],
            [[r.get("mu"), r_cell(r.get("right_rms")), r.get("right_n"), r.get("right_warn"),
              r_cell(r.get("left_rms")), r.get("left_n"), r.get("left_warn")]
             for r in mu_rows]))
        parts.append(_r_over_one(mu_rows))
    proba = (summary.get("regime") or {}).get("proba")
    if proba:
        parts.append("<h2>Regime (classifier)</h2>")
        parts.append(_table(["label", "probability"],
                            sorted(([k, v] for k, v in proba.items()),
                                   key=lambda kv: -(kv[1] or 0.0))))
    # --- ground truth
    if truth:
        ti = truth.get("impacts") or {}
        parts.append("<h2>Ground truth (simulated recording)</h2>")
        parts.append(_table(["quantity", "value"], [
            ["true impacts", ti.get("n")], ["detectable (SNR >= 8)", ti.get("detectable")],
            ["matched (same wall, 0.5 ms)", ti.get("matched")],
            ["precision", ti.get("precision")], ["recall (detectable)", ti.get("recall")],
            ["median timing error (µs)", None if ti.get("timing_median") is None
             else ti["timing_median"] * 1e6],
            ["true regime", (truth.get("regime") or {}).get("label") or _NA],
            ["true half-clearance (mm)", None if truth.get("b_true") is None
             else truth["b_true"] * 1e3],
            ["effects simulated", _effects_text(truth.get("effects"))]]))
    # --- recording
    parts.append("<h2>Recording</h2>")
    rows = [["name", str(name)]]
    for k, v in (meta or {}).items():
        rows.append([str(k), v if isinstance(v, (int, float)) or v is None else str(v)])
    fc = summary.get("forcing") or {}
    rows += [["fitted forcing frequency (Hz)", fc.get("frequency")],
             ["fitted base amplitude (mm)", None if fc.get("amplitude") is None
              else fc["amplitude"] * 1e3],
             ["forcing fitted from", str(fc.get("source", _NA))],
             ["acceleration noise (m/s²)", imp.get("noise")],
             *_pulse_rows(summary),
             ["unreliable impacts", imp.get("unreliable")],
             ["flights (stick-then-fly)", f"{(summary.get('flights') or {}).get('n', 0)} "
              f"({(summary.get('flights') or {}).get('stick', 0)})"]]
    parts.append(_table(["field", "value"], rows))
    feats = summary.get("features") or {}
    if feats:
        parts.append("<h2>Return-map features</h2>")
        parts.append(_table(["feature", "value"], [[k, v] for k, v in feats.items()]))
    # --- figures
    parts.append("<h2>Figures</h2>")
    if not figures:
        parts.append('<p class="muted">Figures were not rendered (--no-figures).</p>')
    for fname, png in figures.items():
        paper, caption = captions.get(fname, ("", ""))
        b64 = base64.b64encode(png).decode("ascii")
        parts.append(f'<figure id="fig-{esc(fname)}"><img alt="{esc(fname)}" '
                     f'src="data:image/png;base64,{b64}"><figcaption><b>{esc(fname)}</b>'
                     f"{' (paper ' + esc(paper) + ')' if paper else ''}: {esc(caption)}"
                     "</figcaption></figure>")
    if files:
        parts.append("<h2>Files</h2><p>Written beside this report: "
                     + ", ".join(f"<code>{esc(f)}</code>" for f in files) + ".</p>")
    return _page(f"vidiscover: {name}", "".join(parts))


def _effects_text(effects) -> str:
    if not effects:
        return "none (nominal model)"
    if isinstance(effects, Mapping):
        def params(v):
            if isinstance(v, Mapping):
                return ", ".join(f"{k}={p}" for k, p in v.items())
            return str(v)

        return "; ".join(f"{k} ({params(v)})" for k, v in effects.items())
    return str(effects)


def render_index(entries: Sequence[Mapping], title: str = "vidiscover reports") -> str:
    """An index page linking several reports, with their key numbers.

    Parameters
    ----------
    entries : sequence of Mapping
        One per report: ``href`` (relative link to its ``report.html``) and
        ``summary`` (its summary dict, with ``truth`` when known).
    title : str
        Page title.

    Returns
    -------
    str
        The HTML document (no external assets; only the relative report links).
    """
    any_truth = any(e["summary"].get("truth") for e in entries)
    header = ["recording", "b (mm)", "impacts", "right", "left", "r right RMS",
              "r left RMS", "regime", "warnings"]
    if any_truth:
        header += ["true r right", "true r left", "true regime"]
    head = "".join(f"<th{_LEFT if k == 0 else ''}>{esc(h)}</th>"
                   for k, h in enumerate(header))
    body = []
    for e in entries:
        s = e["summary"]
        imp = s.get("impacts") or {}
        rest = s.get("restitution") or {}
        cells = [f'<td class="l"><a href="{esc(e["href"])}">{esc(s.get("recording"))}</a></td>']
        vals = [None if s.get("b") is None else s["b"] * 1e3, imp.get("n"), imp.get("right"),
                imp.get("left"), (rest.get("right") or {}).get("rms"),
                (rest.get("left") or {}).get("rms"),
                (s.get("regime") or {}).get("label") or "not classified",
                len(s.get("warnings") or [])]
        tr = s.get("truth")
        if any_truth:
            trr = (tr or {}).get("restitution") or {}
            vals += [(trr.get("right") or {}).get("rms"), (trr.get("left") or {}).get("rms"),
                     ((tr or {}).get("regime") or {}).get("label") or _NA]
        vals[4:6] = [r_cell(v) for v in vals[4:6]]
        flag = ' class="flag"'
        cells += [f"<td{flag if isinstance(v, Flagged) else ''}>"
                  f"{esc(v if isinstance(v, str) else fmt(v))}</td>" for v in vals]
        body.append("<tr>" + "".join(cells) + "</tr>")
    table = f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"
    intro = (f"<h1>{esc(title)}</h1><p>{len(entries)} analysed recording(s); click a name "
             "for its report (figures, restitution per wall, friction sensitivity).</p>")
    return _page(title, intro + table)


def _pulse_rows(summary: Mapping) -> list:
    """Rows for the learned pulse response and the removed offsets."""
    pr = summary.get("pulse_response") or {}
    off = summary.get("offsets") or {}
    kind = f"{pr.get('kind', _NA)}" + (f" order {pr['order']}" if pr.get("order") else "")
    return [["pulse response" + (" (learned)" if pr.get("learned") else " (given)"), kind],
            ["pulse cut-off (Hz)", pr.get("cutoff_hz")],
            ["contact duration (µs)", None if pr.get("tau") is None else pr["tau"] * 1e6],
            ["pulse delay after contact entry (µs)",
             None if pr.get("delay") is None else pr["delay"] * 1e6],
            ["accelerometer bias removed (m/s²)", off.get("a_bias")],
            ["laser / base zero offsets removed (µm)",
             f"{fmt(1e6 * off['x_offset'], 4)} / {fmt(1e6 * off['xe_offset'], 4)}"
             if off.get("x_offset") is not None else _NA]]
