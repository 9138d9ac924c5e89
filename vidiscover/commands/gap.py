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

from ..cli import check_out_dir, emit, handle_errors
from ..errors import InputError

__all__ = ["gap", "gap_check", "run_gap", "human_gap", "human_check"]


def _check_jobs(n_jobs: int | None) -> int | None:
    if n_jobs is not None and n_jobs < 1:
        raise InputError(f"--n-jobs must be >= 1 (worker processes), was {n_jobs!r}")
    return n_jobs


def _fmt(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def human_gap(doc: dict) -> str:
    """A few lines describing a gap diagnosis."""
    lines = [f"{doc['recording']}: gap before {doc['gap_before']:.1f} "
             f"(threshold {doc['threshold']:g}; "
             f"{'significant' if doc['significant'] else 'no significant gap'})"]
    comps = doc["components"]
    lines.append("  components (before -> after): " + ", ".join(
        f"{g} {c['before']:.1f}->{c['after']:.1f}" for g, c in comps.items()))
    lines.append("  candidates (validated gap, shrink):")
    for e in doc["effects"]:
        params = ", ".join(f"{k}={_fmt(v)}" for k, v in e["params"].items())
        lines.append(f"    {e['name']:<32} {e['gap_after']:>10.1f}  "
                     f"{100 * e['shrink']:>7.1f} %  ({params})")
    if doc["attributed"]:
        lines.append("  attributed: " + ", ".join(
            f"{a['name']} ({100 * a['share']:.0f} % of the gap)" for a in doc["attributed"]))
    lines.append(f"  unexplained share: {100 * doc['unexplained']:.0f} %  -> verdict: "
                 f"{doc['verdict']}")
    if doc.get("out"):
        lines.append(f"  written to {doc['out']}/ ({', '.join(_top_level(doc['files']))})")
    return "\n".join(lines)


def _top_level(files: list[str]) -> list[str]:
    """The written files, with folders named once (``figures/``)."""
    out: list[str] = []
    for f in files:
        name = f.split("/", 1)[0] + "/" if "/" in f else f
        if name not in out:
            out.append(name)
    return out


def _html(doc: dict, figures: list[str]) -> str:
    import html

    rows = "".join(
        f"<tr><td>{html.escape(e['name'])}</td><td>{e['gap_after']:.2f}</td>"
        f"<td>{100 * e['shrink']:.1f} %</td><td>{html.escape(str(e['params']))}</td></tr>"
        for e in doc["effects"])
    comp = "".join(f"<tr><td>{g}</td><td>{c['before']:.2f}</td><td>{c['after']:.2f}</td></tr>"
                   for g, c in doc["components"].items())
    imgs = "".join(f'<p><img src="figures/{f}" alt="{f}"></p>' for f in figures)
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>gap: "
            f"{html.escape(doc['recording'])}</title></head><body>"
            f"<h1>Sim-to-real gap: {html.escape(doc['recording'])}</h1>"
            f"<p>Gap before {doc['gap_before']:.2f}, after {doc['gap_after']:.2f}; verdict "
            f"<b>{html.escape(doc['verdict'])}</b>; unexplained share "
            f"{100 * doc['unexplained']:.0f} %.</p>"
            f"<h2>Components</h2><table border=1><tr><th>group</th><th>before</th>"
            f"<th>after</th></tr>{comp}</table>"
            f"<h2>Candidates</h2><table border=1><tr><th>effect</th><th>gap after</th>"
            f"<th>shrink</th><th>params</th></tr>{rows}</table>{imgs}</body></html>")


def run_gap(path: Path, out: Path, *, meta: Path | None = None, seed: int = 0,
            n_jobs: int | None = None, scheduler=None, figures: bool = True) -> dict:
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
    rec = read_recording(path, meta=meta)
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
              help="Output directory (summary.json, figures/, report.html).")
@click.option("--meta", type=click.Path(path_type=Path), default=None,
              help="Metadata JSON, if not beside the recording (rec.json).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the simulated side's sensor noise.")
@click.option("--n-jobs", type=int, default=None,
              help="Worker processes for the candidate fits (default: all cores).")
@click.option("--scheduler", default=None, help="Dask scheduler address (tcp://host:8786).")
@click.option("--no-figures", is_flag=True, help="Skip the figures.")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON document.")
@handle_errors
def gap(recording, out, meta, seed, n_jobs, scheduler, no_figures, as_json):
    """Diagnose the sim-to-real gap of RECORDING against the paper's nominal model.

    Says where the gap lies (components), which catalogue effect removes it
    (fitted, validated, penalised), how far it shrinks, and what stays unexplained.
    """
    if seed < 0:
        raise InputError(f"--seed must be >= 0, was {seed!r}")
    doc = run_gap(recording, out, meta=meta, seed=seed, n_jobs=_check_jobs(n_jobs),
                  scheduler=scheduler, figures=not no_figures)
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
              help="Also write the result to DIR/gap_check.json.")
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
