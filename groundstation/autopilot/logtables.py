"""Every table of a flight log, and its full-rate IMU.

Every DataFlash message type with a time (``CLOCKS``) and every ULog topic that carries numbers becomes a table (``FlightLog.tables``:
one ``Series`` per type and instance, on the autopilot's clock), so the Channels tab can plot any of
them. Names: the type or topic in lower case, with ``_<instance>`` for a multi-instance DataFlash
type (the field its FMTU marks ``#``: ``IMU`` instance 1 -> ``imu_1``) and for a ULog topic's
``multi_id`` above 0 (``sensor_accel_1``); a name the session's own tables use (``imu``, ``gps``...)
gets ``_log`` appended; two names made one by the lower case (``caseTopic``, ``casetopic``) are kept
apart (``names.kept_apart``: the later gets ``__2``, and a warning says so). Columns: every numeric field
but the time (``CLOCKS``, ``timestamp``), DataFlash values as pymavlink's ``DFReader`` gives them (its
format scaling applied: ``c`` /100, ``L`` 1e-7) with the unit FMTU gives; ULog array elements as
``name_<i>`` (kept apart from a field of that name). Each column in the form the log has it where float32 holds
every value exactly (``logged_dtype``: a float32 or 8/16-bit integer field, unscaled), else in float64: a table is
about the size of its records in the file, and each value, widened, is the one pyulog or DFReader gives.

The full-rate IMU (``FAST``: tables ``gyro_fast_<imu>`` with ``gyr_{x,y,z}_rad_s`` and ``accel_fast_<imu>``
with ``acc_{x,y,z}_m_s2``, body FRD, every sample at its own time, and ``batch``: the batch it came in, so that
a reader can tell a burst from a continuous stream):

- ArduPilot's batch sampler: an ``ISBH`` header (batch ``N``, sensor ``type`` 0 accel / 1 gyro, IMU
  ``instance``, multiplier ``mul``, ``smp_cnt`` samples, ``SampleUS`` the first sample's time,
  ``smp_rate`` Hz) then ``ISBD`` records (``N``, ``seqno``, 32 int16 each of ``x``, ``y``, ``z``): sample
  ``k = 32 seqno + j`` is ``value / mul`` (rad/s, m/s²) at ``SampleUS + k / smp_rate`` (each batch at its own
  rate), ``batch`` its ``N``. A batch is one sensor's contiguous burst (1024 samples at ~2 kHz by default), then
  a gap; gyro and accel bursts alternate, so neither sensor is a continuous stream.
- PX4's ``sensor_gyro_fifo`` / ``sensor_accel_fifo``: ``samples`` values ``x[i] * scale`` spaced ``dt`` µs,
  the newest (``i = samples - 1``) at ``timestamp_sample``; one table per ``multi_id``; ``batch`` the message's
  index in the topic (one message follows the other: a continuous stream).
"""

from __future__ import annotations

import functools
import re
from array import array
from collections import defaultdict

import numpy as np

from groundstation.autopilot.flightlog import Series
from groundstation.names import kept_apart

# kind -> (table name before ``_<imu>``, fields, their unit): the table's columns are ``<field>_<unit>``
FAST = {"gyro": ("gyro_fast", ("gyr_x", "gyr_y", "gyr_z"), "rad/s"), "accel": ("accel_fast", ("acc_x", "acc_y", "acc_z"), "m/s2")}
ISB_TYPES = {0: "accel", 1: "gyro"}  # ISBH ``type`` (ArduPilot's IMU_SENSOR_TYPE_ACCEL, _GYRO)
BATCH = "batch"  # the full-rate tables' column of the batch (ISBH ``N``, a fifo message's index) a sample came in
FIFO_TOPICS = {"sensor_gyro_fifo": "gyro", "sensor_accel_fifo": "accel"}
ISBD_SAMPLES = 32  # int16 values per axis in one ISBD record
# The autopilot's boot clock, by the first field a DataFlash format has: (field, µs per unit). ``TimeMS`` in
# logs before ArduPilot 3.3 (2015), whose ``GPS`` carries its boot time in ``T`` ms (``TimeMS`` there: GPS time).
CLOCKS = (("TimeUS", 1), ("T", 1000), ("TimeMS", 1000))
RESERVED = ("imu", "onboard", "mag_raw", "baro", "gps", "position", "truth")  # a log session's own tables
DATAFLASH_SKIPPED = ("FMT", "FMTU", "UNIT", "MULT")  # the log's description of itself, not data
NUMERIC = set("bBhHiIfdgcCeELMqQ")  # DataFlash format characters of numbers (not strings nor ``a`` arrays)


# Logged dtypes whose every value float32 holds exactly: a table keeps such a column in float32 (widened to
# float64, each value is the one the log's reader gives); any other (32- and 64-bit integers, float64), and a
# value scaled to a physical unit, in float64.
EXACT_IN_FLOAT32 = frozenset(np.dtype(t) for t in ("?", "i1", "u1", "i2", "u2", "f2", "f4"))


def logged_dtype(dtype) -> np.dtype:
    """The dtype a table holds a column logged as ``dtype`` in: float32 where that holds it exactly, else float64."""
    return np.dtype(np.float32 if np.dtype(dtype) in EXACT_IN_FLOAT32 else np.float64)


def logged_column(values: np.ndarray) -> np.ndarray:
    """A new contiguous array of the logged ``values`` in ``logged_dtype`` (no view: a view holds what it is cut from)."""
    return np.array(values, dtype=logged_dtype(values.dtype))


def held_dtypes(series: Series) -> dict[str, str]:
    """A table's columns -> the dtype its session holds each in (``catalogue.Column.held``): the table's own."""
    return {name: values.dtype.name for name, values in series.columns.items()}


def fast_name(kind: str, instance: int) -> str:
    """The table of one IMU's full-rate gyro or accel: ``gyro_fast_0``, ``accel_fast_1``."""
    return f"{FAST[kind][0]}_{instance}"


def table_name(name: str, instance=None) -> str:
    name = name.lower() if instance is None else f"{name.lower()}_{instance}"
    return f"{name}_log" if name in RESERVED else name


class DataflashTables:
    """Collects where every message ``DFReader`` returns starts in the file (``add``), then ``tables(data)``: the
    log's tables and units, each type's records decoded from the file's bytes into columns at once (a Python
    object per value, kept to the end, took ten times the file)."""

    def __init__(self):
        self.starts = defaultdict(lambda: array("q"))  # type -> the file offsets of its records, in file order
        self.layouts: dict[str, _Layout] = {}  # type -> which of its fields are kept, and how
        self.isbh: dict[int, tuple] = {}  # batch N -> (kind, instance, mul, count, first sample µs, rate Hz)
        self.isbd = defaultdict(list)  # (kind, instance) -> [((mul, count, first µs, rate), N, seqno, x, y, z)]

    def add(self, msg, start: int) -> None:
        """``msg`` as DFReader read it from the record at file offset ``start`` (its header's)."""
        msg_type = msg.get_type()
        if msg_type in DATAFLASH_SKIPPED:
            return
        if msg_type == "ISBH":
            self.isbh[msg.N] = (ISB_TYPES.get(msg.type), msg.instance, msg.mul, msg.smp_cnt, msg.SampleUS, msg.smp_rate)
        elif msg_type == "ISBD":
            self._burst(msg)
        layout = self.layouts.get(msg_type)
        if layout is None:
            layout = self.layouts[msg_type] = _Layout(msg.fmt)
        if layout.take is not None:
            self.starts[msg_type].append(start)

    def _burst(self, msg) -> None:
        header = self.isbh.get(msg.N)
        if header is None or header[0] is None or not header[2]:
            return  # its header was lost (damaged bytes, a cut log start): no scale, no time
        self.isbd[header[:2]].append((header[2:], msg.N, msg.seqno, *msg._elements[-3:]))  # x, y, z: the last three fields

    def fields(self, data: np.ndarray, msg_type: str, starts, names) -> np.ndarray:
        """(rows, 1 + len(names)): the time (µs) and the fields ``names`` of the records of ``msg_type`` at
        ``starts`` in the file's bytes ``data``, as DFReader gives them."""
        layout = self.layouts[msg_type]
        if missing := [name for name in names if name not in layout.names]:
            raise ValueError(f"its {msg_type} messages have no {', '.join(missing)}")
        time_us, values = layout.values(layout.records(data, np.frombuffer(starts, dtype=np.int64)), names)
        return np.column_stack([time_us, *values])

    def tables(self, data: np.ndarray) -> tuple[dict[str, Series], dict[str, dict[str, str]], list[str]]:
        """The tables, their units, and a warning per type renamed to keep it apart (``kept_apart``); ``data``:
        the file's bytes. The tables in the order their first records come in the file, the full-rate ones first."""
        made = []  # (table name, series, units)
        for (kind, instance), records in self.isbd.items():
            times, values, batch = _isbd_samples(records)
            made.append((fast_name(kind, instance), in_order(times, {**dict(zip(FAST[kind][1], values.T)), BATCH: batch}, "ISBH/ISBD"),
                         dict.fromkeys(FAST[kind][1], FAST[kind][2])))
        parts = []  # (first record's offset, table name, series, units)
        while self.starts:  # each type's offsets let go once its table is made
            msg_type, starts = self.starts.popitem()
            layout = self.layouts[msg_type]
            starts = np.frombuffer(starts, dtype=np.int64)
            records = layout.records(data, starts)
            if layout.instance is None:
                groups = [(None, slice(None))]
            else:
                keys, inverse = np.unique(records[layout.instance], return_inverse=True)
                groups = [(key.item(), inverse.reshape(-1) == k) for k, key in enumerate(keys)]
            for instance, rows in groups:
                time_us, values = layout.values(records[rows])
                source = msg_type if instance is None else f"{msg_type}[{instance}]"
                parts.append((starts[rows][0], table_name(msg_type, instance),
                              in_order(time_us, dict(zip(layout.names, values)), source), layout.units))
        made += [part[1:] for part in sorted(parts, key=lambda part: part[0])]
        return named_tables(made, "DataFlash message")


def _isbd_samples(records) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One sensor's ISBD records as samples: times (µs), (n, 3) values in SI units, and each one's batch ``N``."""
    mul, count, first_us, rate_hz = (np.array([r[0][i] for r in records], dtype=float)[:, None] for i in range(4))
    batch = np.array([r[1] for r in records], dtype=np.uint16)[:, None]  # ISBH's and ISBD's ``N``: logged as ``H``
    k = np.array([r[2] for r in records], dtype=float)[:, None] * ISBD_SAMPLES + np.arange(ISBD_SAMPLES)[None, :]
    xyz = np.stack([np.array([r[3 + a] for r in records], dtype=float) for a in range(3)], axis=-1)  # (records, 32, 3)
    keep = k < count
    return (first_us + k * 1e6 / rate_hz)[keep], (xyz / mul[:, :, None])[keep], logged_column(np.broadcast_to(batch, k.shape)[keep])


class _Layout:
    """One DataFlash type's kept fields: its boot time (``CLOCKS``) then its numbers, their units, and the
    format's multipliers (``c`` 0.01, ``L`` 1e-7) applied to the raw values as DFReader applies them."""

    def __init__(self, fmt):
        clock, us_per_unit = next(((f, scale) for f, scale in CLOCKS if f in fmt.colhash), (None, 1))
        kept = [i for i, (c, f) in enumerate(zip(fmt.columns, fmt.format)) if f in NUMERIC and c != clock]
        self.names = [fmt.columns[i] for i in kept]
        self.units = {c: fmt.get_unit(c) for c in self.names}
        has_time = clock is not None and bool(kept)
        self.take = [f"f{i}" for i in (fmt.colhash[clock], *kept)] if has_time else None  # a type without time: no table
        self.dtype, self.length = record_dtype(fmt.msg_struct), fmt.len
        mults = [None, *(fmt.msg_mults[i] for i in kept)]
        # DFReader divides by 1/m for m < 1 (more exact than multiplying by m) and multiplies otherwise: so do we
        self.scale = np.array([us_per_unit, *(m if m is not None and m >= 1.0 else 1.0 for m in mults[1:])])
        self.divisor = np.array([1.0 / m if m is not None and 0.0 < m < 1.0 else 1.0 for m in mults])
        at = fmt.colhash.get(fmt.instance_field) if fmt.instance_field is not None else None
        self.instance = None if at is None else f"f{at}"

    def records(self, data: np.ndarray, starts: np.ndarray) -> np.ndarray:
        """The records at file offsets ``starts`` of the file's bytes ``data``, as a structured array (field ``f<i>``:
        element ``i`` of DFReader's unpacking)."""
        bodies = np.lib.stride_tricks.sliding_window_view(data, self.length - 3)[starts + 3]  # one copy: the records' bytes
        return bodies.view(self.dtype).reshape(len(starts))

    def values(self, records: np.ndarray, fields=None) -> tuple[np.ndarray, list[np.ndarray]]:
        """The time in µs (rows,) and a column per kept field of ``records`` (or those ``fields`` of them), each
        its own array (a column cut from a shared one holds on to it): the values DFReader gives, a field it does
        not scale in its ``logged_dtype``, a scaled one in float64."""
        at = [0, *(1 + self.names.index(name) for name in fields)] if fields is not None else range(len(self.take))
        time_us = records[self.take[0]] * self.scale[0] / self.divisor[0]
        values = []
        for field in at[1:]:
            raw = records[self.take[field]]
            if self.scale[field] == 1.0 and self.divisor[field] == 1.0:
                values.append(logged_column(raw))
            else:
                column = raw.astype(float)
                column *= self.scale[field]
                column /= self.divisor[field]
                values.append(column)
        return time_us, values


# DFReader's struct codes (``DFFormat.msg_struct``: little-endian, unpadded) as numpy's; ``<n>s`` a string of n bytes
STRUCT_TO_NUMPY = {"b": "i1", "B": "u1", "e": "<f2", "h": "<i2", "H": "<u2", "i": "<i4", "I": "<u4", "f": "<f4", "d": "<f8",
                   "q": "<i8", "Q": "<u8"}
_STRUCT_CODE = re.compile(r"(\d*)([a-zA-Z])")


def record_dtype(msg_struct: str) -> np.dtype:
    """A DataFlash record's body as a numpy dtype: field ``f<i>`` is element ``i`` of ``struct.unpack(msg_struct)``."""
    formats = [f"V{count or 1}" if code == "s" else STRUCT_TO_NUMPY[code] for count, code in _STRUCT_CODE.findall(msg_struct)]
    return np.dtype({"names": [f"f{i}" for i in range(len(formats))], "formats": formats})


def ulog_tables(data_list) -> tuple[dict[str, Series], dict[str, dict[str, str]], list[str]]:
    """Every topic instance of a ULog (``pyulog``'s ``data_list``, timestamps already checked; each one's columns
    taken from it) as a table, and the fifo topics' full-rate tables; their units; a warning per topic renamed to
    keep it apart."""
    fast, made, renamed = [], [], []  # (table name, series, units); warnings of fields kept apart
    for data in data_list:
        topic, data.data = data.data, {}  # pyulog's buffer of the topic goes with this round, not with the log
        fields = [name for name, values in topic.items() if name != "timestamp" and values.dtype.kind in "biuf"]
        if not len(topic["timestamp"]) or not fields:
            continue
        flat, said = kept_apart([_flat(f) for f in fields], [f"{data.name}.{f}" for f in fields], "ULog field")
        # copies, the time too: a view of a field holds on to pyulog's buffer of the topic's every record and field
        columns = {name: logged_column(topic[field]) for name, field in zip(flat, fields)}
        renamed += said
        made.append((table_name(data.name, data.multi_id or None), in_order(topic["timestamp"].copy(), columns, data.name), {}))
        if data.name in FIFO_TOPICS:
            kind = FIFO_TOPICS[data.name]
            fast.append((fast_name(kind, data.multi_id), fifo_series(topic, kind), dict.fromkeys(FAST[kind][1], FAST[kind][2])))
    tables, units, warnings = named_tables(fast + made, "ULog topic")
    return tables, units, renamed + warnings


def named_tables(made: list[tuple[str, Series, dict]], what: str) -> tuple[dict[str, Series], dict[str, dict], list[str]]:
    """``made`` (table name, series, units) as tables and units by name, names kept apart (the full-rate
    tables first: the session finds them by their names); the warnings of those renamed."""
    names, warnings = kept_apart([name for name, _, _ in made], [series.source for _, series, _ in made], what)
    return ({n: series for n, (_, series, _) in zip(names, made)}, {n: units for n, (_, _, units) in zip(names, made)},
            warnings)


def fifo_series(data: dict, kind: str) -> Series:
    """A ``sensor_*_fifo`` topic's samples: ``samples`` per message, ``dt`` µs apart, the newest at ``timestamp_sample``."""
    count = np.asarray(data["samples"], dtype=int)
    slots = np.arange(max(int(count.max(initial=0)), 1))
    valid = slots[None, :] < count[:, None]
    newest = np.asarray(data["timestamp_sample"], dtype=float)[:, None]
    times = newest - (count[:, None] - 1 - slots[None, :]) * np.asarray(data["dt"], dtype=float)[:, None]
    scale = np.asarray(data["scale"], dtype=float)[:, None]
    axes = [np.column_stack([data[f"{a}[{i}]"] for i in slots]) * scale for a in "xyz"]
    batch = np.broadcast_to(np.arange(len(count), dtype=float)[:, None], valid.shape)
    return in_order(times[valid], {**{c: v[valid] for c, v in zip(FAST[kind][1], axes)}, BATCH: batch[valid]}, f"{kind} fifo")


def in_order(time_us, columns: dict, source: str) -> Series:
    """A table's rows sorted by time (stable: rows sharing a time, a burst of parameters, keep theirs);
    rows already in order (a log's usual) are taken as they are, float columns (float32 or float64: their
    ``logged_dtype``) without a copy; other columns in float64."""
    time_us = np.asarray(time_us)
    columns = {n: v if v.dtype.kind == "f" else v.astype(float) for n, v in ((n, np.asarray(v)) for n, v in columns.items())}
    if len(time_us) < 2 or (time_us[1:] >= time_us[:-1]).all():
        return Series(time_us, columns, source)
    order = np.argsort(time_us, kind="stable")
    return Series(time_us[order], {n: v[order] for n, v in columns.items()}, source)


_INDEX = re.compile(r"\[(\d+)\]")


@functools.cache  # the same fields in every instance of a topic, in every log
def _flat(field: str) -> str:
    """A ULog field as a column name: ``gyro_rad[0]`` -> ``gyro_rad_0``."""
    return _INDEX.sub(r"_\1", field)
