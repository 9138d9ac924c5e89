"""The effects catalogue: what separates a real rig from the paper's model.

Each effect is registered once (:data:`EFFECTS`) with its parameters, defaults and
validity ranges; the simulator, the sensor model, the CLI parser and the gap
diagnosis all read the same registry. An :class:`Effects` value is the set of
switched-on effects with their parameters.

CLI syntax (``--effect``): ``NAME`` (defaults), ``NAME=VALUE[,VALUE...]``
(positional, in the order of the parameters) or ``NAME=key=value[,key=value...]``.

Examples
--------
>>> fx = Effects.parse(["coulomb_friction=0.3", "asymmetric_restitution=0.88,0.2"])
>>> fx.value("coulomb_friction", "mu"), fx.value("asymmetric_restitution", "r_left")
(0.3, 0.2)
>>> Effects().mu
0.0
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from .errors import InputError
from .restitution_laws import RestitutionLaw

__all__ = ["EffectSpec", "EFFECTS", "EXTRA_EFFECTS", "Effects", "register_effect"]


def _range(lo: float, hi: float, *, lo_open: bool = False) -> Callable[[Any], bool]:
    def check(v: Any) -> bool:
        return isinstance(v, (int, float)) and math.isfinite(v) and (
            (v > lo) if lo_open else (v >= lo)) and v <= hi
    check.__doc__ = f"{'(' if lo_open else '['}{lo}, {hi}]"
    return check


def _law(v: Any) -> bool:
    RestitutionLaw.parse(v)  # raises InputError with its own message
    return True


_law.__doc__ = "a restitution law spec such as 'linear:0.95:0.1' or 'power:0.3:0.5'"


@dataclass(frozen=True)
class EffectSpec:
    """One catalogue entry.

    Parameters
    ----------
    name : str
        Contract name (the README's effects table).
    params : Mapping[str, Any]
        Parameter names with their defaults, in positional order.
    checks : Mapping[str, Callable]
        Validity check per parameter (its docstring states the rule).
    acts_on : {"dynamics", "excitation", "sensor"}
        Which part of the model it changes.
    doc : str
        One-line meaning.
    units : Mapping[str, str]
        Units per parameter, for messages and reports.
    """

    name: str
    params: Mapping[str, Any]
    checks: Mapping[str, Callable[[Any], bool]]
    acts_on: str
    doc: str
    units: Mapping[str, str] = field(default_factory=dict)


#: The catalogue of the README's effects table (names are a contract).
EFFECTS: dict[str, EffectSpec] = {}
#: Effects outside the catalogue: simulated, but never a candidate of the gap diagnosis.
EXTRA_EFFECTS: dict[str, EffectSpec] = {}


def register_effect(spec: EffectSpec, *, catalogue: bool = True) -> EffectSpec:
    """Add ``spec`` to the catalogue (or to :data:`EXTRA_EFFECTS`)."""
    (EFFECTS if catalogue else EXTRA_EFFECTS)[spec.name] = spec
    return spec


_R = _range(0.0, 1.0)
register_effect(EffectSpec(
    "asymmetric_restitution", {"r_right": 0.8782, "r_left": 0.2018},
    {"r_right": _R, "r_left": _R}, "dynamics",
    "the two walls restitute differently", {"r_right": "", "r_left": ""}))
register_effect(EffectSpec(
    "velocity_dependent_restitution",
    {"right": "linear:0.95:0.15", "left": "linear:0.95:0.15"},
    {"right": _law, "left": _law}, "dynamics",
    "r depends on impact speed: per wall 'linear:r0:a' (r0 - a v) or 'power:a:p' (1 - a v^p)"))
register_effect(EffectSpec(
    "coulomb_friction", {"mu": 0.1}, {"mu": _range(0.0, 1.5)}, "dynamics",
    "dry friction between ball and LO", {"mu": ""}))
register_effect(EffectSpec(
    "inclination", {"theta": 1.0}, {"theta": _range(-30.0, 30.0)}, "dynamics",
    "the rig is tilted: constant g sin(theta) on the ball (theta > 0 pulls it right)",
    {"theta": "deg"}))
register_effect(EffectSpec(
    "sensor_resonance", {"f_s": 180.0, "zeta_s": 0.02},
    {"f_s": _range(20.0, 5000.0), "zeta_s": _range(0.0, 0.9, lo_open=True)}, "sensor",
    "the laser reads an aluminium sheet that rings after impacts", {"f_s": "Hz", "zeta_s": ""}))
register_effect(EffectSpec(
    "excitation_distortion", {"h2": 0.05, "phi2": 0.0, "h3": 0.0, "phi3": 0.0},
    {"h2": _range(0.0, 0.5), "phi2": _range(-10.0, 10.0),
     "h3": _range(0.0, 0.5), "phi3": _range(-10.0, 10.0)}, "excitation",
    "the base motion is not a pure sine: 2nd/3rd harmonics (relative amplitude, phase rad)",
    {"h2": "", "phi2": "rad", "h3": "", "phi3": "rad"}))
register_effect(EffectSpec(
    "clearance_error", {"db": 0.0005}, {"db": _range(-0.02, 0.02)}, "dynamics",
    "the true half-clearance is b + db, not the nominal b", {"db": "m"}))
register_effect(EffectSpec(
    "contact_duration", {"tau": 1e-4}, {"tau": _range(0.0, 0.005, lo_open=True)}, "sensor",
    "impacts last a finite time tau (acceleration pulse width)", {"tau": "s"}))
register_effect(EffectSpec(
    "restitution_drift", {"side": "left", "rate": -0.04},
    {"side": lambda v: v in ("left", "right"), "rate": _range(-1.0, 1.0)}, "dynamics",
    "out of the catalogue: one wall's restitution drifts linearly in time (per second)",
    {"rate": "1/s"}), catalogue=False)


def _spec(name: str) -> EffectSpec:
    spec = EFFECTS.get(name) or EXTRA_EFFECTS.get(name)
    if spec is None:
        known = ", ".join(list(EFFECTS) + list(EXTRA_EFFECTS))
        raise InputError(f"unknown effect {name!r}; known effects: {known}")
    return spec


def _coerce(value: Any) -> Any:
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return value.strip()
    return value


@dataclass(frozen=True)
class Effects:
    """A set of switched-on effects with their parameters (an immutable value).

    Parameters
    ----------
    active : Mapping[str, Mapping[str, Any]]
        Effect name -> parameters; missing parameters take the catalogue defaults.
    """

    active: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        resolved = {}
        for name, given in dict(self.active).items():
            spec = _spec(name)
            given = dict(given or {})
            unknown = sorted(set(given) - set(spec.params))
            if unknown:
                raise InputError(f"effect {name}: unknown parameter(s) {', '.join(unknown)}; "
                                 f"its parameters are {', '.join(spec.params)}")
            values = {k: _coerce(given.get(k, d)) for k, d in spec.params.items()}
            for k, v in values.items():
                if not spec.checks[k](v):
                    raise InputError(f"effect {name}: {k} must be in {spec.checks[k].__doc__}, "
                                     f"was {v!r}")
            resolved[name] = MappingProxyType(values)
        object.__setattr__(self, "active", MappingProxyType(resolved))

    # ------------------------------------------------------------------ parsing
    @classmethod
    def parse(cls, items: list[str] | tuple[str, ...]) -> Effects:
        """Build from CLI strings ``NAME``, ``NAME=v1,v2`` or ``NAME=k=v,k=v``."""
        active: dict[str, dict[str, Any]] = {}
        for item in items:
            name, _, rest = str(item).partition("=")
            name = name.strip()
            spec = _spec(name)
            params: dict[str, Any] = {}
            if rest.strip() and rest.strip().lower() != "on":
                parts = [p.strip() for p in rest.split(",")]
                keys = list(spec.params)
                for i, part in enumerate(parts):
                    key, eq, val = part.partition("=")
                    if eq:
                        params[key.strip()] = val
                    elif i < len(keys):
                        params[keys[i]] = part
                    else:
                        raise InputError(f"--effect {item!r}: {name} takes at most {len(keys)} "
                                         f"value(s) ({', '.join(keys)})")
            if name in active:
                raise InputError(f"--effect {name} given twice; give it once with all parameters")
            active[name] = params
        return cls(active)

    @classmethod
    def from_dict(cls, data: Mapping[str, Mapping[str, Any]]) -> Effects:
        """Inverse of :meth:`to_dict`."""
        return cls(dict(data))

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """JSON-ready ``{name: {param: value}}``."""
        return {k: dict(v) for k, v in self.active.items()}

    def __reduce__(self):
        # read-only mapping proxies do not pickle; rebuild from the plain dict so
        # effects travel to joblib and Dask workers
        return (Effects.from_dict, (self.to_dict(),))

    def with_effect(self, name: str, **params: Any) -> Effects:
        """A copy with ``name`` switched on (or its parameters replaced)."""
        active = self.to_dict()
        active[name] = params
        return Effects(active)

    def without(self, name: str) -> Effects:
        """A copy with ``name`` switched off."""
        return Effects({k: v for k, v in self.to_dict().items() if k != name})

    # ------------------------------------------------------------------ queries
    def __contains__(self, name: object) -> bool:
        return name in self.active

    def __bool__(self) -> bool:
        return bool(self.active)

    @property
    def names(self) -> list[str]:
        """Names of the switched-on effects."""
        return list(self.active)

    def value(self, name: str, param: str, default: Any = None) -> Any:
        """Parameter ``param`` of effect ``name``, or ``default`` if it is off."""
        if name not in self.active:
            return default
        return self.active[name][param]

    @property
    def mu(self) -> float:
        """Coulomb friction coefficient (0 when off)."""
        return float(self.value("coulomb_friction", "mu", 0.0))

    @property
    def theta_deg(self) -> float:
        """Inclination (deg, 0 when off)."""
        return float(self.value("inclination", "theta", 0.0))

    @property
    def db(self) -> float:
        """Clearance error (m, 0 when off)."""
        return float(self.value("clearance_error", "db", 0.0))

    @property
    def tau(self) -> float:
        """Contact duration (s, 0 = instantaneous when off)."""
        return float(self.value("contact_duration", "tau", 0.0))

    def harmonics(self) -> list[tuple[int, float, float]]:
        """Base-motion harmonics as (order, relative amplitude, phase rad), order 1 first."""
        out = [(1, 1.0, 0.0)]
        if "excitation_distortion" in self.active:
            p = self.active["excitation_distortion"]
            for n in (2, 3):
                if p[f"h{n}"] > 0:
                    out.append((n, float(p[f"h{n}"]), float(p[f"phi{n}"])))
        return out

    def restitution_laws(self, r_nominal: float) -> dict[str, RestitutionLaw]:
        """Law per side: velocity-dependent > asymmetric > nominal constant."""
        laws = {"right": RestitutionLaw.constant(r_nominal),
                "left": RestitutionLaw.constant(r_nominal)}
        if "asymmetric_restitution" in self.active:
            p = self.active["asymmetric_restitution"]
            laws = {"right": RestitutionLaw.constant(p["r_right"]),
                    "left": RestitutionLaw.constant(p["r_left"])}
        if "velocity_dependent_restitution" in self.active:
            p = self.active["velocity_dependent_restitution"]
            laws = {side: RestitutionLaw.parse(p[side]) for side in ("right", "left")}
        return laws

    def describe(self) -> str:
        """One line, e.g. ``'coulomb_friction(mu=0.3), inclination(theta=2)'``."""
        if not self.active:
            return "none (nominal model)"
        return ", ".join(f"{n}(" + ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                                                 for k, v in p.items()) + ")"
                         for n, p in self.active.items())
