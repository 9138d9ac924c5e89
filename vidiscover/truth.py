"""Ground truth of a simulated recording: a typed, frozen value.

A simulated recording carries what the sensors could not see: the true impacts
(with their restitution coefficient and LO velocity jump), the sticking phases, the
ball and LO motion, the effects and parameters used and, once labelled, the regime.
:class:`GroundTruth` holds it; :meth:`GroundTruth.to_dict` is the JSON content of
``rec.truth.json`` (the README's 'Recording format') and :meth:`GroundTruth.from_dict` reads it
back, including files written before the keys ``contact``, ``t_in``, ``t_out``,
``v_in`` and ``v_out`` existed.

This module is a shared value: it imports only numpy, the standard library and the
other shared values, so the analysis may take a :class:`GroundTruth` without
importing the simulator.

Examples
--------
>>> import numpy as np
>>> from vidiscover.effects import Effects
>>> from vidiscover.params import preset
>>> imp = TrueImpacts.from_columns(t=[0.1, 0.2], side=["right", "left"],
...                                u_minus=[0.5, -0.4], u_plus=[-0.44, 0.08], r=[0.88, 0.2])
>>> mot = TrueMotion(t0=0.0, dt=0.5, x=np.zeros(3), xd=np.zeros(3), y=np.zeros(3),
...                  yd=np.zeros(3))
>>> gt = GroundTruth(params=preset("paper", b=0.009), effects=Effects(), b_true=0.009,
...                  settle=20.0, duration=1.0, seed=0, sensors={}, impacts=imp,
...                  motion=mot)
>>> gt.impacts.n, gt.impacts.window(0.15, 1.0).side.tolist(), gt.label
(2, ['left'], None)
>>> gt = gt.with_regime({"label": "2ipc_asym", "ipc": 2.0})
>>> back = GroundTruth.from_dict(gt.to_dict())
>>> back.label, back.impacts.t_out.tolist(), back == gt
('2ipc_asym', [0.1, 0.2], True)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from .effects import Effects
from .errors import InputError
from .params import SystemParams

__all__ = ["GroundTruth", "TrueImpacts", "TrueMotion", "StickPhase", "TRUTH_VERSION"]

#: Version written in ``rec.truth.json``.
TRUTH_VERSION = 1

_SIDES = ("right", "left")
#: Float columns of :class:`TrueImpacts` that every truth file has (besides ``t``).
_FLOATS = ("u_minus", "u_plus", "r", "v_minus", "v_plus", "w_minus", "w_plus", "x", "dv")
#: Per-impact JSON keys, in file order (``t_in``... first, as the simulators write them).
_RECORD_KEYS = ("t", "t_in", "t_out", "v_in", "v_out", "side", "u_minus", "u_plus", "r",
                "v_minus", "v_plus", "w_minus", "w_plus", "x", "stuck", "dv")


def _frozen(values, dtype, name: str) -> np.ndarray:
    """A read-only 1-D copy of ``values`` (the caller's array is left untouched)."""
    try:
        arr = np.array(values, dtype=dtype)
    except (TypeError, ValueError):
        raise InputError(f"ground truth: {name} must be a list of numbers") from None
    if arr.ndim != 1:
        raise InputError(f"ground truth: {name} must be 1-D, has shape {arr.shape}")
    arr.setflags(write=False)
    return arr


def _arrays_equal(a, b, names) -> bool:
    return all(np.array_equal(getattr(a, n), getattr(b, n),
                              equal_nan=getattr(a, n).dtype.kind == "f") for n in names)


@dataclass(frozen=True, eq=False)
class TrueImpacts:
    """True impacts of the record window, as columns (times in record time).

    Build it with :meth:`from_columns` (missing contact columns default to the
    instantaneous-impact values), :meth:`from_table` (a simulator's impact table)
    or :meth:`from_records` (the JSON list). Every array is a read-only copy.

    Attributes
    ----------
    t : ndarray
        Impact time (s); the start of the contact for compliant walls.
    t_in, t_out : ndarray
        Start and end of the contact (s); both equal ``t`` for instantaneous impacts.
    side : ndarray of str
        ``"right"`` (z = +b) or ``"left"`` (z = -b).
    u_minus, u_plus : ndarray
        Relative velocity z' before / after (m/s).
    v_in, v_out : ndarray
        Relative velocity at the start / end of the contact (m/s): ``u_minus`` /
        ``u_plus``.
    r : ndarray
        True restitution coefficient.
    v_minus, v_plus : ndarray
        LO velocity before / after (m/s).
    w_minus, w_plus : ndarray
        Ball velocity before / after (m/s).
    x : ndarray
        LO displacement at the impact (m).
    dv : ndarray
        LO velocity jump ``v_plus - v_minus`` (m/s), the accelerometer pulse area.
    stuck : ndarray of bool
        The ball stuck to the wall after this impact.
    """

    t: np.ndarray
    t_in: np.ndarray
    t_out: np.ndarray
    side: np.ndarray
    u_minus: np.ndarray
    u_plus: np.ndarray
    v_in: np.ndarray
    v_out: np.ndarray
    r: np.ndarray
    v_minus: np.ndarray
    v_plus: np.ndarray
    w_minus: np.ndarray
    w_plus: np.ndarray
    x: np.ndarray
    dv: np.ndarray
    stuck: np.ndarray

    def __post_init__(self) -> None:
        n = None
        for f in dataclasses.fields(self):
            kind = str if f.name == "side" else bool if f.name == "stuck" else float
            arr = _frozen(getattr(self, f.name), kind, f"impacts.{f.name}")
            if n is not None and arr.size != n:
                raise InputError(f"ground truth: impacts.{f.name} has {arr.size} values, "
                                 f"impacts.t has {n}; every impact column needs one per impact")
            n = arr.size
            object.__setattr__(self, f.name, arr)
        bad = ~np.isin(self.side, _SIDES)
        if bad.any():
            raise InputError(f"ground truth: impact side must be 'right' or 'left', was "
                             f"{self.side[bad][0]!r}")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TrueImpacts):
            return NotImplemented
        return _arrays_equal(self, other, [f.name for f in dataclasses.fields(self)])

    @classmethod
    def from_columns(cls, t, side, *, t_in=None, t_out=None, u_minus=None, u_plus=None,
                     v_in=None, v_out=None, r=None, v_minus=None, v_plus=None, w_minus=None,
                     w_plus=None, x=None, dv=None, stuck=None) -> TrueImpacts:
        """Build from columns; a missing column takes its default.

        ``t_in`` and ``t_out`` default to ``t``, ``v_in``/``v_out`` to
        ``u_minus``/``u_plus``, ``dv`` to ``v_plus - v_minus``, ``stuck`` to False and
        the other columns to NaN. ``side`` may be strings or +1 (right) / -1 (left).
        """
        t = np.asarray(t, dtype=float)
        side = np.asarray(side)
        if side.dtype.kind in "iuf":
            side = np.where(side > 0, "right", "left")
        nan = np.full(t.shape, np.nan)
        u_minus = nan if u_minus is None else u_minus
        u_plus = nan if u_plus is None else u_plus
        v_minus = nan if v_minus is None else v_minus
        v_plus = nan if v_plus is None else v_plus
        if dv is None:
            dv = np.asarray(v_plus, dtype=float) - np.asarray(v_minus, dtype=float)
        return cls(t=t, t_in=t if t_in is None else t_in, t_out=t if t_out is None else t_out,
                   side=side, u_minus=u_minus, u_plus=u_plus,
                   v_in=u_minus if v_in is None else v_in,
                   v_out=u_plus if v_out is None else v_out,
                   r=nan if r is None else r, v_minus=v_minus, v_plus=v_plus,
                   w_minus=nan if w_minus is None else w_minus,
                   w_plus=nan if w_plus is None else w_plus, x=nan if x is None else x,
                   dv=dv, stuck=np.zeros(t.shape, bool) if stuck is None else stuck)

    @classmethod
    def from_table(cls, table, t_offset: float = 0.0, dv=None) -> TrueImpacts:
        """Build from a simulator's impact table (``ImpactTable``), shifting times.

        Parameters
        ----------
        table : ImpactTable
            Columns ``t``, ``side`` (+1/-1), ``u_minus`` ... ``stuck`` and, when the
            simulator gives it, ``t_out`` (the end of the contact).
        t_offset : float
            Subtracted from the times (the settle time: simulation -> record time).
        dv : ndarray, optional
            LO velocity jumps (default ``v_plus - v_minus``).
        """
        t = table.t - t_offset
        t_out = getattr(table, "t_out", None)
        return cls.from_columns(
            t, table.side, t_out=None if t_out is None else t_out - t_offset,
            u_minus=table.u_minus, u_plus=table.u_plus, r=table.r, v_minus=table.v_minus,
            v_plus=table.v_plus, w_minus=table.w_minus, w_plus=table.w_plus, x=table.x,
            dv=dv, stuck=table.stuck)

    @classmethod
    def from_records(cls, records) -> TrueImpacts:
        """Build from the JSON list of impact dicts (keys ``t``, ``side``, ``r``...).

        Raises
        ------
        InputError
            If it is not a list of objects, or an impact lacks one of the keys every
            truth file has (``t``, ``side``, ``u_minus`` ... ``stuck``, ``dv``).
        """
        if not isinstance(records, list) or not all(isinstance(i, Mapping) for i in records):
            raise InputError("ground truth: 'impacts' must be a list of objects")
        need = ("t", "side", *_FLOATS, "stuck")
        for k, imp in enumerate(records):
            missing = [key for key in need if key not in imp]
            if missing:
                raise InputError(f"ground truth: impact {k} lacks {', '.join(missing)}")
        cols = {key: [i[key] for i in records] for key in need}
        for key in ("t_in", "t_out", "v_in", "v_out"):
            if records and all(key in i for i in records):
                cols[key] = [i[key] for i in records]
        return cls.from_columns(**cols)

    @property
    def n(self) -> int:
        """Number of impacts."""
        return int(self.t.size)

    @property
    def speed(self) -> np.ndarray:
        """Impact speed |z'-| (m/s)."""
        return np.abs(self.u_minus)

    @property
    def sign(self) -> np.ndarray:
        """Sides as +1 (right) / -1 (left)."""
        return np.where(self.side == "right", 1, -1)

    def select(self, mask) -> TrueImpacts:
        """The impacts where ``mask`` (boolean or integer index) selects."""
        return TrueImpacts(**{f.name: getattr(self, f.name)[mask]
                              for f in dataclasses.fields(self)})

    def window(self, t0: float, t1: float) -> TrueImpacts:
        """The impacts with ``t0 <= t <= t1`` (s)."""
        return self.select((self.t >= t0) & (self.t <= t1))

    def to_records(self) -> list[dict]:
        """JSON-ready list of one dict per impact (the ``impacts`` of the truth file)."""
        cols = [getattr(self, key).tolist() for key in _RECORD_KEYS]
        return [dict(zip(_RECORD_KEYS, row)) for row in zip(*cols)]


@dataclass(frozen=True, eq=False)
class TrueMotion:
    """The true LO and ball motion, sampled like the recording.

    Attributes
    ----------
    t0, dt : float
        Time of the first sample and sampling interval (s, record time).
    x, xd : ndarray
        LO displacement (m) and velocity (m/s).
    y, yd : ndarray
        Ball displacement (m) and velocity (m/s).
    """

    t0: float
    dt: float
    x: np.ndarray
    xd: np.ndarray
    y: np.ndarray
    yd: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "t0", float(self.t0))
        object.__setattr__(self, "dt", float(self.dt))
        if not self.dt > 0:
            raise InputError(f"ground truth: motion.dt must be > 0 s, was {self.dt!r}")
        for name in ("x", "xd", "y", "yd"):
            object.__setattr__(self, name, _frozen(getattr(self, name), float,
                                                   f"motion.{name}"))
        if len({self.x.size, self.xd.size, self.y.size, self.yd.size}) != 1:
            raise InputError("ground truth: motion.x, xd, y and yd must have one value "
                             "per sample each")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TrueMotion):
            return NotImplemented
        return (self.t0, self.dt) == (other.t0, other.dt) and _arrays_equal(
            self, other, ("x", "xd", "y", "yd"))

    @property
    def t(self) -> np.ndarray:
        """Sample times (s)."""
        return self.t0 + self.dt * np.arange(self.x.size)

    def to_dict(self) -> dict:
        """JSON-ready form (``t0``, ``dt``, ``x``, ``xd``, ``y``, ``yd``)."""
        return {"t0": self.t0, "dt": self.dt, "x": self.x.tolist(), "xd": self.xd.tolist(),
                "y": self.y.tolist(), "yd": self.yd.tolist()}


class StickPhase(NamedTuple):
    """A phase where the ball moved with the LO.

    ``t_start``, ``t_end`` in record time (s); ``where`` is ``"right"``/``"left"``
    (stuck to a wall) or ``"middle"`` (held by static friction).
    """

    t_start: float
    t_end: float
    where: str


@dataclass(frozen=True)
class GroundTruth:
    """Everything known about a simulated recording that the sensors did not record.

    Attributes
    ----------
    params : SystemParams
        Nominal parameters of the simulation.
    effects : Effects
        Switched-on effects.
    b_true : float
        True half-clearance (m): ``params.b`` plus any ``clearance_error``.
    settle, duration : float
        Simulated time before the record and record length (s).
    seed : int
        Seed of the sensor noise.
    sensors : dict
        The sensor configuration (``SensorConfig.to_dict()``).
    impacts : TrueImpacts
        True impacts inside the record.
    motion : TrueMotion
        True LO and ball motion at the sample times.
    sticking : tuple of StickPhase
        Sticking phases clipped to the record.
    status : int
        Simulator status (0: reached the end).
    message : str
        Simulator message.
    regime : dict or None
        Ground-truth regime (``label`` and the quantities behind it, the
        README's 'Regime labels'); None until labelled (:meth:`with_regime`).
    contact : dict or None
        The compliant-contact model (``{"right": {...}, "left": {...}}``); None for
        the exact engine (instantaneous impacts).
    version : int
        File format version.
    """

    params: SystemParams
    effects: Effects
    b_true: float
    settle: float
    duration: float
    seed: int
    sensors: dict
    impacts: TrueImpacts
    motion: TrueMotion
    sticking: tuple = ()
    status: int = 0
    message: str = ""
    regime: dict | None = None
    contact: dict | None = None
    version: int = TRUTH_VERSION

    def __post_init__(self) -> None:
        if not isinstance(self.impacts, TrueImpacts):
            raise InputError(f"ground truth: impacts must be TrueImpacts, was "
                             f"{type(self.impacts).__name__}")
        if not isinstance(self.motion, TrueMotion):
            raise InputError(f"ground truth: motion must be TrueMotion, was "
                             f"{type(self.motion).__name__}")
        object.__setattr__(self, "sticking", tuple(StickPhase(*s) for s in self.sticking))

    @property
    def label(self) -> str | None:
        """The true regime label, or None before labelling."""
        return None if self.regime is None else self.regime.get("label")

    def with_regime(self, regime) -> GroundTruth:
        """A copy with the regime attached.

        Parameters
        ----------
        regime : Mapping or RegimeTruth
            ``RegimeTruth.to_dict()``, or anything with a ``to_dict()`` giving it.
        """
        data = regime.to_dict() if hasattr(regime, "to_dict") else regime
        if not isinstance(data, Mapping) or "label" not in data:
            raise InputError(f"ground truth: a regime needs a 'label', was {regime!r}")
        return dataclasses.replace(self, regime=dict(data))

    def to_dict(self) -> dict:
        """JSON-ready content of ``rec.truth.json``."""
        return {
            "version": self.version, "params": self.params.to_dict(),
            "effects": self.effects.to_dict(), "b_true": self.b_true,
            "settle": self.settle, "duration": self.duration, "seed": self.seed,
            "sensors": dict(self.sensors), "status": self.status, "message": self.message,
            "impacts": self.impacts.to_records(),
            "sticking": [{"t_start": a, "t_end": b, "where": w} for a, b, w in self.sticking],
            "motion": self.motion.to_dict(),
            "regime": None if self.regime is None else dict(self.regime),
            "contact": self.contact}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> GroundTruth:
        """Read the content of a ``rec.truth.json`` (the inverse of :meth:`to_dict`).

        ``contact``, ``regime`` and ``version`` may be absent (older files), and so
        may the contact keys of the impacts; keys this version does not know are
        ignored.

        Raises
        ------
        InputError
            One line naming the missing or malformed part.
        """
        if not isinstance(data, Mapping):
            raise InputError(f"ground truth must be a JSON object, found "
                             f"{type(data).__name__}")
        need = ("params", "effects", "b_true", "settle", "duration", "seed", "sensors",
                "status", "message", "impacts", "sticking", "motion")
        missing = [k for k in need if k not in data]
        if missing:
            raise InputError(f"ground truth lacks {', '.join(missing)}; write it with "
                             "vidiscover simulate")
        try:
            mot = data["motion"]
            motion = TrueMotion(t0=mot.get("t0", 0.0), dt=mot["dt"], x=mot["x"],
                                xd=mot["xd"], y=mot["y"], yd=mot["yd"])
            sticking = tuple(StickPhase(float(s["t_start"]), float(s["t_end"]),
                                        str(s["where"])) for s in data["sticking"])
            params = SystemParams(**data["params"])
            effects = Effects.from_dict(data["effects"])
            return cls(params=params, effects=effects, b_true=float(data["b_true"]),
                       settle=float(data["settle"]), duration=float(data["duration"]),
                       seed=data["seed"], sensors=dict(data["sensors"]),
                       impacts=TrueImpacts.from_records(data["impacts"]), motion=motion,
                       sticking=sticking, status=int(data["status"]),
                       message=str(data["message"]),
                       regime=None if data.get("regime") is None else dict(data["regime"]),
                       contact=data.get("contact"),
                       version=int(data.get("version", TRUTH_VERSION)))
        except InputError:
            raise
        except (AttributeError, KeyError, TypeError, ValueError) as err:
            raise InputError(f"ground truth is malformed ({type(err).__name__}: {err}); "
                             "write it with vidiscover simulate") from None
