"""An append-only table of float64 rows, cheap enough to grow at 100 Hz for hours.

Rows are stored flat in one ``array('d')``: appending a row is a single C call, memory is 8 bytes
per value, and the newest rows (``tail``) are a slice, which is all the live view needs. One
writer thread may append while other threads read: each append and each slice holds the GIL.
"""

from __future__ import annotations

from array import array

import numpy as np


class Table:
    def __init__(self, columns: tuple[str, ...] | list[str]):
        self.columns = tuple(columns)
        self._width = len(self.columns)
        self._data = array("d")
        self.append = self._data.extend  # append(row): row is a sequence of len(columns) numbers

    def __len__(self) -> int:
        return len(self._data) // self._width

    def array(self) -> np.ndarray:
        """All rows as an (N, len(columns)) float64 array (a copy)."""
        return np.array(self._data, dtype=float).reshape(-1, self._width)

    def tail(self, rows: int) -> np.ndarray:
        """The newest ``rows`` rows (fewer if the table is shorter), as a copy."""
        n = min(rows, len(self)) * self._width
        return np.array(self._data[len(self._data) - n :], dtype=float).reshape(-1, self._width)

    def column(self, name: str) -> np.ndarray:
        return self.array()[:, self.columns.index(name)]

    def to_dict(self) -> dict[str, np.ndarray]:
        data = self.array()
        return {name: data[:, i] for i, name in enumerate(self.columns)}
