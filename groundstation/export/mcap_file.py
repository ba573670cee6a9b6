"""A session to an MCAP file, which Foxglove, Lichtblick, PlotJuggler and Rerun open.

The topics are ``foxglove_topics``' (the same the live bridge serves); the file is written by
foxglove-sdk's writer (Foxglove's own, with the well-known schemas) to a temporary name and renamed when
complete (``files.atomic_output``).
"""

from __future__ import annotations

import numpy as np

from groundstation.errors import UserError
from groundstation.export.files import atomic_output
from groundstation.export.foxglove_topics import Topics, earliest_time_s, log_in_time_order, origin_ns, time_metadata
from groundstation.session.product import SessionData, event_time_s


def in_range(time_s: np.ndarray, t_from: float | None, t_to: float | None) -> np.ndarray:
    """Indices of the rows in [t_from, t_to] (every row when neither is given)."""
    keep = np.ones(len(time_s), dtype=bool)
    if t_from is not None:
        keep &= time_s >= t_from
    if t_to is not None:
        keep &= time_s <= t_to
    return np.flatnonzero(keep)


CHUNK_BYTES = 256 * 1024  # uncompressed: a few seconds of a busy log a chunk, so a seek reads little


def export_mcap(data: SessionData, request, writing, cancel) -> tuple[str, list[str]]:
    """``write_mcap`` as ``export.request.FORMATS`` calls it."""
    writing(0, 1)
    messages = write_mcap(data, request.out, request.overwrite, request.t_from, request.t_to)
    writing(1, 1)
    return f"{messages} messages on {len(data.tables)} tables, /tf, /attitude/* and /events", []


def write_mcap(data: SessionData, path, overwrite: bool = False, t_from: float | None = None,
               t_to: float | None = None) -> int:
    """Writes every table, every attitude and every event of ``data`` between ``t_from`` and ``t_to``
    (session seconds) to ``path``, in log-time order across channels; returns the number of messages.
    The file's ``time`` metadata says what its log times are on (``origin_ns``)."""
    import foxglove
    from foxglove.mcap import MCAPWriteOptions

    origin = origin_ns(data.metadata, earliest_time_s(data.tables))
    check_log_times(origin, data, path)
    with atomic_output(path, overwrite) as temporary:
        context = foxglove.Context()
        writer = foxglove.open_mcap(temporary, allow_overwrite=True, context=context,
                                    writer_options=MCAPWriteOptions(chunk_size=CHUNK_BYTES))
        try:
            writer.write_metadata("session", {str(k): str(v) for k, v in data.metadata.items()})
            writer.write_metadata("time", time_metadata(data.metadata, origin))
            topics = Topics(context, data.catalogue, origin)
            streams = [s for name, columns in data.tables.items()
                       for s in topics.table_messages(name, columns, in_range(columns["time_s"], t_from, t_to))]
            if data.parameters:  # the autopilot's parameters (last values; their changes are /events)
                writer.write_metadata("parameters", {name: repr(value) for name, value in data.parameters.items()})
                streams.append(topics.parameters_messages(data.parameters))
            times = np.array([event_time_s(e) for e in data.events])
            chosen = in_range(times, t_from, t_to)
            streams.append(topics.event_messages([data.events[i] for i in chosen], times[chosen]))
            count = log_in_time_order(streams)
        finally:
            writer.close()
    return count


LAST_LOG_TIME_NS = 2**63 - 1  # log times are int64 ns since 1970 on the way to the writer (``log_time_ns``): to 2262


def check_log_times(origin: int, data: SessionData, path) -> None:
    """UserError when a row or an event of ``data`` lies later than an MCAP log time can say (a log whose
    clock says it ran for 292,000 years: crafted or damaged)."""
    times = [np.asarray(t["time_s"], dtype=float) for t in data.tables.values()]
    times.append(np.array([event_time_s(e) for e in data.events], dtype=float))
    latest_s = max((float(np.nanmax(t)) for t in times if np.isfinite(t).any()), default=0.0)
    if origin + latest_s * 1e9 > LAST_LOG_TIME_NS:
        raise UserError(f"cannot write {path}: this session's times reach {latest_s:.3g} s, beyond what an MCAP log "
                        "time holds (ns since 1970 in 64 bits, to the year 2262); export it as CSV or Parquet")
