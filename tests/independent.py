"""Recordings of an independent simulator (copied from ``shared/independent``).

They stand in for a real rig: compliant walls, smooth dry friction, causal analog
anti-alias filters, integrated with ``solve_ivp`` by code that shares nothing with
vidiscover. ``load(name)`` gives the recording, its metadata and the truth key
(``setup``, ``impacts`` per contact episode, ``label``, ``strobe``).
"""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import numpy as np
import pandas as pd

from vidiscover.io import read_metadata
from vidiscover.recording import Recording

DATA = Path(__file__).parent / "data" / "independent"
CASES = tuple(sorted(p.name[:-len(".csv.gz")] for p in DATA.glob("*.csv.gz")))
GAP_TRUTH = json.loads((DATA / "gap_truth.json").read_text())


def load(name: str) -> tuple[Recording, dict]:
    """The recording ``name`` (e.g. ``"P01_b8_chatter"``) and its truth key."""
    with gzip.open(DATA / f"{name}.csv.gz", "rt") as fh:
        df = pd.read_csv(fh)
    meta = read_metadata(DATA / f"{name}.json")
    cols = {c: df[c].to_numpy(dtype=float) for c in ("t", "x", "a", "xe")}
    rec = Recording(cols["t"], cols["x"], cols["a"], cols["xe"], meta, name=name)
    key = json.loads((DATA / f"{name}.key.json").read_text())
    return rec, key


def true_impacts(key: dict) -> dict[str, np.ndarray]:
    """Truth contact episodes as arrays: t_in, t_out, side (+1/-1), v_in, r."""
    imps = key["impacts"]
    return {"t_in": np.array([i["t_in"] for i in imps]),
            "t_out": np.array([i["t_out"] for i in imps]),
            "side": np.array([1 if i["side"] == "right" else -1 for i in imps]),
            "v_in": np.array([i["v_in"] for i in imps]),
            "r": np.array([i["r"] for i in imps])}
