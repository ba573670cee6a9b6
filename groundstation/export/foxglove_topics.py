"""A session as Foxglove topics: the one mapping that the MCAP export and the live Foxglove bridge share.

- every table of the session: a JSON channel ``/<table>``, one message per row, every column under its
  own name (units in the names, as everywhere); NaN is ``null`` (JSON has no NaN); the channel's JSON
  schema gives each column's label and unit from the catalogue, so a plot panel lists them;
- every attitude estimate (each host estimator and the aircraft's own, ``onboard``): a Foxglove
  ``FrameTransform`` on ``/tf`` from ``ned`` to a frame named after the estimator (Foxglove's 3D panel
  shows them as axes), and its angles in degrees on ``/attitude/<name>`` (``pitch_deg``, ``roll_deg``,
  ``yaw_deg``, by ``quaternion.euler_deg``, the one conversion every view uses);
- every event (configuration, warnings, settings changes, autopilot messages, ...): a Foxglove ``Log``
  on ``/events``, its severity from its kind.

A message's log time is ``origin_ns`` plus its session time (the recording's ``start_utc`` for a file,
the wall clock at the session's first byte live), so Foxglove's timeline reads real time of day.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from datetime import datetime, timezone

import numpy as np

from groundstation import quaternion
from groundstation.session.catalogue import Catalogue
from groundstation.text import clean

NED_FRAME = "ned"  # the parent frame of every attitude: the quaternions are body -> NED (w-first)
# Event kinds a pilot must not miss are warnings; failures are errors; everything else is information.
_ERROR_KINDS = frozenset({"recording_failed", "disconnected"})
_WARNING_KINDS = frozenset({"warning", "config_conflict", "device_reset", "clock_jump", "gap"})


def origin_ns(metadata: dict, earliest_s: float = 0.0) -> int:
    """The wall-clock time of session time 0 in ns since the epoch: the recording's ``start_utc``; for a
    session that has none (a flight log, a dataset) the epoch, moved on by whole seconds when rows come
    before time 0 (``earliest_s`` < 0), since MCAP's log times cannot be negative."""
    try:
        start = datetime.fromisoformat(str(metadata.get("start_utc")))
    except ValueError:
        return math.ceil(max(0.0, -earliest_s)) * 1_000_000_000
    if start.tzinfo is None:
        start = start.replace(tzinfo=timezone.utc)
    return int(start.timestamp() * 1e9)


def earliest_time_s(tables: dict[str, dict[str, np.ndarray]]) -> float:
    """The earliest session time in any table (0 when none is earlier)."""
    firsts = [np.nanmin(t["time_s"]) for t in tables.values() if np.isfinite(t["time_s"]).any()]
    return min([0.0, *firsts])


def log_time_ns(origin: int, time_s: np.ndarray) -> np.ndarray:
    """Session times as log times (int64 ns). Rows without a time (NaN) keep the origin."""
    offsets = np.nan_to_num(np.asarray(time_s, dtype=float) * 1e9, nan=0.0)
    return origin + np.rint(offsets).astype(np.int64)


def json_schema(catalogue: Catalogue, table: str) -> dict:
    """A channel's JSON schema: each column a number (or null for NaN), described by its label and unit."""
    columns = catalogue[table].columns if table in catalogue else ()
    properties = {c.name: {"type": ["number", "null"], "description": c.header} for c in columns}
    return {"type": "object", "title": table, "properties": properties}


def row_payloads(columns: dict[str, np.ndarray], rows: slice | np.ndarray = slice(None)) -> Iterable[bytes]:
    """Each row of a table as a JSON object (NaN as null), encoded: the payload of one message.

    Floats go out as Python's shortest round-trip text, so a reader gets the float64 written, bit for bit."""
    names = list(columns)
    values = [np.asarray(columns[n], dtype=float)[rows].tolist() for n in names]
    for row in zip(*values):
        yield json.dumps({n: (v if math.isfinite(v) else None) for n, v in zip(names, row)}).encode()


def estimates_in(table: str, columns) -> dict[str, tuple[str, str, str, str]]:
    """The attitude estimates a table carries: ``<name>_qw`` .. ``_qz`` (each host estimator in ``imu``),
    or ``qw`` .. ``qz`` (the aircraft's own in ``onboard``, named after its table)."""
    names = {c[:-3] for c in columns if c.endswith("_qw")}
    found = {n: tuple(f"{n}_q{c}" for c in "wxyz") for n in sorted(names)}
    if "qw" in columns:
        found[table] = ("qw", "qx", "qy", "qz")
    return {n: q for n, q in found.items() if all(c in columns for c in q)}


class Topics:
    """The session's channels in a foxglove ``Context``: an MCAP writer or a WebSocket server opened on
    the same context receives what is logged here."""

    def __init__(self, context, catalogue: Catalogue, origin: int):
        import foxglove
        from foxglove.channels import FrameTransformsChannel, LogChannel

        self._foxglove = foxglove
        self._context = context
        self.catalogue = catalogue
        self.origin = origin
        self._channels: dict[str, object] = {}
        self._tf = FrameTransformsChannel("/tf", context=context)
        self._log = LogChannel("/events", context=context)

    def _channel(self, topic: str, schema: dict):
        if topic not in self._channels:
            self._channels[topic] = self._foxglove.Channel(topic, schema=schema, context=self._context)
        return self._channels[topic]

    def advertise(self, tables) -> None:
        """Opens the channels of these tables now (a live client subscribes before their first rows)."""
        for name in tables:
            self._channel(f"/{name}", json_schema(self.catalogue, name))

    def rows(self, name: str, columns: dict[str, np.ndarray], rows: slice | np.ndarray = slice(None)) -> int:
        """Logs rows of a table on ``/<name>``, and the attitudes they carry on ``/tf`` and
        ``/attitude/<estimate>``; returns the number of messages."""
        channel = self._channel(f"/{name}", json_schema(self.catalogue, name))
        time_s = np.asarray(columns["time_s"], dtype=float)[rows]
        times = log_time_ns(self.origin, time_s)
        count = 0
        for log_time, payload in zip(times.tolist(), row_payloads(columns, rows)):
            channel.log(payload, log_time=log_time)
            count += 1
        estimates = {n: np.column_stack([np.asarray(columns[c], dtype=float)[rows] for c in q])
                     for n, q in estimates_in(name, columns).items()}
        return count + self._attitudes(time_s, times, estimates)

    def _attitudes(self, time_s: np.ndarray, times: np.ndarray, estimates: dict[str, np.ndarray]) -> int:
        """Each estimate (name -> (N, 4) w-first body -> NED) on ``/tf`` and ``/attitude/<name>``; a row
        where an estimate is NaN (not converged yet, a gap row) carries no transform for it."""
        from foxglove.messages import FrameTransform, FrameTransforms, Quaternion

        count = 0
        finite = {name: np.isfinite(q).all(axis=1) for name, q in estimates.items()}
        for name, q in estimates.items():
            yaw, pitch, roll = quaternion.euler_deg(q)
            angles = {"time_s": time_s, "pitch_deg": pitch, "roll_deg": roll, "yaw_deg": yaw}
            rows = np.flatnonzero(finite[name])
            channel = self._channel(f"/attitude/{name}", _ANGLES_SCHEMA)
            for log_time, payload in zip(times[rows].tolist(), row_payloads(angles, rows)):
                channel.log(payload, log_time=log_time)
                count += 1
        for i, log_time in enumerate(times.tolist()):
            transforms = [FrameTransform(timestamp=_stamp(log_time), parent_frame_id=NED_FRAME, child_frame_id=name,
                                         rotation=Quaternion(w=float(q[i, 0]), x=float(q[i, 1]), y=float(q[i, 2]),
                                                             z=float(q[i, 3])))
                          for name, q in estimates.items() if finite[name][i]]
            if transforms:
                self._tf.log(FrameTransforms(transforms=transforms), log_time=log_time)
                count += 1
        return count

    def parameters(self, parameters: dict[str, float]) -> int:
        """The autopilot's parameters (name -> value) as one message on ``/parameters`` at session time 0."""
        schema = {"type": "object", "title": "parameters", "additionalProperties": {"type": ["number", "null"]}}
        values = {name: (v if math.isfinite(v) else None) for name, v in parameters.items()}
        self._channel("/parameters", schema).log(json.dumps(values).encode(), log_time=self.origin)
        return 1

    def events(self, events: Iterable[dict], times_s: Iterable[float]) -> int:
        """Each event as a Foxglove ``Log`` on ``/events`` at its session time: its message (or its
        fields) as text, its kind as the name, a level from the kind."""
        from foxglove.messages import Log, LogLevel

        count = 0
        for event, time_s in zip(events, times_s):
            log_time = int(log_time_ns(self.origin, np.array([time_s]))[0])
            kind = str(event.get("kind", ""))
            level = (LogLevel.Error if kind in _ERROR_KINDS else LogLevel.Warning if kind in _WARNING_KINDS
                     else LogLevel.Info)
            self._log.log(Log(timestamp=_stamp(log_time), level=level, message=event_text(event), name=kind),
                          log_time=log_time)
            count += 1
        return count


def _stamp(log_time_ns: int):
    from foxglove.messages import Timestamp

    return Timestamp(sec=log_time_ns // 1_000_000_000, nsec=log_time_ns % 1_000_000_000)


_ANGLES_SCHEMA = {"type": "object", "title": "attitude", "properties": {
    "time_s": {"type": "number", "description": "time (s)"},
    **{f"{a}_deg": {"type": ["number", "null"], "description": f"{a} (°)"} for a in ("pitch", "roll", "yaw")}}}
_EVENT_PLUMBING = frozenset({"kind", "t_s", "t_host_ns", "wall_time", "session_time_s"})


def event_text(event: dict) -> str:
    """What an event says: its message when it has one, else its fields (``kind: field value, ...``)."""
    if event.get("message"):
        return clean(str(event["message"]))  # a log's message can carry escape sequences (``text.clean``)
    fields = ", ".join(f"{k} {v}" for k, v in event.items() if k not in _EVENT_PLUMBING)
    return clean(f"{event.get('kind', 'event')}: {fields}" if fields else str(event.get("kind", "event")))
