"""Regime commands: ``classify`` and ``train`` (regime classifier) and ``sweep``."""

from __future__ import annotations

from pathlib import Path

import click

from ..cli import (
    OUT_DIR_HELP,
    channels_option,
    check_out_dir,
    check_out_file,
    emit,
    handle_errors,
    recording_paths,
)
from ..errors import InputError
from ..params import PRESETS


# ---- classify / train (owned by the regime classifier) ----
def _check_model_out(out: Path) -> Path:
    if out.suffix != ".skops":
        raise InputError(f"--out {out}: a model file must end in .skops, e.g. --out "
                         "regime_model.skops")
    if not out.parent.is_dir():
        raise InputError(f"--out {out}: directory {out.parent} does not exist; create it "
                         "first")
    return check_out_file(out)


def _proba_text(proba: dict) -> str:
    top = sorted(proba.items(), key=lambda kv: -kv[1])[:3]
    return ", ".join(f"{k} {v:.2f}" for k, v in top if v > 0)


@click.command()
@click.argument("recordings", nargs=-1, type=click.Path(path_type=Path))
@click.option("--meta", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Metadata JSON for every recording (default: each recording's sidecar).")
@click.option("--model", "model_path", type=click.Path(dir_okay=False, path_type=Path),
              default=None, help="Regime model (.skops from `vidiscover train`; default: "
                                 "the model shipped with vidiscover).")
@channels_option
@click.option("--json", "as_json", is_flag=True,
              help="Print a JSON list of {file, label, method, proba, warnings}.")
@handle_errors
def classify(recordings, meta, model_path, channels, as_json):
    """Label recordings by regime, with class probabilities.

    Every recording is analysed from its sensor data alone (impacts, return map,
    LO response) and labelled by the regime classifier, or by the label rules below
    where the model keeps them (the labels for which the rules beat the classifier
    in training); each result says which method labelled it. A warning names the
    feature or rig ratio that lies outside the classifier's training domain.

    \b
    Labels (ipc: impacts per forcing cycle, after the transient):
      no_impact   fewer than one impact per 20 cycles
      1ipc        periodic, one impact in >= 90 % of cycles
      2ipc_sym    periodic, two alternating impacts per cycle, evenly spaced
      2ipc_asym   periodic, two alternating impacts per cycle, unevenly spaced
      multi_ipc   periodic, anything else (3+ impacts, chatter, same-wall repeats)
      smr         strongly modulated response: impacts in bursts on a slowly
                  modulated LO envelope
      chaotic     impacts, but neither periodic nor SMR
    """  # noqa: D301 - the backspace is click's no-rewrap marker
    from ..io import read_recording
    from ..regimes.classifier import load_default_model, load_model, warning_text

    recordings = recording_paths(recordings)
    recs = [read_recording(p, meta=meta, channels=channels) for p in recordings]
    model = load_model(model_path) if model_path is not None else load_default_model()
    results = [model.classify(rec, file=str(p)).to_dict() for p, rec in zip(recordings, recs)]
    for r in results:
        for w in r["warnings"]:
            click.echo(f"vidiscover: warning: {r['file']}: {warning_text(w)}", err=True)
    human = "\n".join(f"{r['file']}: {r['label']} [{r['method']}] "
                      f"({_proba_text(r['proba'])})" for r in results)
    emit(as_json, results, human)


@click.command()
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Model file to write (.skops); its training report goes beside it "
                   "(MODEL.json).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the training sweep (the test sweep uses seed + 100003).")
@click.option("--n", "n", type=int, default=2500, show_default=True,
              help="Random training cases (rare labels get targeted cases on top).")
@click.option("--n-test", type=int, default=800, show_default=True,
              help="Random held-out test cases of each simulated test set (0: none).")
@click.option("--n-realism", type=int, default=0, show_default=True,
              help="Random training cases of other rigs, compliant walls and instrument "
                   "chains, drawn as the realism corpus draws them.")
@click.option("--n-corpus-train", type=int, default=0, show_default=True,
              help="Recordings analysed as a user's (pulse learned; a few seconds "
                   "each) added to the training set: the realism corpus's 96 dev cases, "
                   "then cases drawn as the corpus draws them from --seed (0: none).")
@click.option("--n-corpus-test", type=int, default=0, show_default=True,
              help="Realism-corpus test cases analysed as a user's recordings (pulse "
                   "learned; a few seconds each) to score on (0: none).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Simulate on a Dask distributed cluster, e.g. tcp://host:8786 "
                   "(default: joblib processes on this machine).")
@click.option("--n-jobs", type=int, default=None,
              help="Worker processes without --scheduler (default: all cores; 1: serial).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document.")
@handle_errors
def train(out, seed, n, n_test, n_realism, n_corpus_train, n_corpus_test, scheduler, n_jobs,
          as_json):
    """Simulate a sweep, train and evaluate the regime classifier.

    Random rigs (clearance, base amplitude and frequency, mass ratio, restitution
    per wall, friction, inclination, sensor noise and resonance) are simulated,
    recorded and analysed; the classifier learns their true regime from the
    features of the recordings and is scored on a held-out sweep simulated with
    other seeds (balanced accuracy, recall per label, confusion table), beside the
    rule-based baseline. The model keeps the rules' label for every label unless the
    classifier beats the rules out of fold by more than 2 standard errors (3 repeats
    of the out-of-fold predictions) and where the rules are right in about half or
    more (``rule_labels`` in the report).
    """
    import time

    from .._atomic import write_json
    from ..regimes.classifier import save_model
    from ..regimes.classifier import train as run_train

    out = _check_model_out(out)
    if n < 1 or min(n_test, n_realism, n_corpus_train, n_corpus_test) < 0:
        raise InputError(f"--n must be >= 1 and --n-test, --n-realism, --n-corpus-train, "
                         f"--n-corpus-test >= 0, were {n}, {n_test}, {n_realism}, "
                         f"{n_corpus_train}, {n_corpus_test}")
    t0 = time.perf_counter()
    model, report = run_train(n, seed, n_test=n_test, n_realism=n_realism,
                              n_corpus_train=n_corpus_train, n_corpus_test=n_corpus_test,
                              n_jobs=n_jobs, scheduler=scheduler, progress=not as_json)
    report["seconds"] = round(time.perf_counter() - t0, 1)
    report["command"] = (f"vidiscover train --seed {seed} --n {n} --n-test {n_test} "
                         f"--n-realism {n_realism} --n-corpus-train {n_corpus_train} "
                         f"--n-corpus-test {n_corpus_test} "
                         f"--out {out}")
    model.metadata["command"] = report["command"]
    meta_path = out.with_suffix(".json")
    save_model(model, out)
    write_json(meta_path, {**dict(model.metadata), "report": report})
    report["outputs"] = [str(out), str(meta_path)]
    lines = [f"trained on {report['n_train']} simulated recordings in "
             f"{report['seconds']:.0f} s; wrote {out} and {meta_path}"]
    if "balanced_accuracy" in report:
        lines.append(_report_text(report))
    emit(as_json, report, "\n".join(lines))


def _report_text(report: dict) -> str:
    """Scores and confusion tables of the classifier and the rule baseline."""
    from ..regimes.classifier import format_report

    return format_report(report)


# ---- sweep (owned by sweep module) ----


def _base_params(preset_name: str, changes: tuple[str, ...]):
    from ..cli import parse_assignments
    from ..params import preset

    return preset(preset_name, **parse_assignments(changes, "--set"))


def _sweep_values(start: float, stop: float, n: int, log: bool):
    import numpy as np

    if n < 1:
        raise InputError(f"--n must be >= 1 (number of sweep points), was {n}")
    if log:
        if not (start > 0 and stop > 0):
            raise InputError(f"--log needs --from and --to > 0, were {start:g} and {stop:g}")
        return np.geomspace(start, stop, n)
    return np.linspace(start, stop, n)


@click.command()
@click.option("--param", required=True, metavar="NAME",
              help="Parameter to sweep: b, amplitude, frequency, r, m1, m2, c1, k1, noise, "
                   "or an effect parameter such as mu (coulomb_friction.mu), theta, r_left.")
@click.option("--from", "start", type=float, required=True,
              help="First value (SI units, e.g. 0.003 for b = 3 mm; theta in deg).")
@click.option("--to", "stop", type=float, required=True, help="Last value.")
@click.option("--n", "n", type=int, required=True, help="Number of points.")
@click.option("--log", is_flag=True, help="Space the values geometrically.")
@click.option("--preset", "preset_name", type=click.Choice(sorted(PRESETS)), default="paper",
              show_default=True, help="Parameter set the sweep starts from.")
@click.option("--set", "fixed", multiple=True, metavar="NAME=VALUE",
              help="Change a fixed parameter of every point, e.g. --set b=0.015.")
@click.option("--effect", multiple=True, metavar="NAME[=VALUE,...]",
              help="Switch on an effect at every point (repeatable), e.g. inclination=2.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Master seed (each point's seed is derived from it and its index).")
@click.option("--settle", type=float, default=10.0, show_default=True,
              help="Simulated time before each record (s).")
@click.option("--duration", type=float, default=5.12, show_default=True,
              help="Record length per point (s).")
@click.option("--noise", type=float, default=1.0, show_default=True,
              help="Scale factor of the sensor noise levels.")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Run on a Dask distributed cluster, e.g. tcp://host:8786 "
                   "(default: joblib processes on this machine).")
@click.option("--n-jobs", type=int, default=None,
              help="Worker processes without --scheduler (default: all cores; 1: serial).")
@click.option("--classify", "use_model", is_flag=True,
              help="Also predict each point's label from the sensor data with the "
                   "shipped regime classifier (column label_pred).")
@click.option("--model", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Regime classifier to predict labels with (implies --classify).")
@click.option("--overlay-branches", "overlay", is_flag=True,
              help="Also find the periodic orbits over the range, continue them, and draw "
                   "the branches over the diagram (stable solid, unstable dashed); writes "
                   "branches.json. Parameters: b, amplitude, frequency, r, m1, m2, c1, k1, "
                   "mu, theta, r_left, r_right.")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              default=Path("sweep-output"), show_default=True,
              help="Output directory: sweep.parquet, bifurcation.parquet, sweep.json, "
                   f"bifurcation.png (and branches.json). {OUT_DIR_HELP}")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document.")
@handle_errors
def sweep(param, start, stop, n, log, preset_name, fixed, effect, seed, settle, duration,
          noise, scheduler, n_jobs, use_model, model, overlay, out, as_json):
    """Sweep a parameter: table of regimes and a bifurcation diagram.

    Every point is simulated, recorded through the sensor model, analysed from the
    sensor data and labelled with its true regime; the bifurcation diagram plots the
    impact time differences (over the forcing period) against the parameter.
    """
    import time

    from ..sweep import sweep as run_sweep
    from ..sweep import write_sweep

    out = check_out_dir(out)               # before the sweep, not after it
    base = _base_params(preset_name, fixed)
    values = _sweep_values(start, stop, n, log)
    if overlay:
        from ..effects import Effects
        from ..orbits.continuation import with_value

        key = param.rpartition(".")[2]
        if key == "noise":
            raise InputError("--overlay-branches: the sensor noise does not change the "
                             "orbits; sweep a physical parameter or drop the flag")
        with_value(base, Effects.parse(list(effect)), key, float(values[0]))  # checks name
    classify = None
    if model is not None:
        from ..regimes.classifier import load_model

        classify = load_model(model)
    elif use_model:
        from ..regimes.classifier import load_default_model

        classify = load_default_model()
    t0 = time.perf_counter()
    df = run_sweep(param, values, base=base, effects=list(effect), seed=seed, settle=settle,
                   duration=duration, noise=noise, scheduler=scheduler, n_jobs=n_jobs,
                   classify=classify, progress=not as_json)
    branches = None
    if overlay:
        from ..orbits.figures import branches_for_sweep

        if not as_json:
            click.echo("continuing periodic orbits over the range ...", err=True)
        branches = branches_for_sweep(base, Effects.parse(list(effect)), key,
                                      float(values[0]), float(values[-1]))
    elapsed = time.perf_counter() - t0
    files = write_sweep(df, out, branches=branches)
    points = df.drop(columns=["dt_T"])
    rows = points.astype(object).where(points.notna(), None).to_dict(orient="records")
    labels = {k: int(v) for k, v in df["label"].value_counts().items()}
    payload = {"param": param, "n": len(df), "seconds": round(elapsed, 3),
               "labels": labels, "rows": rows, "outputs": [str(f) for f in files]}
    counts = ", ".join(f"{k} {v}" for k, v in labels.items())
    human = (f"swept {param} over {len(df)} values from {values[0]:g} to {values[-1]:g} "
             f"in {elapsed:.1f} s\nregimes: {counts}\n")
    if branches is not None:
        payload["branches"] = [{"kind": b.kind, "points": len(b.points),
                                "bifurcations": [x.type for x in b.bifurcations]}
                               for b in branches]
        stable = sum(p.stable for b in branches for p in b.points)
        human += (f"{len(branches)} orbit branches over the range "
                  f"({stable} of {sum(len(b.points) for b in branches)} points stable)\n")
    if classify is not None:
        agree = float((df["label_pred"] == df["label"]).mean())
        payload["label_agreement"] = agree
        human += f"predicted label = true label at {100 * agree:.0f} % of the points\n"
    human += "\n".join(f"  {f}" for f in files)
    emit(as_json, payload, human)
