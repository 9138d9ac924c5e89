"""Simulated training and test sets for the regime classifier.

A case is a seeded random draw of a realistic rig (:data:`PARAM_RANGES`): clearance,
base amplitude and frequency, mass ratio, restitution per wall, friction,
inclination, sensor noise and sheet resonance. Each case is simulated exactly (short
settle, a 5.12 s record), recorded through the sensor model, analysed (stages 1-4,
a small bootstrap) and turned into one row: the registered features computed from
the recording alone, the ground-truth label of the simulated state
(:func:`vidiscover.regimes.labels.label_simulation`) and the drawn parameters.

Rare labels are oversampled by targeted draws: new cases jittered around the
parameters of cases that already showed the label (and, for ``smr``, draws from
the near-resonant box where it lives), each with its own fresh seed.

Every case derives all its randomness from its own seed, so a set is the same
whether it is built serially, on joblib processes or on a Dask cluster.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, replace

import numpy as np
import pandas as pd

from ..errors import InputError
from .labels import LABELS

__all__ = ["PARAM_RANGES", "Case", "draw_cases", "simulate_case", "generate",
           "feature_context", "M1"]

#: LO mass of every drawn rig (kg, the paper's); the ball mass follows the mass ratio.
M1 = 4.168

#: Ranges of the random draws (SI units; theta in degrees; noise a scale factor of
#: the default sensor noise). The mass ratio is m2 / m1.
PARAM_RANGES: Mapping[str, tuple[float, float]] = {
    "b": (0.003, 0.030),
    "amplitude": (0.2e-3, 1.0e-3),
    "frequency": (6.0, 10.0),
    "mass_ratio": (0.003, 0.04),
    "r_right": (0.2, 0.95),
    "r_left": (0.2, 0.95),
    "mu": (0.0, 0.3),
    "theta": (0.0, 2.0),
    "noise": (0.5, 3.0),
    "f_s": (120.0, 400.0),
    "zeta_s": (0.01, 0.05),
}

#: Boxes of targeted draws for labels that random draws rarely hit (subset of the
#: keys of :data:`PARAM_RANGES`; the others are drawn over their full range).
TARGET_BOXES: Mapping[str, Mapping[str, tuple[float, float]]] = {
    "smr": {"b": (0.010, 0.020), "amplitude": (0.2e-3, 0.4e-3), "frequency": (8.3, 8.65),
            "mass_ratio": (0.019, 0.038)},
}

_LOG_SCALE = ("b", "mass_ratio")
_SETTLE, _DURATION, _N_BOOT = 12.0, 5.12, 20


@dataclass(frozen=True)
class Case:
    """One simulated rig: parameters, effects and seed.

    Parameters
    ----------
    seed : int
        Seed of the sensor noise and of the bootstrap.
    b, amplitude, frequency, mass_ratio : float
        Half-clearance (m), base amplitude (m), frequency (Hz), m2 / m1.
    r_right, r_left : float
        Restitution of each wall.
    mu, theta : float
        Coulomb friction coefficient and inclination (deg).
    noise : float
        Sensor-noise scale factor.
    f_s, zeta_s : float
        Sheet resonance (Hz, damping ratio); ``f_s = 0`` switches it off.
    origin : str
        "random", or "target:LABEL" for a targeted draw.
    settle, duration : float
        Simulated settling time and record length (s).
    """

    seed: int
    b: float
    amplitude: float
    frequency: float
    mass_ratio: float
    r_right: float
    r_left: float
    mu: float = 0.0
    theta: float = 0.0
    noise: float = 1.0
    f_s: float = 0.0
    zeta_s: float = 0.02
    origin: str = "random"
    settle: float = _SETTLE
    duration: float = _DURATION

    def params(self):
        """:class:`~vidiscover.params.SystemParams` of the rig."""
        from ..params import preset

        return preset("paper", b=self.b, amplitude=self.amplitude, frequency=self.frequency,
                      m1=M1, m2=self.mass_ratio * M1, r=self.r_right)

    def effects(self):
        """:class:`~vidiscover.effects.Effects` switched on for the rig."""
        from ..effects import Effects

        items = [f"asymmetric_restitution={self.r_right!r},{self.r_left!r}"]
        if self.mu > 0:
            items.append(f"coulomb_friction={self.mu!r}")
        if self.theta != 0:
            items.append(f"inclination={self.theta!r}")
        if self.f_s > 0:
            items.append(f"sensor_resonance={self.f_s!r},{self.zeta_s!r}")
        return Effects.parse(items)

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return asdict(self)


def _uniform(rng, name, box=None):
    lo, hi = (box or PARAM_RANGES)[name]
    if name in _LOG_SCALE:
        return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
    return float(rng.uniform(lo, hi))


def _random_case(rng, box: Mapping[str, tuple[float, float]] | None = None,
                 origin: str = "random") -> Case:
    box = dict(box or {})
    vals = {k: _uniform(rng, k, box if k in box else None)
            for k in ("b", "amplitude", "frequency", "mass_ratio", "r_right", "r_left")}
    mu = _uniform(rng, "mu") if rng.random() < 0.5 else 0.0
    theta = _uniform(rng, "theta") if rng.random() < 0.5 else 0.0
    noise = _uniform(rng, "noise")
    on = rng.random() < 0.5
    f_s = _uniform(rng, "f_s") if on else 0.0
    zeta_s = _uniform(rng, "zeta_s") if on else 0.02
    return Case(seed=int(rng.integers(2**31 - 1)), mu=mu, theta=theta, noise=noise,
                f_s=f_s, zeta_s=zeta_s, origin=origin, **vals)


def _jitter(rng, case: Case, label: str, scale: float = 0.05) -> Case:
    """A new case near ``case``, with a fresh seed and fresh sensors.

    Each drawn parameter moves by ``scale`` of its range (log range for b and the
    mass ratio), clipped to the range.
    """
    new = {}
    for k in ("b", "amplitude", "frequency", "mass_ratio", "r_right", "r_left", "mu",
              "theta"):
        lo, hi = PARAM_RANGES[k]
        v = getattr(case, k)
        if k in ("mu", "theta") and v == 0:
            new[k] = 0.0
            continue
        if k in _LOG_SCALE:
            v = math.exp(math.log(v) + rng.normal(0, scale) * math.log(hi / lo))
        else:
            v = v + rng.normal(0, scale) * (hi - lo)
        new[k] = float(min(max(v, lo), hi))
    on = rng.random() < 0.5
    return replace(case, seed=int(rng.integers(2**31 - 1)), noise=_uniform(rng, "noise"),
                   f_s=_uniform(rng, "f_s") if on else 0.0,
                   zeta_s=_uniform(rng, "zeta_s") if on else 0.02,
                   origin=f"target:{label}", **new)


def draw_cases(n: int, seed: int) -> list[Case]:
    """``n`` random cases over :data:`PARAM_RANGES` from ``seed``.

    Examples
    --------
    >>> a, b = draw_cases(3, seed=1), draw_cases(3, seed=1)
    >>> a == b, 0.003 <= a[0].b <= 0.03
    (True, True)
    """
    rng = np.random.default_rng(seed)
    return [_random_case(rng) for _ in range(n)]


def feature_context(analysis):
    """Rebuild the feature context of an analysis.

    Returns the :class:`~vidiscover.analysis.returnmap.FeatureContext` of an
    :class:`~vidiscover.analysis.AnalysisResult`, to compute features registered
    after it was made.
    """
    from ..analysis.returnmap import FeatureContext

    det = analysis.detection
    return FeatureContext(t=det.t, side=det.side, dv=det.dv, t_start=float(det.t0),
                          t_end=float(det.t0) + det.n_samples / det.sample_rate,
                          forcing=analysis.forcing, ts=analysis.reconstruction.t,
                          x=analysis.reconstruction.x, returnmap=analysis.returnmap)


def simulate_case(case: Case) -> dict:
    """Simulate, record, label and analyse one case; return its row.

    Returns
    -------
    dict
        ``label`` (ground truth), ``truth_*`` (the quantities behind it), the drawn
        parameters, ``status`` ("ok" or the reason the case was dropped) and
        ``feature:NAME`` for every registered feature.
    """
    from ..analysis import analyze
    from ..analysis.returnmap import compute_features
    from ..workflows import known_pulse, simulate_to_memory
    from .features import ALL_FEATURES

    row = {f"param:{k}": v for k, v in case.to_dict().items()}
    try:
        rec, truth, res = simulate_to_memory(case.params(), case.effects(), seed=case.seed,
                                             settle=case.settle, duration=case.duration,
                                             noise=case.noise)
        out = analyze(rec, n_boot=_N_BOOT, seed=case.seed,
                      pulse=known_pulse(None, case.effects()))
    except InputError as err:
        row.update(label=None, status=f"error: {err}")
        return row
    feats = dict(out.features)
    missing = [n for n in ALL_FEATURES if n not in feats]
    if missing:
        feats.update(compute_features(feature_context(out), missing))
    row.update(label=truth.label, status="ok" if res.status == 0 else f"sim: {res.message}")
    row.update({f"truth:{k}": v for k, v in truth.regime.items() if k != "label"})
    row.update({f"feature:{k}": v for k, v in feats.items()})
    return row


def _run(cases, n_jobs, scheduler, progress, desc):
    from ..scale import parallel_map

    return parallel_map(simulate_case, cases, scheduler=scheduler, n_jobs=n_jobs,
                        progress=progress, desc=desc)


def generate(n: int, seed: int, *, min_per_label: int | None = None, rounds: int = 3,
             n_jobs: int | None = 1, scheduler=None, progress: bool = False) -> pd.DataFrame:
    """Simulate a labelled set: ``n`` random cases, then targeted draws for rare labels.

    Parameters
    ----------
    n : int
        Random cases.
    seed : int
        Master seed (draws and per-case seeds derive from it).
    min_per_label : int, optional
        Wanted cases per label (default ``max(4, n // 20)``); labels below it get
        targeted draws (at most ``2 * min_per_label`` per label and
        ``max(8, n // 4)`` in all per round).
    rounds : int
        Rounds of targeted draws.
    n_jobs, scheduler, progress
        Passed to :func:`vidiscover.scale.parallel_map`.

    Returns
    -------
    DataFrame
        One row per case that simulated and analysed cleanly (see
        :func:`simulate_case`).
    """
    if not (isinstance(n, (int, np.integer)) and n >= 1):
        raise InputError(f"n (number of cases) must be a positive integer, was {n!r}")
    rng = np.random.default_rng([seed, 1])
    cases = draw_cases(int(n), seed)
    rows = _run(cases, n_jobs, scheduler, progress, "random cases")
    want = max(4, n // 20) if min_per_label is None else int(min_per_label)
    cap = max(8, n // 4)
    for _ in range(rounds):
        extra: list[Case] = []
        for lab in LABELS:
            have = [r for r in rows if r["status"] == "ok" and r["label"] == lab]
            short = want - len(have)
            if short <= 0 or not (have or lab in TARGET_BOXES):
                continue
            k = min(2 * short, 2 * want, cap - len(extra))
            n_box = (k - k // 2 if have else k) if lab in TARGET_BOXES else 0
            extra += [_random_case(rng, TARGET_BOXES[lab], f"target:{lab}")
                      for _ in range(n_box)]
            extra += [_jitter(rng, _case_of(have[i]), lab)
                      for i in rng.integers(len(have), size=k - n_box)] if have else []
        if not extra:
            break
        rows += _run(extra, n_jobs, scheduler, progress, "targeted cases")
    df = pd.DataFrame(rows)
    return df[df["status"] == "ok"].reset_index(drop=True)


def _case_of(row: dict) -> Case:
    return Case(**{k.split(":", 1)[1]: v for k, v in row.items() if k.startswith("param:")})
