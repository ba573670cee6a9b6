"""Table: the same rows back as went in, across chunk boundaries; memory linear in the rows."""

import gc
import threading
import tracemalloc

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from groundstation.session_parts.table import LIVE_CHUNK_ROWS, LIVE_KEEP_ROWS, Table

COLUMNS = ("time_s", "a", "b")


@settings(max_examples=100, derandomize=True)
@given(
    st.integers(1, 7),
    st.lists(st.one_of(st.integers(0, 3), st.integers(0, 20).map(lambda n: -n - 1)), max_size=30),
    st.integers(0, 40),
)
def test_rows_come_back_in_order_across_chunks(chunk_rows, steps, tail_rows):
    """Appends (a non-negative step: rows one by one) and bulk extends (negative: -n - 1 rows) mixed."""
    table, expected, counter = Table(COLUMNS, chunk_rows=chunk_rows), [], 0
    for step in steps:
        count = step if step >= 0 else -step - 1
        rows = [(counter + k, -(counter + k), 0.5 * (counter + k)) for k in range(count)]
        counter += count
        if step >= 0:
            for row in rows:
                table.append(row)
        else:
            table.extend(np.array(rows, dtype=float).reshape(-1, 3))
        expected += rows
    reference = np.array(expected, dtype=float).reshape(-1, 3)
    assert len(table) == len(reference)
    np.testing.assert_array_equal(table.array(), reference)
    np.testing.assert_array_equal(table.tail(tail_rows), reference[len(reference) - min(tail_rows, len(reference)) :])
    for i, name in enumerate(COLUMNS):
        np.testing.assert_array_equal(table.column(name), reference[:, i])
        np.testing.assert_array_equal(table.to_dict()[name], reference[:, i])


def test_returned_arrays_are_copies_or_read_only():
    table = Table(COLUMNS, chunk_rows=2)
    for k in range(5):
        table.append((k, k, k))
    table.array()[:] = -1
    table.column("a")[:] = -1
    table.tail(3)[:] = -1
    assert table.array()[:, 0].tolist() == [0, 1, 2, 3, 4]


def test_a_table_made_whole_holds_its_rows_without_a_copy():
    """``Table.holding`` takes an array in rows or in columns as it is (read-only from then on) and
    ``to_dict`` gives views of it; anything else is copied once."""
    for order in "CF":
        rows = np.arange(15, dtype=float).reshape(5, 3).copy(order=order)
        table = Table.holding(COLUMNS, rows)
        columns = table.to_dict()
        assert all(np.shares_memory(column, rows) for column in columns.values())
        assert columns["a"].tolist() == [1, 4, 7, 10, 13] and len(table) == 5
        assert not rows.flags.writeable
    strided = np.arange(30, dtype=float).reshape(5, 6)[:, ::2]
    table = Table.holding(COLUMNS, strided)
    assert not np.shares_memory(table.to_dict()["a"], strided) and table.to_dict()["a"].tolist() == strided[:, 1].tolist()
    table.append((9.0, 9.0, 9.0))  # a table made whole still grows as any other
    assert table.column("time_s").tolist() == [0, 6, 12, 18, 24, 9]


def test_a_table_handed_over_gives_its_columns_in_their_dtypes_and_lets_its_rows_go():
    """``hand_over``: the rows as ``to_dict`` gives them, each column copied into its dtype across the blocks and the
    growing chunk (a table made whole: views), the table holding none of them after; ``len`` still counts them."""
    rng = np.random.default_rng(35)
    rows = rng.normal(size=(23, 3))
    dtypes = {"time_s": np.dtype(float), "a": np.dtype(np.float32), "b": np.dtype(float)}
    table = Table(COLUMNS, chunk_rows=10)
    for row in rows:
        table.append(row)
    expected = table.to_dict()
    columns = table.hand_over(dtypes)
    for name, column in columns.items():
        assert column.dtype == dtypes[name] and column.flags.c_contiguous
        np.testing.assert_array_equal(column, expected[name].astype(dtypes[name]))
    assert len(table) == 23 and table.forgotten == 23 and not len(table.array())
    assert all(not len(column) for column in Table(COLUMNS).hand_over(dtypes).values())
    whole = Table.holding(COLUMNS, rows)
    assert all(np.shares_memory(column, rows) for column in whole.hand_over(dtypes).values())


def traced_bytes(rows: int, width: int = 12) -> tuple[int, int]:
    """Memory held by a table of ``rows`` appended rows, and Python objects created for it."""
    gc.collect()
    objects_before = len(gc.get_objects())
    tracemalloc.start()
    table = Table([f"c{i}" for i in range(width)], chunk_rows=10_000)
    row = tuple(float(i) for i in range(width))
    for _ in range(rows):
        table.append(row)
    held, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    objects = len(gc.get_objects()) - objects_before
    del table
    return held, objects


def test_memory_is_linear_in_the_rows_with_no_object_per_row():
    small_bytes, small_objects = traced_bytes(20_000)
    large_bytes, large_objects = traced_bytes(200_000)
    per_row = (large_bytes - small_bytes) / 180_000
    assert 12 * 8 <= per_row <= 12 * 8 * 1.15  # 8 bytes a value, at most one chunk's growth slack
    assert large_objects - small_objects < 100  # blocks only, never an object per row


def test_reader_thread_sees_whole_rows_in_order_while_a_writer_appends():
    table = Table(COLUMNS, chunk_rows=64)
    done, bad = threading.Event(), []

    def read():
        while not done.is_set():
            data = table.array()
            if len(data) and not (np.array_equal(data[:, 0], np.arange(len(data))) and np.array_equal(data[:, 1], -data[:, 0])):
                bad.append(len(data))

    reader = threading.Thread(target=read)
    reader.start()
    for k in range(20_000):
        table.append((k, -k, 0.0))
    done.set()
    reader.join()
    assert not bad and len(table) == 20_000


def test_a_reader_copying_a_large_growing_chunk_never_stops_the_writer():
    """The live view copies the tables while the reader thread appends: a copy that held the growing
    chunk's buffer made ``append`` raise BufferError, which ended the reader thread (decoding stopped)."""
    table = Table([f"c{i}" for i in range(100)], chunk_rows=200_000)  # the imu table with ten estimators is ~100 wide
    done = threading.Event()

    def read():
        while not done.is_set():
            table.array()
            table.column("c0")

    reader = threading.Thread(target=read)
    reader.start()
    try:
        row = tuple(range(100))
        for _ in range(30_000):
            table.append(row)
    finally:
        done.set()
        reader.join()
    assert len(table) == 30_000


def test_a_bounded_table_keeps_its_newest_rows_and_counts_them_all():
    """A live session's table (``keep_rows``) fed far more rows than its bound keeps the newest ones, at most
    the bound and one chunk, in order; ``len`` counts every row (readers count new rows by it) and ``tail``
    gives the newest."""
    table = Table(COLUMNS, chunk_rows=64, keep_rows=500)
    rows = np.column_stack([np.arange(20_000.0), -np.arange(20_000.0), np.ones(20_000)])
    for i, row in enumerate(rows):
        table.append(row)
        if i % 997 == 0:
            kept = table.array()
            assert 0 < len(kept) <= 500 + 64 + 64 and kept[-1, 0] == i
    kept = table.array()
    assert len(table) == 20_000 and table.forgotten == 20_000 - len(kept) and 500 <= len(kept) <= 500 + 2 * 64
    assert np.array_equal(kept, rows[table.forgotten :]) and np.array_equal(table.column("a"), rows[table.forgotten :, 1])
    assert np.array_equal(table.tail(300), rows[-300:])
    table.extend(rows[:2000])  # the batch path's bulk rows are bounded too
    assert len(table) == 22_000 and len(table.array()) <= 2000 + 64


def test_a_live_table_holds_no_more_after_its_ten_minutes():
    """A live session's table at 100 Hz (issue 35: the app's RSS grew from 10 to 20 minutes): once it holds
    its ``LIVE_KEEP_ROWS`` (the newest 10 minutes), twice as long a flight holds no more, give or take its
    forgetting in whole blocks (3 %; the blocks of 8,192 rows let it grow 27 % more, to 12.7 minutes)."""
    table = Table(COLUMNS, chunk_rows=LIVE_CHUNK_ROWS, keep_rows=LIVE_KEEP_ROWS)
    row = [0.0, 1.0, 2.0]
    held = []
    for i in range(2 * LIVE_KEEP_ROWS):
        row[0] = i / 100.0
        table.append(row)
        if i + 1 >= LIVE_KEEP_ROWS and (i + 1) % 500 == 0:
            held.append(len(table.array()))
    assert held[0] == LIVE_KEEP_ROWS and max(held) <= 1.035 * LIVE_KEEP_ROWS
