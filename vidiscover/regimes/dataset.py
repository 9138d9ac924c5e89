"""Simulated training and test sets for the regime classifier.

A case is a seeded random draw of a realistic rig (:data:`PARAM_RANGES`): clearance,
base amplitude and frequency, mass ratio, restitution per wall, friction,
inclination, sensor noise and sheet resonance. Each case is simulated exactly (short
settle, a 5.12 s record), recorded through the sensor model, analysed (stages 1-4,
a small bootstrap) and turned into one row: the features of
:data:`~vidiscover.regimes.features.ALL_FEATURES` computed from the recording alone,
the ground-truth label of the simulated state
(:func:`vidiscover.regimes.labels.label_simulation`) and the drawn parameters.

Other rigs, contact models and instrument chains (:func:`draw_realism_cases`) are
drawn as the realism corpus draws them (m1 1-10 kg, natural frequency 5-25 Hz, drive
at 0.7-1.2 of it, compliant or exact walls, causal anti-alias filters, other sample
rates, ADC, offsets); training analyses are given the chain's pulse (with the true
contact duration) for speed, while :func:`corpus_set` and :func:`recording_row`
analyse recordings as a user's are, with the pulse learned from the recording.

Rare labels are oversampled by targeted draws: new cases jittered around the
parameters of cases that already showed the label (and, for ``smr``, draws from
the near-resonant box where it lives), each with its own fresh seed.

Every case derives all its randomness from its own seed, so a set is the same
whether it is built serially, on joblib processes or on a Dask cluster.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields, replace

import numpy as np
import pandas as pd

from ..errors import InputError, SimulationError
from .labels import LABELS

__all__ = ["PARAM_RANGES", "Case", "draw_cases", "draw_realism_cases", "simulate_case",
           "generate", "feature_context", "probe_rows", "probe_mismatch", "reproduce_row", "M1",
           "draw_corpus_cases", "corpus_draw_set"]

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

#: Ranges of the rigs of a training set (paper-rig draws and realism draws
#: together): mass ratio m2 / m1, forcing over natural frequency, record length in
#: forcing periods (dimensionless: another rig within them is in domain), and the
#: half-clearance b (m; gravity and contact mechanics do not scale with it). A
#: recording outside them is outside the training domain.
DOMAIN: Mapping[str, tuple[float, float]] = {
    "b": (0.003, 0.030),
    "mass_ratio": (0.003, 0.05),
    "drive_ratio": (0.7, 1.2),
    "record_periods": (30.0, 52.0),
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
        "random" (a draw over :data:`PARAM_RANGES` at the paper's rig), "realism" (a
        rig, contact model and instrument chain drawn as the realism corpus draws
        them), or "target:LABEL" for a targeted draw.
    settle, duration : float
        Simulated settling time and record length (s).
    m1, k1, c1 : float
        LO mass (kg), stiffness (N/m) and damping (N s/m); ``k1 = 0``: the paper's
        stiffness and damping.
    contact : tuple of str
        Compliant walls (``--contact`` syntax, e.g. ``("right=kelvin-voigt:k=3e7,r=0.8",
        "left=...")``); empty: the exact engine with ``r_right`` / ``r_left``.
    sensors : dict or None
        Fields of :class:`vidiscover.sensors.SensorConfig` (the instrument chain);
        None: the default sensors with ``noise``, ``f_s`` and ``zeta_s``.
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
    m1: float = M1
    k1: float = 0.0
    c1: float = 0.0
    contact: tuple = ()
    sensors: dict | None = field(default=None, hash=False)

    def params(self):
        """:class:`~vidiscover.params.SystemParams` of the rig."""
        from ..params import SystemParams, preset

        if self.k1 > 0:
            return SystemParams(m1=self.m1, c1=self.c1, k1=self.k1, m2=self.mass_ratio * self.m1,
                                b=self.b, amplitude=self.amplitude, frequency=self.frequency,
                                r=self.r_right)
        return preset("paper", b=self.b, amplitude=self.amplitude, frequency=self.frequency,
                      m1=M1, m2=self.mass_ratio * M1, r=self.r_right)

    def sensor_config(self):
        """The instrument chain (:class:`~vidiscover.sensors.SensorConfig`) or None."""
        from ..sensors import SensorConfig

        return SensorConfig(**self.sensors) if self.sensors else None

    def contact_model(self):
        """The compliant walls, or None for the exact engine."""
        from ..simulation.contact import ContactModel

        return ContactModel.parse(list(self.contact)) if self.contact else None

    def effects(self):
        """:class:`~vidiscover.effects.Effects` switched on for the rig."""
        from ..effects import Effects

        items = [] if self.contact else [
            f"asymmetric_restitution={self.r_right!r},{self.r_left!r}"]
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
    rig = case.k1 > 0
    for k in ("b", "amplitude", "frequency", "mass_ratio", "r_right", "r_left", "mu",
              "theta"):
        lo, hi = PARAM_RANGES[k]
        v = getattr(case, k)
        if k in ("mu", "theta") and v == 0:
            new[k] = 0.0
            continue
        if rig and k in ("amplitude", "frequency", "mass_ratio"):
            # another rig: keep its masses and frequency, move the base amplitude
            # in proportion (the ranges of the paper's rig do not apply)
            new[k] = v * math.exp(rng.normal(0, scale)) if k == "amplitude" else v
            continue
        if k in _LOG_SCALE:
            v = math.exp(math.log(v) + rng.normal(0, scale) * math.log(hi / lo))
        else:
            v = v + rng.normal(0, scale) * (hi - lo)
        new[k] = float(min(max(v, lo), hi))
    on = rng.random() < 0.5 and case.sensors is None
    return replace(case, seed=int(rng.integers(2**31 - 1)), noise=_uniform(rng, "noise"),
                   f_s=_uniform(rng, "f_s") if on else 0.0,
                   zeta_s=_uniform(rng, "zeta_s") if on else 0.02,
                   origin=f"target:{label}", **new)


def _realism_draw(rng, compliant: bool) -> Case:
    """A rig and instrument chain drawn as the realism corpus draws them.

    With ``compliant`` the walls are the drawn compliant contacts; otherwise the
    exact engine with restitutions drawn over :data:`PARAM_RANGES`.
    """
    from ..corpus import draw_realism_case

    rc = draw_realism_case(rng, "train", 0)
    r_right, r_left = _uniform(rng, "r_right"), _uniform(rng, "r_left")
    return Case(seed=rc.seed, b=rc.b, amplitude=rc.amplitude, frequency=rc.frequency,
                mass_ratio=rc.m2 / rc.m1, r_right=r_right, r_left=r_left, mu=rc.mu,
                theta=rc.theta, noise=1.0, f_s=0.0, origin="realism", settle=rc.settle,
                duration=rc.duration, m1=rc.m1, k1=rc.k1, c1=rc.c1,
                contact=tuple(rc.contact) if compliant else (), sensors=dict(rc.sensors))


def draw_realism_cases(n: int, seed: int, compliant_share: float = 0.5) -> list[Case]:
    """``n`` cases of other rigs, contact models and instrument chains from ``seed``.

    A share ``compliant_share`` of them has compliant walls (the compliant-contact
    engine), the others the exact engine; every one its own drawn instrument chain.
    """
    rng = np.random.default_rng([seed, 2])
    return [_realism_draw(rng, rng.random() < compliant_share) for _ in range(n)]


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
    :class:`~vidiscover.analysis.AnalysisResult`, to compute another feature set on
    it (``compute_features(feature_context(analysis), features)``).
    """
    from ..analysis.returnmap import FeatureContext

    return FeatureContext.of(analysis.detection, analysis.forcing, analysis.reconstruction,
                             analysis.returnmap, analysis.recording)


def simulate_case(case: Case) -> dict:
    """Simulate, record, label and analyse one case; return its row.

    Returns
    -------
    dict
        ``label`` (ground truth), ``truth_*`` (the quantities behind it), the drawn
        parameters, ``status`` ("ok" or the reason the case was dropped) and
        ``feature:NAME`` for every feature of
        :data:`~vidiscover.regimes.features.ALL_FEATURES`.
    """
    from ..analysis import analyze
    from ..workflows import known_pulse, simulate_to_memory
    from .features import ALL_FEATURES

    row = {f"param:{k}": v for k, v in case.to_dict().items()}
    try:
        sensors = case.sensor_config()
        rec, truth, res = simulate_to_memory(case.params(), case.effects(), seed=case.seed,
                                             settle=case.settle, duration=case.duration,
                                             noise=case.noise, sensors=sensors,
                                             contact=case.contact_model())
        pulse = known_pulse(sensors, case.effects()) if not case.contact else None
        if pulse is None:
            pulse = _training_pulse(sensors, truth)
        out = analyze(rec, n_boot=_N_BOOT, seed=case.seed, pulse=pulse, features=ALL_FEATURES)
    except (InputError, SimulationError) as err:
        # (a drawn compliant case the integrator gives up on is dropped, not fatal: it
        # stopped a whole generate on seed 12005)
        row.update(label=None, status=f"error: {err}")
        return row
    feats = out.features
    row.update(label=truth.label, status="ok" if res.status == 0 else f"sim: {res.message}")
    row.update({f"truth:{k}": v for k, v in truth.regime.items() if k != "label"})
    row.update({f"feature:{k}": v for k, v in feats.items()})
    return row


def _training_pulse(sensors, truth):
    """The instrument's pulse for a training recording, told rather than learned.

    Learning the pulse from every training recording would take seconds each; the
    training sets are given the acquisition chain's pulse with the median true
    contact duration and the mounted resonance (an approximation of a compliant
    contact's shape). Held-out sets are analysed as a user's recording is: the pulse
    learned from the recording.
    """
    from dataclasses import replace as dc_replace

    from ..sensors import SensorConfig
    from ..workflows import known_pulse

    sensors = sensors if sensors is not None else SensorConfig()
    base = known_pulse(dc_replace(sensors, mount_resonance=None))
    imp = truth.impacts
    dur = np.asarray(imp.t_out, float) - np.asarray(imp.t_in, float)
    tau = float(np.median(dur)) if dur.size else 0.0
    mount = (sensors.mount_resonance or 0.0) / sensors.sample_rate
    kw = {"tau": tau}
    if mount and base.kind != "linear-phase":
        kw.update(mount=mount, mount_zeta=sensors.mount_zeta)
    return dc_replace(base, **kw)


def _run(cases, n_jobs, scheduler, progress, desc):
    from ..scale import parallel_map

    return parallel_map(simulate_case, cases, scheduler=scheduler, n_jobs=n_jobs,
                        progress=progress, desc=desc)


def generate(n: int, seed: int, *, n_realism: int = 0, min_per_label: int | None = None,
             rounds: int = 3, n_jobs: int | None = 1, scheduler=None, progress: bool = False
             ) -> pd.DataFrame:
    """Simulate a labelled set: ``n`` random cases, then targeted draws for rare labels.

    Parameters
    ----------
    n : int
        Random cases at the paper's rig (exact engine, default sensors).
    seed : int
        Master seed (draws and per-case seeds derive from it).
    n_realism : int
        Random cases of other rigs, compliant or exact walls and drawn instrument
        chains (:func:`draw_realism_cases`).
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
    if not (isinstance(n, (int, np.integer)) and n >= 0 and n + n_realism >= 1):
        raise InputError(f"n (number of cases) must be a positive integer, was {n!r}")
    rng = np.random.default_rng([seed, 1])
    cases = draw_cases(int(n), seed) + draw_realism_cases(int(n_realism), seed)
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


#: Training rows a model keeps in its metadata (:func:`probe_rows`), per origin: the
#: first rows of the paper rig's random draw, of the other rigs and of the corpus.
PROBE_PER_ORIGIN: Mapping[str, int] = {"random": 8, "realism": 4, "corpus_dev": 2,
                                        "corpus_draw": 1}
#: Labels of probe rows: periodic or impact-free motions (a chaotic row's features
#: differ at the rounding level between machines whose libm rounds the last bit
#: differently; so does a periodic row with a neighbouring attractor, which
#: :func:`probe_rows` tries and leaves out).
PROBE_LABELS = ("no_impact", "1ipc", "2ipc_sym", "2ipc_asym", "multi_ipc")
#: Tolerance within which a recomputed probe row must match its kept features.
PROBE_RTOL, PROBE_ATOL = 1e-7, 1e-12
#: Candidates tried per kept probe row before an origin is left with fewer.
PROBE_TRIES = 4


def probe_rows(data: pd.DataFrame) -> list[dict]:
    """A few training rows, to check later that ``train --seed`` still reproduces them.

    The simulator, the sensor model and the analysis make the training set; a change
    to any of them changes the rows, and a model trained on the old rows no longer
    comes out of its own command. The rows kept here (:data:`PROBE_PER_ORIGIN`,
    labels :data:`PROBE_LABELS`) are recomputed by :func:`reproduce_row` in the test
    suite, which then says that the shipped model must be retrained.

    Returns
    -------
    list of dict
        ``origin``, ``name``, ``params`` (the ``param:`` columns), ``label`` and
        ``features`` (the ``feature:`` columns) of each kept row.
    """
    origin = (data["param:origin"].astype(str) if "param:origin" in data
              else pd.Series("random", index=data.index))
    out = []
    for kind, k in PROBE_PER_ORIGIN.items():
        rows = data[(origin == kind) & data["label"].isin(PROBE_LABELS)]
        kept = 0
        for _, row in rows.head(PROBE_TRIES * k).iterrows():
            probe = {
                "origin": kind,
                "name": row["name"] if isinstance(row.get("name"), str) else "",
                "params": {c.split(":", 1)[1]: row[c] for c in data.columns
                           if c.startswith("param:") and not _missing(row[c])},
                "label": str(row["label"]),
                "features": {c.split(":", 1)[1]: float(row[c]) for c in data.columns
                             if c.startswith("feature:")}}
            if probe_mismatch(probe, reproduce_row(probe, nudge=True)) is None:
                out.append(probe)
                kept += 1
                if kept == k:
                    break
    return out


def probe_mismatch(probe: Mapping, row: Mapping) -> str | None:
    """Why a recomputed ``row`` differs from the ``probe`` it should reproduce, or None.

    Features must agree within :data:`PROBE_RTOL` / :data:`PROBE_ATOL` (last-bit libm
    differences between CPUs), the label exactly.
    """
    if row.get("status") != "ok" or row.get("label") != probe["label"]:
        return f"status {row.get('status')!r}, label {row.get('label')!r} vs {probe['label']!r}"
    for name, want in probe["features"].items():
        got = float(row[f"feature:{name}"])
        want = math.nan if want is None else float(want)       # NaN is null in JSON
        if math.isnan(want) != math.isnan(got) or (
                not math.isnan(want)
                and abs(got - want) > PROBE_ATOL + PROBE_RTOL * abs(want)):
            return f"feature {name}: {got!r} vs {want!r}"
    return None


def _missing(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


def reproduce_row(probe: Mapping, *, nudge: bool = False) -> dict:
    """Recompute the training row a :func:`probe_rows` entry was taken from.

    With ``nudge``, the drive amplitude moves up by one unit in the last place: a row
    that then changes (a motion with a neighbouring attractor, a detection on a
    threshold's edge) would change between CPUs too, and is not kept as a probe.
    """
    def nudged(case):
        return replace(case, amplitude=float(np.nextafter(case.amplitude, np.inf))) \
            if nudge else case

    if probe["origin"] == "corpus_dev":
        from ..corpus import realism_case

        split, index = probe["name"].rsplit("-", 1)
        return _corpus_row(nudged(realism_case(split, int(index))))
    if probe["origin"] == "corpus_draw":
        from ..corpus import draw_realism_case

        split, index = probe["name"].rsplit("-", 1)     # draw{seed}-{index}
        rng = np.random.default_rng([int(split[len("draw"):]), 3, int(index)])
        return _corpus_row(nudged(draw_realism_case(rng, split, int(index))))
    names = {f.name for f in fields(Case)}
    params = {k: _tuples(v) for k, v in probe["params"].items() if k in names}
    params["seed"] = int(params["seed"])        # a float in a table with missing values
    return simulate_case(nudged(Case(**params)))


def _tuples(v):
    """JSON's lists back to the tuples they were (a case's walls, a chain's fields)."""
    if isinstance(v, list):
        return tuple(_tuples(x) for x in v)
    if isinstance(v, dict):
        return {k: _tuples(x) for k, x in v.items()}
    return v


def _case_of(row: dict) -> Case:
    return Case(**{k.split(":", 1)[1]: v for k, v in row.items() if k.startswith("param:")})


def recording_row(rec, label: str | None, name: str = "") -> dict:
    """Analyse a recording as a user's (the pulse learned from it) into a labelled row.

    Returns
    -------
    dict
        ``name``, ``label`` (the given truth), ``status`` and ``feature:NAME`` for
        every feature of :data:`~vidiscover.regimes.features.ALL_FEATURES`.
    """
    from ..analysis import analyze
    from .features import ALL_FEATURES

    row = {"name": name or rec.name, "label": label}
    try:
        out = analyze(rec, n_boot=0, features=ALL_FEATURES)
    except InputError as err:
        row.update(status=f"error: {err}")
        return row
    feats = out.features
    row.update(status="ok", **{f"feature:{k}": v for k, v in feats.items()})
    return row


def _corpus_row(case) -> dict:
    sim = case.simulate()
    row = recording_row(sim.recording, sim.truth.label, case.name)
    row.update({"param:m1": case.m1, "param:frequency": case.frequency,
                "param:b": case.b, "param:compliant": True,
                "param:anti_alias": case.sensors.get("anti_alias"),
                "param:sample_rate": case.sensors.get("sample_rate")})
    return row


def draw_corpus_cases(n: int, seed: int) -> list:
    """``n`` recordings drawn as the realism corpus draws them, from ``seed``.

    Case ``i`` is a pure function of ``(seed, i)`` (its draws come from
    ``numpy.random.default_rng([seed, 3, i])``), named ``draw{seed}-{i:03d}``; none is
    a case of the corpus's fixed splits. Training adds them to the corpus's ``dev``
    split when it wants more recordings analysed as a user's than that split holds.
    """
    from ..corpus import draw_realism_case

    return [draw_realism_case(np.random.default_rng([seed, 3, i]), f"draw{seed}", i)
            for i in range(int(n))]


def corpus_draw_set(n: int, seed: int, *, n_jobs: int | None = 1, scheduler=None,
                    progress: bool = False) -> pd.DataFrame:
    """:func:`draw_corpus_cases` analysed as a user would (the pulse learned)."""
    from ..scale import parallel_map

    rows = parallel_map(_corpus_row, draw_corpus_cases(n, seed), scheduler=scheduler,
                        n_jobs=n_jobs, progress=progress, desc=f"corpus draws {seed}")
    df = pd.DataFrame(rows)
    return df[df["status"] == "ok"].reset_index(drop=True)


def corpus_set(split: str = "test", n: int | None = None, *, n_jobs: int | None = 1,
               scheduler=None, progress: bool = False) -> pd.DataFrame:
    """The realism corpus split ``split`` (first ``n`` cases) analysed as a user would.

    Every case (compliant walls, other rigs, drawn instrument chains; see
    :mod:`vidiscover.corpus`) is simulated, labelled from its true motion and
    analysed with the pulse learned from the recording.
    """
    from ..corpus import realism_corpus
    from ..scale import parallel_map

    rows = parallel_map(_corpus_row, realism_corpus(split, n), scheduler=scheduler,
                        n_jobs=n_jobs, progress=progress, desc=f"corpus {split}")
    df = pd.DataFrame(rows)
    return df[df["status"] == "ok"].reset_index(drop=True)
