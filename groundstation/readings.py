"""Readings that arrive on some samples only (magnetometer, barometer, GPS), as the batch ``run``
methods take them: an array with a row per sample, NaN rows where no reading arrived."""

from __future__ import annotations

import numpy as np


def optional_rows(values, n: int, width: int, name: str) -> list:
    """(n, width) array -> one tuple per row, None for a row of NaN; ``values`` None -> n Nones."""
    if values is None:
        return [None] * n
    rows = np.asarray(values, dtype=float).reshape(-1, width)
    if len(rows) != n:
        raise ValueError(f"{name} has {len(rows)} rows of {width}, expected {n}")
    missing = np.isnan(rows).all(axis=1).tolist()
    return [None if gone else tuple(r) for r, gone in zip(rows.tolist(), missing)]
