"""``vidiscover orbits`` and ``vidiscover continue``: periodic orbits of the exact model.

``orbits`` finds the periodic impacting orbits at one parameter set (Newton shooting
on the exact impact map, seeded by simulations and by the closed-form symmetric
two-impact orbit) with their Floquet multipliers (JSON keys ``orbits[] {kind,
impacts_per_period, period_cycles, stable, multipliers[], impacts[] {t, side, v}}``;
``v`` is the relative velocity z' just before the impact, m/s; ``t`` the impact time in
[0, p T) of the forcing).

``continue`` follows every orbit found at ``--from`` through ``--param`` to ``--to``
(pseudo-arclength continuation) and writes ``continuation.json``, ``branches.csv`` and
``figures/branches.png`` atomically (JSON keys ``branches[] {kind, points[] {value,
stable, max_multiplier}}``, ``bifurcations[] {type, value}``, ``outputs``).
"""

from __future__ import annotations

from pathlib import Path

import click

from ..cli import OUT_DIR_HELP, _parse_params, check_out_dir, emit, handle_errors
from ..errors import InputError
from ..params import PRESETS

__all__ = ["orbits", "continue_", "run_orbits", "run_continue"]


def _effects(effect):
    from ..effects import Effects

    return Effects.parse(list(effect))


def run_orbits(params, effects, *, max_period: int = 4) -> dict:
    """Orbits at one parameter set as the ``orbits`` JSON document."""
    from ..orbits.find import find_orbits

    if not 1 <= max_period <= 8:
        raise InputError(f"--max-period must be in 1..8 forcing periods, was {max_period!r}")
    found, notes = find_orbits(params, effects, max_period=max_period)
    return {"params": params.to_dict(), "effects": effects.to_dict(),
            "orbits": [o.to_dict() for o in found], "notes": notes,
            "found": bool(found),
            "reason": "" if found else "no periodic impacting orbit found: " + "; ".join(notes)}


def human_orbits(doc: dict) -> str:
    """A few lines per orbit."""
    if not doc["orbits"]:
        return doc["reason"]
    lines = []
    for o in doc["orbits"]:
        mult = ", ".join(f"{m['abs']:.4g}" for m in o["multipliers"])
        lines.append(f"{o['kind']:<10} {o['impacts_per_period']:g} impacts/period over "
                     f"{o['period_cycles']} period(s)  "
                     f"{'stable' if o['stable'] else 'UNSTABLE'}  |multipliers| {mult}")
        for i in o["impacts"]:
            lines.append(f"    t = {i['t']:.6f} s  {i['side']:<5}  z'- = {i['v']:+.4f} m/s")
    if doc["notes"]:
        lines.append("notes: " + "; ".join(doc["notes"]))
    return "\n".join(lines)


_PRESET = click.option("--preset", "preset_name", type=click.Choice(sorted(PRESETS)),
                       default="paper", show_default=True, help="Parameter set.")
_SET = click.option("--set", "fixed", multiple=True, metavar="NAME=VALUE",
                    help="Change a rig parameter, e.g. --set amplitude=0.0004 (repeatable).")
_EFFECT = click.option("--effect", multiple=True, metavar="NAME[=VALUE,...]",
                       help="Switch on an effect, e.g. asymmetric_restitution=0.88,0.7, "
                            "coulomb_friction=0.05, inclination=2 (repeatable).")


@click.command("orbits")
@_PRESET
@click.option("--b", type=float, default=None, help="Half-clearance (m), e.g. 0.012.")
@_SET
@_EFFECT
@click.option("--max-period", type=int, default=4, show_default=True,
              help="Longest orbit period searched, in forcing periods.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document.")
@handle_errors
def orbits(preset_name, b, fixed, effect, max_period, as_json):
    """Periodic impacting orbits of the exact model, with their stability."""
    params = _parse_params(preset_name, b, fixed)
    doc = run_orbits(params, _effects(effect), max_period=max_period)
    emit(as_json, doc, human_orbits(doc))


def run_continue(params, effects, param: str, start: float, stop: float, out: Path, *,
                 max_points: int = 200, figures: bool = True) -> dict:
    """Find the orbits at ``start`` and continue them to ``stop``; write the outputs."""
    import csv
    import io

    from .._atomic import atomic_directory, write_json
    from ..orbits.continuation import continue_orbit, param_value, with_value
    from ..orbits.find import find_orbits

    out = check_out_dir(out)
    param_value(params, effects, param)            # a one-line error for a bad name
    if start == stop:
        raise InputError(f"--from and --to are both {start!r}; give a range")
    if max_points < 2:
        raise InputError(f"--max-points must be >= 2, was {max_points!r}")
    pr, fx = with_value(params, effects, param, start)
    found, notes = find_orbits(pr, fx)
    branches = [continue_orbit(pr, fx, o, param, stop, max_points=max_points) for o in found]
    docs = [b.to_dict() for b in branches]
    bifs = [{**bif, "branch": i, "kind": d["kind"]} for i, d in enumerate(docs)
            for bif in d["bifurcations"]]
    doc = {"param": param, "from": start, "to": stop, "params": pr.to_dict(),
           "effects": fx.to_dict(), "branches": docs, "bifurcations": bifs, "notes": notes,
           "reason": "" if found else "no periodic impacting orbit found at --from: "
                                      + "; ".join(notes)}
    files = ["continuation.json", "branches.csv"]
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["branch", "kind", "value", "stable", "max_multiplier", "t", "x"])
    for i, d in enumerate(docs):
        for p in d["points"]:
            w.writerow([i, d["kind"], repr(p["value"]), p["stable"], repr(p["max_multiplier"]),
                        repr(p["t"]), repr(p["x"])])
    with atomic_directory(out) as tmp:
        (Path(tmp) / "branches.csv").write_text(buf.getvalue(), encoding="utf-8")
        if figures and branches:
            import matplotlib.pyplot as plt

            from ..orbits.figures import plot_branches

            (Path(tmp) / "figures").mkdir()
            fig = plot_branches(branches, Path(tmp) / "figures" / "branches.png", param=param)
            plt.close(fig)
            files.append("figures/branches.png")
        doc["outputs"] = [str(out / f) for f in files]
        write_json(Path(tmp) / "continuation.json", doc)
    return doc


def human_continue(doc: dict) -> str:
    """One line per branch and per bifurcation."""
    if not doc["branches"]:
        return doc["reason"]
    lines = []
    for i, b in enumerate(doc["branches"]):
        vals = [p["value"] for p in b["points"]] or [float("nan")]
        n_st = sum(p["stable"] for p in b["points"])
        lines.append(f"branch {i}: {b['kind']} ({'-'.join(b['sides'])}, p = "
                     f"{b['period_cycles']}), {len(vals)} points, {doc['param']} "
                     f"{min(vals):.6g}..{max(vals):.6g}, {n_st} stable; {b['end_reason']}")
    for bif in doc["bifurcations"]:
        lines.append(f"  {bif['type']:<16} {doc['param']} = {bif['value']:.8g} "
                     f"(branch {bif['branch']}) {bif['detail']}")
    lines += [f"  {f}" for f in doc["outputs"]]
    return "\n".join(lines)


@click.command("continue")
@click.option("--param", required=True, metavar="NAME",
              help="Parameter to follow: b, amplitude, frequency, r, c1, k1, m1, m2, mu, "
                   "theta, r_left, r_right.")
@click.option("--from", "start", type=float, required=True,
              help="Start value (orbits are found there).")
@click.option("--to", "stop", type=float, required=True, help="End value.")
@_PRESET
@click.option("--b", type=float, default=None, help="Half-clearance (m) when --param is not b.")
@_SET
@_EFFECT
@click.option("--max-points", type=int, default=200, show_default=True,
              help="Bound on the points per branch.")
@click.option("--out", type=click.Path(path_type=Path), required=True,
              help="Output directory (continuation.json, branches.csv, figures/). "
                   f"{OUT_DIR_HELP}")
@click.option("--no-figures", is_flag=True, help="Skip the figure.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON document.")
@handle_errors
def continue_(param, start, stop, preset_name, b, fixed, effect, max_points, out, no_figures,
              as_json):
    """Follow orbit branches through a parameter, with their bifurcations.

    Orbits found at --from are continued to --to; folds, period doublings,
    Neimark-Sacker and grazing points are located along the branches.
    """
    params = _parse_params(preset_name, b, fixed)
    doc = run_continue(params, _effects(effect), param, start, stop, out,
                       max_points=max_points, figures=not no_figures)
    emit(as_json, doc, human_continue(doc))
