"""Column tables: results keep plain numpy columns and build DataFrames on demand.

Building a pandas DataFrame costs more than the numerics of a stage, so the
results store ``{name: ndarray}`` and expose a cached DataFrame property.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:      # pandas is imported where a table is built, not to analyse
    import pandas as pd

__all__ = ["check_columns", "to_frame", "empty_columns"]


def check_columns(cols: Mapping[str, np.ndarray], names: Sequence[str], where: str) -> int:
    """Check that ``cols`` has every name in ``names``, all one-dimensional of one length.

    Returns
    -------
    int
        The common length.
    """
    missing = [c for c in names if c not in cols]
    if missing:
        raise ValueError(f"{where}: missing column(s) {', '.join(missing)}")
    sizes = {c: np.shape(cols[c]) for c in names}
    lengths = {s[0] if len(s) == 1 else -1 for s in sizes.values()}
    if len(lengths) != 1 or -1 in lengths:
        raise ValueError(f"{where}: columns must be 1-D of one length, got shapes {sizes}")
    return lengths.pop() if lengths else 0


def to_frame(cols: Mapping[str, np.ndarray], names: Sequence[str]) -> pd.DataFrame:
    """DataFrame with the columns ``names`` in that order (then any others)."""
    import pandas as pd

    order = list(names) + [c for c in cols if c not in names]
    return pd.DataFrame({c: np.asarray(cols[c]) for c in order})


def empty_columns(spec: Mapping[str, type]) -> dict[str, np.ndarray]:
    """Zero-length columns of the given dtypes."""
    return {c: np.zeros(0, dtype=d) for c, d in spec.items()}
