"""An append-only table of float64 rows, cheap enough to grow at 100 Hz for hours.

Rows are stored flat, 8 bytes per value and no Python object per row: the newest rows in one
``array('d')`` (appending a row is one C call), sealed into a read-only numpy block every
``chunk_rows`` rows (the block is a view of that array's memory: no copy). Memory is linear in the
rows, with at most one growing chunk of slack; a column is read without copying the other columns,
and ``extend`` adds a whole array of rows at once (the batch path).

A live session's tables are bounded (``keep_rows``): once more than that many rows are sealed behind
the newest, whole blocks are forgotten from the front, so an hours-long flight holds fewer than
``keep_rows`` + two chunks of rows per table (the sealed ones and the growing one) (the recording on disk keeps every byte, and export and
replay read it, not these tables). ``len`` still counts every row appended (the readers count new
rows by it); ``array``, ``column`` and ``to_dict`` give the rows kept, ``forgotten`` says how many
went before them.

One writer thread may append while other threads read: the blocks and the growing chunk are
published together as one tuple, and each append and each slice of the growing chunk holds the GIL,
so a reader sees whole rows, in order. Readers copy the growing chunk by slicing it (a C copy) and
never take a buffer on it: while a buffer is exported the array cannot grow, and ``append`` in the
reader thread would raise BufferError.
"""

from __future__ import annotations

from array import array

import numpy as np

CHUNK_ROWS = 65_536  # 11 minutes at 100 Hz per block
# A live session's bound: the newest 10 minutes at 100 Hz (the longest live window), kept in blocks of
# 10 s so that a table holds what it holds at 10 minutes from then on, within 3 % (issue 35; blocks of 82 s
# grew it 27 % more, to 12.7 minutes): under 62 048 rows a table (51 MB for the imu table of the app's ten
# estimators, 102 columns).
LIVE_KEEP_ROWS = 60_000
LIVE_CHUNK_ROWS = 1_024


class Table:
    def __init__(self, columns: tuple[str, ...] | list[str], chunk_rows: int = CHUNK_ROWS, keep_rows: int | None = None):
        self.columns = tuple(columns)
        self.keep_rows = keep_rows  # None: every row stays
        self.forgotten = 0  # rows dropped from the front to stay within ``keep_rows``
        self._width = len(self.columns)
        self._chunk_values = chunk_rows * self._width
        self._state: tuple[tuple[np.ndarray, ...], array] = ((), array("d"))
        self._sealed_rows = 0

    @classmethod
    def holding(cls, columns, rows: np.ndarray) -> Table:
        """A table of ``rows``, an (N, len(columns)) array taken as it is when it is float64 in rows or in
        columns (the caller gives it up: no copy, and it becomes read-only), else copied once."""
        table = cls(columns)
        rows = np.asarray(rows, dtype=float)
        if rows.ndim != 2 or rows.shape[1] != len(table.columns) or not (rows.flags.c_contiguous or rows.flags.f_contiguous):
            rows = np.ascontiguousarray(rows).reshape(-1, len(table.columns))
        if len(rows):
            rows.flags.writeable = False
            table._state = ((rows,), array("d"))
            table._sealed_rows = len(rows)
        return table

    def append(self, row) -> None:
        """Add one row: a sequence of len(columns) numbers."""
        growing = self._state[1]
        growing.extend(row)
        if len(growing) >= self._chunk_values:
            self._seal()

    def extend(self, rows) -> None:
        """Add rows from an (N, len(columns)) array-like in one step (copied)."""
        rows = np.array(rows, dtype=float, copy=True).reshape(-1, self._width)
        if len(rows):
            self._seal()
            blocks, growing = self._state
            rows.flags.writeable = False
            self._sealed_rows += len(rows)
            self._state = (self._kept(blocks + (rows,)), growing)

    def _seal(self) -> None:
        blocks, growing = self._state
        if len(growing):
            block = np.frombuffer(growing, dtype=float).reshape(-1, self._width)  # never extended again
            self._sealed_rows += len(block)
            self._state = (self._kept(blocks + (block,)), array("d"))

    def _kept(self, blocks: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
        """``blocks`` without the oldest ones that the newest ``keep_rows`` sealed rows do not need."""
        if self.keep_rows is None:
            return blocks
        sealed = sum(len(b) for b in blocks)
        while len(blocks) > 1 and sealed - len(blocks[0]) >= self.keep_rows:
            sealed -= len(blocks[0])
            self.forgotten += len(blocks[0])
            blocks = blocks[1:]
        return blocks

    def __len__(self) -> int:
        return self._sealed_rows + len(self._state[1]) // self._width

    def _parts(self) -> list[np.ndarray]:
        """The blocks and a copy of the growing chunk, a consistent snapshot."""
        blocks, growing = self._state
        return [*blocks, np.frombuffer(growing[:], dtype=float).reshape(-1, self._width)]

    def array(self) -> np.ndarray:
        """All rows as an (N, len(columns)) float64 array (a copy)."""
        return np.concatenate(self._parts())

    def tail(self, rows: int) -> np.ndarray:
        """The newest ``rows`` rows (fewer if the table is shorter), as a copy."""
        blocks, growing = self._state
        n = min(rows, len(growing) // self._width) * self._width
        newest = [np.frombuffer(growing[len(growing) - n :], dtype=float).reshape(-1, self._width)]
        have = n // self._width
        for block in reversed(blocks):
            if have >= rows:
                break
            newest.insert(0, block[max(0, len(block) - (rows - have)) :])
            have += len(newest[0])
        return np.concatenate(newest)

    def column(self, name: str) -> np.ndarray:
        """One column (a copy of that column only)."""
        i = self.columns.index(name)
        return np.concatenate([part[:, i] for part in self._parts()])

    def hand_over(self, dtypes: dict[str, np.dtype]) -> dict[str, np.ndarray]:
        """Every column, and the rows let go: the table's maker is done with it (a product is made of it). Views
        of the one block when the rows are in one (a table made whole: no copy), else each column copied into its
        dtype (``dtypes``, by name) from the blocks themselves: a table's rows are held twice at most while its
        columns are made, not once more as a whole array and its float64 columns beside their float32 form
        (``to_dict``). ``len`` still counts every row appended; ``forgotten`` says they all went."""
        self._seal()  # the growing chunk becomes a block without a copy: nothing appends to it again
        blocks = self._state[0]
        self._state, self.forgotten = ((), array("d")), self._sealed_rows
        if len(blocks) == 1 and not blocks[0].flags.writeable:
            return {name: blocks[0][:, i] for i, name in enumerate(self.columns)}
        return {name: np.concatenate([block[:, i] for block in blocks] or [np.zeros(0)], dtype=dtypes[name])
                for i, name in enumerate(self.columns)}

    def to_dict(self) -> dict[str, np.ndarray]:
        """Every column: views of the one block when the rows are in one (a table made whole: read-only, no
        copy), else of a copy of them."""
        parts = [part for part in self._parts() if len(part)]
        data = parts[0] if len(parts) == 1 and not parts[0].flags.writeable else self.array()
        return {name: data[:, i] for i, name in enumerate(self.columns)}
