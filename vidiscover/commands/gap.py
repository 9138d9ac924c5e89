"""``vidiscover gap REC --out DIR`` and ``vidiscover gap-check``: sim-to-real gap.

``gap`` diagnoses one recording against the nominal model (the README's gap section) and
writes ``summary.json`` (keys ``gap_before``, ``effects[] {name, params, gap_after,
shrink}``, ``attributed[]``, ``unexplained``, plus components per group and per
statistic), ``figures/waterfall.png``, ``figures/returnmap.png``,
``figures/restitution.png`` and a small ``report.html``, atomically.

``gap-check`` runs the withheld-effect battery and prints the attribution accuracy,
the confusion table and the shrink per case (JSON keys ``accuracy``,
``confusion``, ``cases``).
"""

from __future__ import annotations

from pathlib import Path

import click

from ..cli import OUT_DIR_HELP, channels_option, check_out_dir, emit, handle_errors
from ..errors import InputError

__all__ = ["gap", "gap_check", "run_gap", "human_gap", "human_check", "param_text"]


def _check_jobs(n_jobs: int | None) -> int | None:
    if n_jobs is not None and n_jobs < 1:
        raise InputError(f"--n-jobs must be >= 1 (worker processes), was {n_jobs!r}")
    return n_jobs


def human_gap(doc: dict) -> str:
    """A few lines describing a gap diagnosis."""
    lines = [f"{doc['recording']}: gap before {doc['gap_before']:.1f} "
             f"(threshold {doc['threshold']:g}; "
             f"{'significant' if doc['significant'] else 'no significant gap'})"]
    comps = doc["components"]
    lines.append("  components (before -> after): " + ", ".join(
        f"{g} {c['before']:.1f}->{c['after']:.1f}" for g, c in comps.items()))
    lines.append("  candidates (validated gap, shrink)" + (
        ":" if doc.get("refined", True) else
        f", fitted on their grids only (no effect can make a gap below "
        f"{doc['threshold_drop'][0]:g} significant):"))
    for e in doc["effects"]:
        params = param_text(e["params"], e.get("ci"))
        lines.append(f"    {e['name']:<32} {e['gap_after']:>10.1f}  "
                     f"{100 * e['shrink']:>7.1f} %  ({params})")
    for name, why in (doc.get("not_fitted") or {}).items():
        lines.append(f"    {name:<32} not fitted: {why}")
    if doc["attributed"]:
        lines.append("  attributed: " + ", ".join(
            f"{a['name']} ({100 * a['share']:.0f} % of the gap; "
            f"{param_text(a['params'], a.get('ci'))})" for a in doc["attributed"]))
    lines.append(f"  unexplained share: {100 * doc['unexplained']:.0f} %  -> verdict: "
                 f"{doc['verdict']}")
    if doc.get("not_excluded"):
        lines.append(f"  not excluded: {', '.join(doc['not_excluded'])} "
                     f"({_NOT_EXCLUDED_WHY})")
    if doc.get("out"):
        lines.append(f"  written to {doc['out']}/ ({', '.join(_top_level(doc['files']))})")
    return "\n".join(lines)


_NOT_EXCLUDED_WHY = ("every wall's impacts come at one speed, where a law per wall gives "
                     "the same r as a constant")


def _top_level(files: list[str]) -> list[str]:
    """The written files, with folders named once (``figures/``)."""
    out: list[str] = []
    for f in files:
        name = f.split("/", 1)[0] + "/" if "/" in f else f
        if name not in out:
            out.append(name)
    return out


def param_text(params: dict, cis: dict | None = None) -> str:
    """``key = value [low, high]`` per fitted parameter, as many digits as it carries.

    A parameter with an interval is printed to two significant digits of the
    interval's half-width; one without, to 3 significant digits (restitution-law
    specs as they are).
    """
    from ..report.html import interval_text

    out = []
    for k, v in params.items():
        ci = (cis or {}).get(k)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            out.append(f"{k} = {v}")
        elif ci and ci[0] is not None and ci[1] is not None and ci[1] > ci[0]:
            out.append(f"{k} = {interval_text(v, ci[0], ci[1])}")
        else:
            out.append(f"{k} = {v:.3g}")
    return "; ".join(out)


_CAPTIONS = {
    "waterfall.png": "Gap components of the nominal model (red, stacked to the total), what "
                     "each attributed effect removes (green) and what remains (grey), on a "
                     "linear axis.",
    "returnmap.png": "Return map of the impact intervals: recording, nominal model and the "
                     "selected model.",
    "restitution.png": "Restitution per impact against time, per wall: recording, nominal "
                       "model and the selected model.",
}


def _html(doc: dict, figures: list[str]) -> str:
    from ..report.html import _card, _page, _table, esc, fmt

    cards = [_card(fmt(doc["gap_before"], 3), "gap before (noise level ~1)"),
             _card(fmt(doc["gap_after"], 3), "gap after"),
             _card(doc["verdict"], "verdict"),
             _card(f"{100 * doc['unexplained']:.0f} %", "unexplained share")]
    body = [f"<h1>Sim-to-real gap: {esc(doc['recording'])}</h1>",
            f'<div class="cards">{"".join(cards)}</div>',
            f"<p>Significance threshold {fmt(doc['threshold'], 3)}"
            + (f" (or one effect removes at least {fmt(doc['threshold_drop'][0], 2)} of the "
               f"gap and leaves at most {100 * doc['threshold_drop'][1]:.0f} %)"
               if doc.get("threshold_drop") else "")
            + f": the gap is {'significant' if doc['significant'] else 'not significant'}.</p>"]
    if doc.get("not_excluded"):
        body.append(f"<p>Not excluded by this recording: {esc(', '.join(doc['not_excluded']))} "
                    f"({esc(_NOT_EXCLUDED_WHY)}).</p>")
    for name, why in (doc.get("not_fitted") or {}).items():
        body.append(f"<p>Not fitted: {esc(name)} ({esc(why)}).</p>")
    if doc["attributed"]:
        body.append("<h2>Attributed</h2>")
        body.append(_table(["effect", "share of the gap", "parameters [95 % interval]"],
                           [[a["name"], f"{100 * a['share']:.0f} %",
                             param_text(a["params"], a.get("ci"))]
                            for a in doc["attributed"]]))
    body.append("<h2>Components</h2>")
    body.append(_table(["group", "before", "after"],
                       [[g, fmt(c["before"], 3), fmt(c["after"], 3)]
                        for g, c in doc["components"].items()]))
    body.append("<h2>Candidates</h2>")
    body.append(_table(["effect", "gap after", "shrink", "parameters"],
                       [[e["name"], fmt(e["gap_after"], 3), f"{100 * e['shrink']:.1f} %",
                         param_text(e["params"], e.get("ci"))] for e in doc["effects"]]))
    for f in figures:
        cap = _CAPTIONS.get(f, "")
        body.append(f'<figure><img src="figures/{esc(f)}" alt="{esc(f)}">'
                    f"<figcaption>{esc(cap)}</figcaption></figure>")
    return _page(f"gap: {doc['recording']}", "".join(body))


def run_gap(path: Path, out: Path, *, meta: Path | None = None, seed: int = 0,
            n_jobs: int | None = None, scheduler=None, figures: bool = True,
            channels: dict | None = None) -> dict:
    """Diagnose one recording file and write the outputs (the ``gap`` command).

    Returns
    -------
    dict
        The summary (``summary.json`` content) plus ``out`` and ``files``.
    """
    from .._atomic import atomic_directory, write_json
    from ..gap import diagnose
    from ..io import read_recording

    out = check_out_dir(out)
    rec = read_recording(path, meta=meta, channels=channels)
    report = diagnose(rec, seed=seed, n_jobs=n_jobs, scheduler=scheduler)
    doc = report.to_dict()
    files = ["summary.json"]
    with atomic_directory(out) as tmp:
        figs = []
        if figures:
            from ..gap.figures import write_figures

            figs = write_figures(report, Path(tmp) / "figures")
            files += [f"figures/{f}" for f in figs]
        (Path(tmp) / "report.html").write_text(_html(doc, figs), encoding="utf-8")
        files.append("report.html")
        write_json(Path(tmp) / "summary.json", doc)
    return {**doc, "out": str(out), "files": files}


@click.command("gap")
@click.argument("recording", type=click.Path(path_type=Path))
@click.option("--out", type=click.Path(path_type=Path), required=True,
              help=f"Output directory (summary.json, figures/, report.html). {OUT_DIR_HELP}")
@click.option("--meta", type=click.Path(path_type=Path), default=None,
              help="Metadata JSON, if not beside the recording (rec.json).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the simulated side's sensor noise.")
@click.option("--n-jobs", type=int, default=None,
              help="Worker processes for the candidate fits (default: all cores).")
@click.option("--scheduler", default=None, help="Dask scheduler address (tcp://host:8786).")
@channels_option
@click.option("--no-figures", is_flag=True, help="Skip the figures.")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON document.")
@handle_errors
def gap(recording, out, meta, seed, n_jobs, scheduler, channels, no_figures, as_json):
    """Diagnose the sim-to-real gap of RECORDING against the paper's nominal model.

    Says where the gap lies (components), which catalogue effect removes it
    (fitted, validated, penalised), how far it shrinks, and what stays unexplained.
    """
    if seed < 0:
        raise InputError(f"--seed must be >= 0, was {seed!r}")
    doc = run_gap(recording, out, meta=meta, seed=seed, n_jobs=_check_jobs(n_jobs),
                  scheduler=scheduler, figures=not no_figures, channels=channels)
    emit(as_json, doc, human_gap(doc))


def human_check(doc: dict) -> str:
    """Table of a gap-check run: per case, then accuracy, confusion, shrink."""
    lines = [f"{'effect':<32}{'mag':<7}{'b mm':>6} {'regime':<10}{'verdict':<34}"
             f"{'before':>9}{'shrink':>8}{'unexpl':>8}"]
    for c in doc["cases"]:
        mark = "ok" if c["correct"] else "XX"
        lines.append(f"{c['effect']:<32}{c['magnitude']:<7}{1e3 * c['b']:>6.1f} "
                     f"{c['regime']:<10}{c['predicted']:<32}{mark}{c['gap_before']:>9.1f}"
                     f"{100 * c['shrink']:>7.0f}%{100 * c['unexplained']:>7.0f}%")

    def pct(v):
        return "n/a" if v is None or v != v else f"{100 * v:.0f} %"

    lines += [
        f"top-1 accuracy (catalogue effects): {pct(doc['accuracy'])} over "
        f"{doc['n_catalogue_cases']} cases",
        f"no-effect cases reported as no significant gap: {pct(doc['none_accuracy'])} "
        f"of {doc['n_none_cases']}",
        f"out-of-catalogue cases with unexplained share >= 50 %: "
        f"{pct(doc['outside_unexplained'])} of {doc['n_outside_cases']}",
        f"median shrink over all catalogue cases: {pct(doc['median_shrink'])} "
        f"(over the right attributions only: {pct(doc.get('median_shrink_correct'))})",
        f"time: {doc['time_s']:.1f} s wall, {doc['cpu_s_cases']:.1f} s CPU in cases",
        "confusion (expected -> predicted: count):"]
    for exp, row in doc["confusion"].items():
        lines.append(f"  {exp:<32} " + ", ".join(f"{k}: {v}" for k, v in row.items()))
    if doc.get("verdicts"):
        lines.append("targets:")
        for v in doc["verdicts"]:
            val = "n/a" if v["value"] is None else f"{v['value']:.3f}"
            lines.append(f"  {v['verdict']:<7}{v['what']}: {val} (target >= {v['target']:g})")
    return "\n".join(lines)


@click.command("gap-check")
@click.option("--quick", is_flag=True, help="A 4-case subset (about a minute).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Offset of the simulated recordings' noise seeds.")
@click.option("--n-jobs", type=int, default=None,
              help="Worker processes over cases (default: all cores).")
@click.option("--scheduler", default=None, help="Dask scheduler address (tcp://host:8786).")
@click.option("--out", type=click.Path(path_type=Path), default=None,
              help=f"Also write the result to DIR/gap_check.json. {OUT_DIR_HELP}")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document.")
@handle_errors
def gap_check(quick, seed, n_jobs, scheduler, out, as_json):
    """Withheld-effect battery: diagnose simulated recordings without being told."""
    from .._atomic import atomic_directory, write_json
    from ..gap import gap_check as run_check

    if seed < 0:
        raise InputError(f"--seed must be >= 0, was {seed!r}")
    if out is not None:
        check_out_dir(out)
    doc = run_check(quick=quick, seed=seed, n_jobs=_check_jobs(n_jobs), scheduler=scheduler,
                    progress=not as_json)
    if out is not None:
        with atomic_directory(out) as tmp:
            write_json(Path(tmp) / "gap_check.json", doc)
    emit(as_json, doc, human_check(doc))
