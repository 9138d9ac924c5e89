"""Parameter sweeps: simulate, record, analyse and label one rig per parameter value.

A sweep is the numerical version of the experimental bifurcation analysis the paper
calls for: one parameter (a :class:`~vidiscover.params.SystemParams` field, an effect
parameter or the sensor noise scale) is stepped over a list of values; at every value
the rig is simulated exactly, recorded through the sensor model, analysed from the
sensor data alone and given its ground-truth regime label (and a predicted label when
a classifier is given). The result is a tidy table (one row per point) and the impact
time differences Delta t_i / T per point, drawn against the parameter as a
bifurcation diagram.

Every point has its own seed, derived from ``(seed, index)`` with
:class:`numpy.random.SeedSequence`, and nothing else random: a serial loop, joblib
processes and a Dask cluster give identical rows.

Examples
--------
>>> df = sweep("b", [0.009, 0.015], settle=3.0, duration=1.0, n_jobs=1, progress=False)
>>> list(df["value"]), bool(df["label"].isin(LABELS).all())
([0.009, 0.015], True)
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .effects import EFFECTS, EXTRA_EFFECTS, Effects
from .errors import InputError
from .params import SystemParams, preset
from .regimes.labels import LABELS

__all__ = ["SweepSpec", "sweep", "sweep_params", "resolve_param", "bifurcation_table",
           "plot_bifurcation", "write_sweep"]

#: Settle time of a sweep point (s). Measured on the paper preset, b = 3-30 mm
#: (28 points): the labels after 10 s equal those after 40 s at every point.
DEFAULT_SETTLE = 10.0
#: Record length of a sweep point (s), the paper's 5.12 s.
DEFAULT_DURATION = 5.12

_PARAM_FIELDS = tuple(f.name for f in dataclasses.fields(SystemParams))


def _numeric_effect_params() -> dict[str, list[tuple[str, str]]]:
    """Bare parameter name -> [(effect, parameter)] over numeric effect parameters."""
    out: dict[str, list[tuple[str, str]]] = {}
    for registry in (EFFECTS, EXTRA_EFFECTS):
        for name, spec in registry.items():
            for key, default in spec.params.items():
                if isinstance(default, (int, float)) and not isinstance(default, bool):
                    out.setdefault(key, []).append((name, key))
    return out


def sweep_params() -> list[str]:
    """Names a sweep accepts: SystemParams fields, ``noise`` and ``EFFECT.PARAM``.

    Bare effect-parameter names (``mu``, ``theta``, ``r_left``...) are accepted too
    when only one effect has a parameter of that name.

    Returns
    -------
    list of str
    """
    effect_params = sorted(f"{e}.{k}" for pairs in _numeric_effect_params().values()
                           for e, k in pairs)
    return [*_PARAM_FIELDS, "noise", *effect_params]


def resolve_param(name: str) -> tuple[str, str | None, str]:
    """Resolve a sweep parameter name.

    Parameters
    ----------
    name : str
        ``b``, ``amplitude``... (a :class:`SystemParams` field), ``noise`` (sensor
        noise scale factor), ``coulomb_friction.mu`` or a unique bare effect
        parameter such as ``mu`` or ``theta``.

    Returns
    -------
    kind : {"params", "noise", "effect"}
    effect : str or None
        Effect name when ``kind == "effect"``.
    key : str
        Field or effect-parameter name.

    Raises
    ------
    InputError
        If the name is unknown, ambiguous or not numeric.
    """
    name = str(name).strip()
    hint = f"sweepable parameters: {', '.join(sweep_params())}"
    if name in _PARAM_FIELDS:
        return "params", None, name
    if name == "noise":
        return "noise", None, "noise"
    effect_params = _numeric_effect_params()
    effect, dot, key = name.partition(".")
    if dot:
        if (effect, key) in [p for pairs in effect_params.values() for p in pairs]:
            return "effect", effect, key
        raise InputError(f"--param {name!r}: not a numeric effect parameter; {hint}")
    pairs = effect_params.get(name, [])
    if len(pairs) == 1:
        return "effect", pairs[0][0], pairs[0][1]
    if len(pairs) > 1:
        options = ", ".join(f"{e}.{k}" for e, k in pairs)
        raise InputError(f"--param {name!r} is ambiguous; use one of {options}")
    raise InputError(f"--param {name!r}: unknown parameter; {hint}")


@dataclass(frozen=True)
class SweepSpec:
    """What a sweep does at every point (an immutable value).

    Parameters
    ----------
    param : str
        Swept parameter (see :func:`resolve_param`).
    values : tuple of float
        Parameter values, one point each, in order.
    base : SystemParams
        Parameters of every point before the swept one is set.
    effects : Effects
        Switched-on effects (a swept effect parameter switches its effect on).
    seed : int
        Master seed; point ``i`` uses ``SeedSequence(seed, spawn_key=(i,))``.
    settle, duration : float
        Simulated time before the record, and record length (s).
    noise : float
        Sensor noise scale factor (overridden when ``param == "noise"``).
    n_boot : int
        Bootstrap resamples of the restitution CIs in :func:`analyze` (0: none).
    threshold : float
        Impact detection threshold of :func:`analyze`.
    """

    param: str
    values: tuple
    base: SystemParams = field(default_factory=lambda: preset("paper"))
    effects: Effects = field(default_factory=Effects)
    seed: int = 0
    settle: float = DEFAULT_SETTLE
    duration: float = DEFAULT_DURATION
    noise: float = 1.0
    n_boot: int = 0
    threshold: float = 5.5

    def __post_init__(self) -> None:
        resolve_param(self.param)
        try:
            values = tuple(float(v) for v in self.values)
        except (TypeError, ValueError):
            raise InputError(f"sweep values must be numbers, were {self.values!r}") from None
        if not values:
            raise InputError("sweep values are empty; give at least one value (--n >= 1)")
        bad = [v for v in values if not math.isfinite(v)]
        if bad:
            raise InputError(f"sweep values must be finite, got {bad[0]!r}")
        object.__setattr__(self, "values", values)
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) \
                or self.seed < 0:
            raise InputError(f"seed must be a non-negative integer, was {self.seed!r}")
        if not (math.isfinite(self.noise) and self.noise >= 0):
            raise InputError(f"noise must be >= 0 (a scale factor), was {self.noise!r}")
        if not (isinstance(self.n_boot, (int, np.integer)) and self.n_boot >= 0):
            raise InputError(f"n_boot must be a non-negative integer, was {self.n_boot!r}")
        if not (isinstance(self.threshold, (int, float)) and math.isfinite(self.threshold)
                and self.threshold > 0):
            raise InputError(f"threshold must be > 0 (matched-filter SNR of the impact "
                             f"detector), was {self.threshold!r}")
        from .simulation.engine import SimOptions  # (the compliant engine stays unloaded)

        SimOptions(settle=self.settle, duration=self.duration)  # validates both
        for v in values:  # fail on a bad value now, not on a worker half-way through
            try:
                self.configure(v)
            except InputError as err:
                raise InputError(f"sweep of {self.param} at {v:g}: {err}") from None

    # Effects holds MappingProxyType (not picklable): ship it to workers as a dict.
    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["effects"] = self.effects.to_dict()
        return state

    def __setstate__(self, state: dict) -> None:
        state = dict(state)
        state["effects"] = Effects.from_dict(state["effects"])
        for key, val in state.items():
            object.__setattr__(self, key, val)

    def configure(self, value: float) -> tuple[SystemParams, Effects, float]:
        """Parameters, effects and noise scale of the point at ``value``."""
        kind, effect, key = resolve_param(self.param)
        params, effects, noise = self.base, self.effects, self.noise
        if kind == "params":
            params = params.replace(**{key: value})
        elif kind == "noise":
            if not value >= 0:
                raise InputError(f"noise must be >= 0 (a scale factor), was {value!r}")
            noise = value
        else:
            current = effects.to_dict().get(effect, {})
            effects = effects.with_effect(effect, **{**current, key: value})
        return params, effects, noise

    def point_seed(self, index: int) -> int:
        """Seed of point ``index`` (sensor noise and bootstrap)."""
        ss = np.random.SeedSequence(int(self.seed), spawn_key=(int(index),))
        return int(ss.generate_state(1, dtype=np.uint32)[0])

    def to_dict(self) -> dict:
        """JSON-ready description."""
        return {"param": self.param, "values": list(self.values), "base": self.base.to_dict(),
                "effects": self.effects.to_dict(), "seed": int(self.seed),
                "settle": self.settle, "duration": self.duration, "noise": self.noise,
                "n_boot": int(self.n_boot), "threshold": self.threshold}


def _label_of(predicted: Any) -> str:
    if isinstance(predicted, (str, np.str_)):
        return str(predicted)
    if isinstance(predicted, dict) and "label" in predicted:
        return str(predicted["label"])
    raise InputError(f"classify must return a label string (or a dict with 'label'), "
                     f"returned {type(predicted).__name__}")


def _run_point(task: tuple[SweepSpec, Callable | None, int]) -> dict:
    """Simulate, record, label and analyse one point (runs on a worker)."""
    # every backend computes the same, explicit feature set
    from .analysis import DetectionOptions, analyze
    from .regimes.features import ALL_FEATURES
    from .workflows import known_pulse, simulate_to_memory

    spec, classify, index = task
    value = spec.values[index]
    params, effects, noise = spec.configure(value)
    seed = spec.point_seed(index)
    rec, truth, result = simulate_to_memory(params, effects, seed=seed, settle=spec.settle,
                                            duration=spec.duration, noise=noise,
                                            name=f"{spec.param}={value:g}")
    regime = truth.regime
    ana = analyze(rec, mu=effects.mu, detection=DetectionOptions(threshold=spec.threshold),
                  n_boot=int(spec.n_boot), seed=seed, features=ALL_FEATURES,
                  pulse=known_pulse(None, effects))   # our own default chain: known
    t = ana.detection.t
    right, left = ana.restitution.right, ana.restitution.left
    row = {
        "index": index, "param": spec.param, "value": value, "seed": seed,
        "label": regime["label"],
        "label_pred": _label_of(classify(ana)) if classify is not None else None,
        "n_impacts_true": truth.impacts.n, "ipc_true": regime["ipc"],
        "phi_true": regime["phi"], "periodic_true": bool(regime["periodic"]),
        "period_true": -1 if regime["period"] is None else int(regime["period"]),
        "r_rms_right": right.rms, "r_rms_left": left.rms,
        "r_n_right": int(right.n), "r_n_left": int(left.n),
        "sim_status": int(result.status),
    }
    for name, val in ana.features.items():
        row[name] = float(val)
    row["dt_T"] = (np.diff(t) / ana.forcing.period).tolist()
    return row


def _is_batch_model(classify) -> bool:
    """True for a regime model that labels a feature table at once (``RegimeModel``)."""
    return (classify is not None and callable(getattr(classify, "decide", None))
            and hasattr(classify, "feature_names"))


def sweep(param: str, values: Sequence[float], *, base: SystemParams | None = None,
          effects: Effects | Sequence[str] = (), seed: int = 0,
          settle: float = DEFAULT_SETTLE, duration: float = DEFAULT_DURATION,
          noise: float = 1.0, n_boot: int = 0, threshold: float = 5.5,
          scheduler: Any = None, n_jobs: int | None = None,
          classify: Callable | None = None, progress: bool = True):
    """Sweep one parameter: one simulated, analysed and labelled rig per value.

    Parameters
    ----------
    param : str
        ``b``, ``amplitude``, ``frequency``, ``r``, ``m2``... (any
        :class:`SystemParams` field), ``noise`` (sensor noise scale), or an effect
        parameter ``EFFECT.PARAM`` (``coulomb_friction.mu``, ``inclination.theta``;
        bare ``mu``/``theta`` work when unambiguous). Values in SI units, theta in deg.
    values : sequence of float
        Parameter values, one point each.
    base : SystemParams, optional
        The other parameters (default ``preset("paper")``).
    effects : Effects or list of str
        Effects switched on at every point (CLI syntax accepted).
    seed : int
        Master seed; each point's seed comes from ``(seed, index)``.
    settle, duration : float
        Simulated settle time and record length (s).
    noise : float
        Sensor noise scale factor.
    n_boot : int
        Bootstrap resamples of the restitution CIs (0: none, the fast default).
    threshold : float
        Impact detection threshold of :func:`vidiscover.analysis.analyze`.
    scheduler : str or distributed.Client, optional
        Run on this Dask cluster (see :func:`vidiscover.scale.parallel_map`).
    n_jobs : int, optional
        joblib processes when no scheduler is given (None: all cores, 1: serial).
    classify : callable, optional
        ``classify(AnalysisResult) -> label`` (a string, or a dict with ``label``);
        must be picklable for parallel runs. Fills ``label_pred``.
    progress : bool
        Show a progress bar.

    Returns
    -------
    pandas.DataFrame
        One row per point, in the order of ``values``: ``index``, ``param``,
        ``value``, ``seed``, ``label`` (ground truth), ``label_pred``,
        ``n_impacts_true``, ``ipc_true``, ``phi_true``, ``periodic_true``,
        ``period_true`` (-1: none), ``r_rms_right``/``left`` and ``r_n_right``/``left``
        (estimated from the sensor data), ``sim_status``, every feature of ``ALL_FEATURES``
        (detected ``n_impacts``, ``impacts_per_cycle``...), and ``dt_T`` (list of
        detected impact time differences over the forcing period).
        ``df.attrs["sweep"]`` holds the spec.

    Raises
    ------
    InputError
        On an unknown parameter or an invalid value (checked before any work).

    Notes
    -----
    Each point starts from the simulator's default initial state (LO at rest, ball
    launched from the centre), so the sweep finds one attractor per value, not the
    hysteresis of a quasi-static up/down sweep. The analysis assumes the point's true
    friction coefficient (0 unless ``coulomb_friction`` is on) and the nominal ``b``.
    The default settle of 10 s was checked on the paper preset: over b = 3-30 mm the
    labels equal those after a 40 s settle.
    """
    import pandas as pd

    from .scale import parallel_map

    fx = effects if isinstance(effects, Effects) else Effects.parse(list(effects))
    spec = SweepSpec(param=param, values=tuple(values),
                     base=base if base is not None else preset("paper"), effects=fx,
                     seed=seed, settle=settle, duration=duration, noise=noise,
                     n_boot=n_boot, threshold=threshold)
    # A regime model labels the whole table in one call in this process (the trees
    # cost ~30 ms per single-row call, ~0.1 ms per row in a batch); any other
    # callable runs per point, in the workers.
    batch = classify if _is_batch_model(classify) else None
    per_point = None if batch is not None else classify
    tasks = [(spec, per_point, i) for i in range(len(spec.values))]
    rows = parallel_map(_run_point, tasks, scheduler=scheduler, n_jobs=n_jobs,
                        progress=progress, desc=f"sweep {param}")
    df = pd.DataFrame(rows)
    if batch is not None and len(df):
        # the labels `classify` gives (the rules' where the model keeps them), not the
        # classifier's alone
        df["label_pred"] = [str(v) for v in batch.decide(df)[0]]
    df.attrs["sweep"] = spec.to_dict()
    return df


def bifurcation_table(df):
    """Long table of the bifurcation diagram: one row per impact time difference.

    Parameters
    ----------
    df : pandas.DataFrame
        A :func:`sweep` result.

    Returns
    -------
    pandas.DataFrame
        Columns ``index``, ``value``, ``label``, ``label_pred``, ``k`` (position in
        the record) and ``dt_T`` (Delta t_k / T).
    """
    import pandas as pd

    counts = np.array([len(d) for d in df["dt_T"]], dtype=int)
    rep = np.repeat(np.arange(len(df)), counts)
    k = np.concatenate([np.arange(c) for c in counts]) if counts.size else np.zeros(0, int)
    dt = np.concatenate([np.asarray(d, float) for d in df["dt_T"]]) if counts.sum() \
        else np.zeros(0)
    return pd.DataFrame({
        "index": df["index"].to_numpy()[rep], "value": df["value"].to_numpy()[rep],
        "label": df["label"].to_numpy()[rep], "label_pred": df["label_pred"].to_numpy()[rep],
        "k": k.astype(np.int64), "dt_T": dt})


_LABEL_COLORS = dict(zip(LABELS, ("0.6", "C0", "C2", "C1", "C4", "C3", "k")))
#: How a swept parameter is drawn: factor applied to its SI value, and its unit.
_AXIS_UNITS = {"b": (1e3, "mm"), "amplitude": (1e3, "mm"), "frequency": (1.0, "Hz"),
               "m1": (1.0, "kg"), "m2": (1.0, "kg"), "c1": (1.0, "N s/m"),
               "k1": (1.0, "N/m"), "theta": (1.0, "deg")}


def axis_scale(param: str) -> tuple[float, str]:
    """Factor and axis label to draw the swept parameter ``param`` with.

    Lengths are drawn in mm (like every other figure), other parameters in their SI
    unit; dimensionless ones (r, mu, noise) carry no unit.

    Examples
    --------
    >>> axis_scale("b")
    (1000.0, 'b (mm)')
    >>> axis_scale("coulomb_friction.mu")
    (1.0, 'coulomb_friction.mu')
    """
    factor, unit = _AXIS_UNITS.get(str(param).rpartition(".")[2], (1.0, ""))
    return factor, f"{param} ({unit})" if unit else str(param)


def plot_bifurcation(df, path: str | Path | None = None, *, branches=None):
    """Bifurcation diagram: Delta t_i / T against the parameter, coloured by label.

    The lower panel shows the ground-truth label of every point (and the predicted
    label, as open markers, when the sweep had a classifier). Lengths are drawn in mm.

    Parameters
    ----------
    df : pandas.DataFrame
        A :func:`sweep` result.
    path : str or Path, optional
        PNG to write.
    branches : list of orbits.Branch or of their ``to_dict()`` documents, optional
        Continued periodic-orbit branches drawn over the diagram (stable solid,
        unstable dashed; see :func:`vidiscover.orbits.figures.overlay_branches`).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .plotting import figure

    param = str(df["param"].iloc[0]) if len(df) else "parameter"
    scale, xlabel = axis_scale(param)
    long = bifurcation_table(df)
    fig, ax = figure(2, 1, sharex=True, figsize=(9, 6.5), height_ratios=(3, 1.3))
    top, bottom = ax[0, 0], ax[1, 0]
    for label in LABELS:
        sel = long["label"] == label
        if sel.any():
            top.scatter(long["value"][sel] * scale, long["dt_T"][sel], s=2, lw=0,
                        color=_LABEL_COLORS[label], label=label, rasterized=True)
    if branches:
        from .orbits.figures import overlay_branches

        overlay_branches(top, branches, color="k", scale=scale, label=False)
        top.plot([], [], "k-", lw=1.2, label="stable orbit")
        top.plot([], [], "k--", lw=1.2, label="unstable orbit")
    top.set_ylabel(r"$\Delta t_i / T$")
    top.set_title(f"Bifurcation diagram: impact time differences vs {param}")
    if len(long) or branches:
        top.legend(loc="upper right", markerscale=4, fontsize=8, ncol=2)
    ypos = {lab: i for i, lab in enumerate(LABELS)}
    colors = [_LABEL_COLORS[lab] for lab in df["label"]]
    bottom.scatter(df["value"] * scale, [ypos[lab] for lab in df["label"]], s=10, c=colors,
                   marker="s", lw=0, label="true")
    if df["label_pred"].notna().any():
        pred = df[df["label_pred"].notna()]
        bottom.scatter(pred["value"] * scale,
                       [ypos.get(lab, -1) + 0.25 for lab in pred["label_pred"]],
                       s=14, facecolors="none", edgecolors="k", lw=0.6, label="predicted")
        bottom.legend(loc="upper right", fontsize=8)
    bottom.set_yticks(range(len(LABELS)), LABELS, fontsize=8)
    bottom.set_ylim(-0.6, len(LABELS) - 0.4)
    bottom.set_xlabel(xlabel)
    bottom.set_ylabel("regime")
    if path is not None:
        fig.savefig(path, dpi=130)
    return fig


def write_sweep(df, out_dir: str | Path, *, branches=None) -> list[Path]:
    """Write a sweep atomically: tables (Parquet), spec (JSON) and the diagram (PNG).

    Files: ``sweep.parquet`` (one row per point, scalar columns), ``bifurcation.parquet``
    (:func:`bifurcation_table`), ``sweep.json`` (spec and label counts) and
    ``bifurcation.png``; with ``branches`` also ``branches.json`` (the continued
    branches, drawn over the diagram). Nothing is written if any step fails.

    Parameters
    ----------
    df : pandas.DataFrame
        A :func:`sweep` result.
    out_dir : str or Path
        Output directory (created; entries of the same names are replaced).
    branches : list of orbits.Branch or of their ``to_dict()`` documents, optional
        Periodic-orbit branches to overlay and save.

    Returns
    -------
    list of Path
        The files written, inside ``out_dir``.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    from ._atomic import atomic_directory, write_json

    out = Path(out_dir)
    names = ["sweep.parquet", "bifurcation.parquet", "sweep.json", "bifurcation.png"]
    docs = None
    if branches is not None:
        docs = [b if isinstance(b, dict) else b.to_dict() for b in branches]
        names.append("branches.json")
    points = df.drop(columns=["dt_T"])
    with atomic_directory(out) as tmp:
        pq.write_table(pa.Table.from_pandas(points, preserve_index=False),
                       tmp / "sweep.parquet")
        pq.write_table(pa.Table.from_pandas(bifurcation_table(df), preserve_index=False),
                       tmp / "bifurcation.parquet")
        write_json(tmp / "sweep.json", {
            "spec": df.attrs.get("sweep", {}), "rows": len(df),
            "labels": {k: int(v) for k, v in df["label"].value_counts().items()}})
        plot_bifurcation(df, tmp / "bifurcation.png", branches=docs)
        if docs is not None:
            write_json(tmp / "branches.json", {"branches": docs})
    return [out / n for n in names]
