"""Per-case cache of the realism benchmarks: the analyses are their slow part.

Pickles that the benchmark itself wrote into the directory the user named (never
files from elsewhere); delete the directory when the simulation, the sensors or the
analysis change.
"""

from __future__ import annotations

import os
import pickle
from collections.abc import Callable
from typing import Any


def cached(cache: str | None, name: str, compute: Callable[[], Any]) -> Any:
    """``compute()``, kept as ``cache/name.pkl`` (written atomically); no cache: computed."""
    path = os.path.join(cache, f"{name}.pkl") if cache else None
    if path and os.path.exists(path):
        with open(path, "rb") as fh:
            return pickle.load(fh)
    value = compute()
    if path:
        os.makedirs(cache, exist_ok=True)
        with open(path + ".tmp", "wb") as fh:
            pickle.dump(value, fh)
        os.replace(path + ".tmp", path)
    return value
