"""A session as Foxglove topics: the one mapping that the MCAP export and the live Foxglove bridge share.

- every table of the session: a protobuf channel ``/<table>``, one message per row, every column a
  ``double`` under its own name (units in the names, as everywhere; ``protobuf_rows``), NaN as NaN. A typed
  schema rather than JSON: Rerun decodes protobuf into series and JSON not at all, Foxglove and Lichtblick
  plot both, and a double carries NaN where JSON has to leave the value out;
- every attitude estimate (each host estimator and the aircraft's own, ``onboard``): a Foxglove
  ``FrameTransform`` on ``/tf`` from ``ned`` to a frame named after the estimator (Foxglove's 3D panel
  shows them as axes), and its angles in degrees on ``/attitude/<name>`` (``pitch_deg``, ``roll_deg``,
  ``yaw_deg``, by ``quaternion.euler_deg``, the one conversion every view uses);
- the autopilot's parameters: one JSON message on ``/parameters`` (name -> value);
- every event (configuration, warnings, settings changes, autopilot messages, ...): a Foxglove ``Log``
  on ``/events``, its severity from its kind.

A message's log time is ``origin_ns`` plus its session time (the session's ``start_utc``: a recording's
start, a flight log's own GPS or UTC time; the wall clock at the session's first byte live), so
Foxglove's timeline reads real time of day.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from datetime import datetime, timezone

import numpy as np

from groundstation import quaternion
from groundstation.export.protobuf_rows import RowEncoder, descriptor_set, message_name
from groundstation.session_parts.catalogue import Catalogue
from groundstation.text import clean

NED_FRAME = "ned"  # the parent frame of every attitude: the quaternions are body -> NED (w-first)
# Event kinds a pilot must not miss are warnings; failures are errors; everything else is information.
_ERROR_KINDS = frozenset({"recording_failed", "disconnected"})
_WARNING_KINDS = frozenset({"warning", "config_conflict", "device_reset", "clock_jump", "gap"})


def origin_ns(metadata: dict, earliest_s: float = 0.0) -> int:
    """The wall-clock time of session time 0 in ns since the epoch: the session's ``start_utc``; for a
    session that has none (a flight log without GPS or UTC time, a dataset) the epoch, moved on by whole
    seconds when rows come before time 0 (``earliest_s`` < 0), since MCAP's log times cannot be negative."""
    try:
        start = datetime.fromisoformat(str(metadata.get("start_utc")))
    except ValueError:
        return math.ceil(max(0.0, -earliest_s)) * 1_000_000_000
    if start.tzinfo is None:
        start = start.replace(tzinfo=timezone.utc)
    return int(start.timestamp() * 1e9)


def time_metadata(metadata: dict, origin: int) -> dict[str, str]:
    """What a file's log times are on, for its metadata: the UTC time of session time 0 and where it
    comes from (``start_utc_source``: a log's GPS or UTC time; else a recording's start on the host's
    clock), or that the session has none and log time counts from the epoch."""
    if "start_utc" not in metadata:
        return {"log_time": "ns from 1970-01-01T00:00:00Z standing for the session's start: its source holds no UTC time",
                "session_time_0_ns": str(origin)}
    return {"log_time": "ns since 1970-01-01T00:00:00Z (UTC)", "session_time_0_ns": str(origin),
            "session_time_0_utc": str(metadata["start_utc"]),
            "source": str(metadata.get("start_utc_source", "the recording's start on the host's clock"))}


def earliest_time_s(tables: dict[str, dict[str, np.ndarray]]) -> float:
    """The earliest session time in any table (0 when none is earlier)."""
    firsts = [np.nanmin(t["time_s"]) for t in tables.values() if np.isfinite(t["time_s"]).any()]
    return min([0.0, *firsts])


def log_time_ns(origin: int, time_s: np.ndarray) -> np.ndarray:
    """Session times as log times (int64 ns). Rows without a time (NaN) keep the origin."""
    offsets = np.nan_to_num(np.asarray(time_s, dtype=float) * 1e9, nan=0.0)
    return origin + np.rint(offsets).astype(np.int64)


def table_schema(table: str, columns):
    """A table's channel schema: its protobuf message, a ``double`` per column (``protobuf_rows``)."""
    import foxglove

    return foxglove.Schema(name=message_name(table), encoding="protobuf", data=descriptor_set(table, columns))


def timed(columns: dict[str, np.ndarray], rows: slice | np.ndarray = slice(None)) -> dict[str, np.ndarray]:
    """The rows of a table with a session time each: a row that came before the first timed one (a CONFIG
    at the start) has none (NaN) and is logged at the session's start, so its ``time_s`` says 0."""
    time_s = np.asarray(columns["time_s"], dtype=float)[rows]
    return {**{c: np.asarray(v, dtype=float)[rows] for c, v in columns.items()}, "time_s": np.nan_to_num(time_s, nan=0.0)}


def estimates_in(table: str, columns) -> dict[str, tuple[str, str, str, str]]:
    """The attitude estimates a table carries: ``<name>_qw`` .. ``_qz`` (each host estimator in ``imu``),
    or ``qw`` .. ``qz`` (the aircraft's own in ``onboard``, named after its table)."""
    names = {c[:-3] for c in columns if c.endswith("_qw")}
    found = {n: tuple(f"{n}_q{c}" for c in "wxyz") for n in sorted(names)}
    if "qw" in columns:
        found[table] = ("qw", "qx", "qy", "qz")
    return {n: q for n, q in found.items() if all(c in columns for c in q)}


@dataclasses.dataclass
class Messages:
    """The messages of one channel in the order written: their log times (int64 ns) and, for message
    ``i``, what the channel logs."""

    channel: object
    log_times: np.ndarray
    payload: Callable[[int], object]


def log_in_time_order(streams: list[Messages]) -> int:
    """Logs the messages of every stream merged by log time (a stream's own order kept among equal
    times), as MCAP readers expect: a chunk then spans a short stretch of time, and a seek opens few
    chunks. Returns the number of messages."""
    if not streams:
        return 0
    times = np.concatenate([s.log_times for s in streams])
    stream = np.concatenate([np.full(len(s.log_times), k) for k, s in enumerate(streams)])
    index = np.concatenate([np.arange(len(s.log_times)) for s in streams])
    order = np.argsort(times, kind="stable")
    for log_time, k, i in zip(times[order].tolist(), stream[order].tolist(), index[order].tolist()):
        streams[k].channel.log(streams[k].payload(i), log_time=log_time)
    return len(order)


class Topics:
    """The session's channels in a foxglove ``Context``: an MCAP writer or a WebSocket server opened on
    the same context receives what is logged here. ``*_messages`` give a part's messages to merge with
    others (``log_in_time_order``); ``rows``, ``events`` and ``parameters`` log them at once."""

    def __init__(self, context, catalogue: Catalogue, origin: int):
        from foxglove.channels import FrameTransformsChannel, LogChannel

        self._context = context
        self.catalogue = catalogue
        self.origin = origin
        self._channels: dict[str, tuple[object, RowEncoder]] = {}
        self._tf = FrameTransformsChannel("/tf", context=context)
        self._log = LogChannel("/events", context=context)
        self._parameters = None  # opened with the first parameters

    def _channel(self, topic: str, table: str, columns) -> tuple[object, RowEncoder]:
        """The channel of a topic of table rows and its encoder, opened with these columns the first time."""
        import foxglove

        if topic not in self._channels:
            channel = foxglove.Channel(topic, schema=table_schema(table, columns), message_encoding="protobuf",
                                       context=self._context)
            self._channels[topic] = channel, RowEncoder(columns)
        return self._channels[topic]

    def advertise(self, tables) -> None:
        """Opens the channels of these tables (those the catalogue describes) now: a live client
        subscribes before their first rows."""
        for name in tables:
            if name in self.catalogue:
                self._channel(f"/{name}", name, self.catalogue[name].column_names)

    def rows(self, name: str, columns: dict[str, np.ndarray], rows: slice | np.ndarray = slice(None)) -> int:
        """Logs rows of a table on ``/<name>``, and the attitudes they carry on ``/tf`` and
        ``/attitude/<estimate>``; returns the number of messages."""
        return log_in_time_order(self.table_messages(name, columns, rows))

    def table_messages(self, name: str, columns: dict[str, np.ndarray],
                       rows: slice | np.ndarray = slice(None)) -> list[Messages]:
        """The messages of rows of a table: one per row on ``/<name>`` (every column under its own name,
        NaN as NaN), and the attitudes the rows carry (``attitude_messages``)."""
        values = timed(columns, rows)
        times = log_time_ns(self.origin, values["time_s"])
        channel, encoder = self._channel(f"/{name}", name, list(columns))
        streams = [_records(channel, encoder, times, values)]
        estimates = {n: np.column_stack([values[c] for c in q]) for n, q in estimates_in(name, columns).items()}
        return streams + self.attitude_messages(values["time_s"], times, estimates)

    def attitude_messages(self, time_s: np.ndarray, times: np.ndarray, estimates: dict[str, np.ndarray]) -> list[Messages]:
        """Each estimate (name -> (N, 4) w-first body -> NED) on ``/attitude/<name>`` and all of them on
        ``/tf`` (one ``FrameTransforms`` a row); a row where an estimate is NaN (not converged yet, a gap
        row) carries nothing of it."""
        from foxglove.messages import FrameTransform, FrameTransforms, Quaternion

        streams = []
        finite = {name: np.isfinite(q).all(axis=1) for name, q in estimates.items()}
        for name, q in estimates.items():
            yaw, pitch, roll = quaternion.euler_deg(q)
            angles = {"time_s": time_s, "pitch_deg": pitch, "roll_deg": roll, "yaw_deg": yaw}
            rows = np.flatnonzero(finite[name])
            channel, encoder = self._channel(f"/attitude/{name}", "attitude", list(angles))
            streams.append(_records(channel, encoder, times[rows], {c: v[rows] for c, v in angles.items()}))
        rows = np.flatnonzero(np.any(list(finite.values()), axis=0)) if estimates else np.zeros(0, dtype=int)

        def transforms(i: int) -> FrameTransforms:
            row, stamp = rows[i], _stamp(int(times[rows[i]]))
            return FrameTransforms(transforms=[
                FrameTransform(timestamp=stamp, parent_frame_id=NED_FRAME, child_frame_id=name,
                               rotation=Quaternion(w=float(q[row, 0]), x=float(q[row, 1]), y=float(q[row, 2]), z=float(q[row, 3])))
                for name, q in estimates.items() if finite[name][row]])

        return streams + [Messages(self._tf, times[rows], transforms)]

    def parameters(self, parameters: dict[str, float]) -> int:
        """Logs the autopilot's parameters (``parameters_messages``)."""
        return log_in_time_order([self.parameters_messages(parameters)])

    def parameters_messages(self, parameters: dict[str, float]) -> Messages:
        """The autopilot's parameters (name -> value) as one JSON message on ``/parameters`` at session
        time 0; a parameter without a value (NaN: JSON has none) is left out."""
        import foxglove

        if self._parameters is None:
            schema = {"type": "object", "title": "parameters", "additionalProperties": {"type": "number"}}
            self._parameters = foxglove.Channel("/parameters", schema=schema, context=self._context)
        values = json.dumps({name: v for name, v in parameters.items() if math.isfinite(v)}).encode()
        return Messages(self._parameters, np.array([self.origin], dtype=np.int64), lambda i: values)

    def events(self, events: list[dict], times_s: list[float]) -> int:
        """Logs events (``event_messages``); returns how many."""
        return log_in_time_order([self.event_messages(events, times_s)])

    def event_messages(self, events: list[dict], times_s: list[float]) -> Messages:
        """Each event as a Foxglove ``Log`` on ``/events`` at its session time: its message (or its
        fields) as text, its kind as the name, a level from the kind."""
        from foxglove.messages import Log, LogLevel

        times = log_time_ns(self.origin, np.asarray(times_s, dtype=float))

        def log(i: int) -> Log:
            kind = str(events[i].get("kind", ""))
            level = (LogLevel.Error if kind in _ERROR_KINDS else LogLevel.Warning if kind in _WARNING_KINDS
                     else LogLevel.Info)
            return Log(timestamp=_stamp(int(times[i])), level=level, message=event_text(events[i]), name=kind)

        return Messages(self._log, times, log)


def _records(channel, encoder: RowEncoder, times: np.ndarray, values: dict[str, np.ndarray]) -> Messages:
    """Rows encoded at once (``RowEncoder``); message ``i`` is its slice of the buffer."""
    buffer, size = encoder.encode(values), encoder.size
    return Messages(channel, times, lambda i: buffer[i * size:(i + 1) * size])


def _stamp(log_time_ns: int):
    from foxglove.messages import Timestamp

    return Timestamp(sec=log_time_ns // 1_000_000_000, nsec=log_time_ns % 1_000_000_000)


_EVENT_PLUMBING = frozenset({"kind", "t_s", "t_host_ns", "wall_time", "session_time_s"})


def event_text(event: dict) -> str:
    """What an event says: its message when it has one, else its fields (``kind: field value, ...``)."""
    if event.get("message"):
        return clean(str(event["message"]))  # a log's message can carry escape sequences (``text.clean``)
    fields = ", ".join(f"{k} {v}" for k, v in event.items() if k not in _EVENT_PLUMBING)
    return clean(f"{event.get('kind', 'event')}: {fields}" if fields else str(event.get("kind", "event")))
