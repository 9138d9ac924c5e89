"""Bit-identity check of ``analyze`` between two versions of the package.

Each version runs this script in its own process (``PYTHONPATH`` pointing at it) with
``--dump FILE``: it analyzes the same recordings (made once, pickled in ``--recs``)
and saves every array and number of each result, walked recursively; ``--compare A
B`` then asserts them equal (``np.array_equal``, NaN-aware; same keys, same dtypes).

Recordings: the exact engine's paper preset at b = 6, 7.5, 9 mm (seed 1, as
``bench_cli.py``; ``pulse=PulseModel()``), the paper's Table-2 walls at the same b
(``bench_analyze.py``'s cases; ``pulse=PulseModel()``, one also with ``mu=0.3`` and a
bootstrap) and the first 10 cases of the spent corpus split ``holdout13`` (learned
pulse). The pulse learner's run time (``response.seconds``) is left out.

Usage::

    PYTHONPATH=A python benchmarks/identity_analyze.py --recs R.pkl --dump A.pkl
    PYTHONPATH=B python benchmarks/identity_analyze.py --recs R.pkl --dump B.pkl
    python benchmarks/identity_analyze.py --compare A.pkl B.pkl
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import pickle
import sys

import numpy as np

ASYM = ("asymmetric_restitution=0.88,0.20",)
#: Leaves that are timings, not results (the pulse learner's wall-clock seconds).
VOLATILE = ("res.detection.response.seconds",)


def make_recordings() -> list:
    """(name, recording, analyze kwargs) of every case."""
    from vidiscover import Effects, SensorConfig, preset, record, simulate
    from vidiscover.corpus import realism_corpus
    from vidiscover.workflows import simulate_to_memory

    out = []
    for b in (0.006, 0.0075, 0.009):
        rec, _, _ = simulate_to_memory(preset("paper", b=b), seed=1, label=False)
        out.append((f"exact-b{b}", rec, {"known": True}))
    for b in (0.006, 0.0075, 0.009):
        res = simulate(preset("paper", b=b), Effects.parse(list(ASYM)), settle=10.0,
                       duration=5.12)
        rec, _ = record(res, SensorConfig(), seed=1)
        out.append((f"table2-b{b}", rec, {"known": True}))
        if b == 0.009:
            out.append((f"table2-b{b}-mu0.3-boot", rec,
                        {"known": True, "mu": 0.3, "n_boot": 200, "seed": 3}))
    for case in realism_corpus("holdout13", 10):
        sim = case.simulate(label=False)
        out.append((case.name, sim.recording, {"known": False}))
    return out


def _leaves(obj, path: str, out: dict, seen: set) -> None:
    if isinstance(obj, np.ndarray):
        out[path] = obj
        return
    if isinstance(obj, (bool, int, float, complex, str, bytes, type(None), np.generic)):
        out[path] = obj
        return
    if id(obj) in seen:
        return
    seen.add(id(obj))
    if isinstance(obj, dict):
        for k, v in obj.items():
            _leaves(v, f"{path}[{k!r}]", out, seen)
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            _leaves(v, f"{path}[{i}]", out, seen)
    elif dataclasses.is_dataclass(obj):
        for f in dataclasses.fields(obj):
            _leaves(getattr(obj, f.name), f"{path}.{f.name}", out, seen)
    elif hasattr(obj, "__dict__"):
        for k, v in vars(obj).items():
            _leaves(v, f"{path}.{k}", out, seen)
    else:
        out[path] = repr(obj)


def dump(recs_path: str, out_path: str) -> None:
    import vidiscover
    from vidiscover.analysis import PulseModel, analyze

    print("vidiscover from", vidiscover.__file__)
    if os.path.exists(recs_path):
        with open(recs_path, "rb") as fh:
            cases = pickle.load(fh)
    else:
        cases = make_recordings()
        with open(recs_path, "wb") as fh:
            pickle.dump(cases, fh)
    results = {}
    for name, rec, kw in cases:
        kw = dict(kw)
        known = kw.pop("known")
        kw.setdefault("n_boot", 0)
        res = analyze(rec, pulse=PulseModel() if known else None, **kw)
        leaves: dict = {}
        _leaves(res, "res", leaves, set())
        results[name] = leaves
        print(name, len(leaves), "leaves", res.detection.n, "impacts")
    with open(out_path, "wb") as fh:
        pickle.dump(results, fh)


def _equal(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        if a.dtype != b.dtype or a.shape != b.shape:
            return False
        if a.dtype.kind in "fc":
            return bool(np.array_equal(a, b, equal_nan=True))
        return bool(np.array_equal(a, b))
    if isinstance(a, float) and isinstance(b, float) and a != a and b != b:
        return True
    return type(a) is type(b) and a == b


def compare(pa: str, pb: str) -> int:
    with open(pa, "rb") as fh:
        A = pickle.load(fh)
    with open(pb, "rb") as fh:
        B = pickle.load(fh)
    bad = 0
    assert A.keys() == B.keys(), (A.keys(), B.keys())
    for name in A:
        if A[name].keys() != B[name].keys():
            print(name, "different leaves:", set(A[name]) ^ set(B[name]))
            bad += 1
            continue
        diff = [k for k in A[name]
                if k not in VOLATILE and not _equal(A[name][k], B[name][k])]
        print(name, len(A[name]), "leaves,", "all equal" if not diff else f"DIFFER: {diff[:8]}")
        bad += bool(diff)
    print("IDENTICAL" if not bad else f"{bad} cases differ")
    return 1 if bad else 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--recs", default="/tmp/identity_recs.pkl")
    p.add_argument("--dump")
    p.add_argument("--compare", nargs=2)
    a = p.parse_args(argv)
    if a.compare:
        return compare(*a.compare)
    dump(a.recs, a.dump)
    return 0


if __name__ == "__main__":
    sys.exit(main())
