"""A ``.tlog`` opened as the live MAVLink session it records: its packets, at their receive times
(``autopilot.tlog.session_packets``: the compressed-clock rule), through a fresh pipeline's MAVLink
front-end, as a recording of that session replays. So the same bytes give the same tables and rows
whether they were recorded live (``.gsrec``) or saved as a ``.tlog`` (tests/autopilot/test_tlog_equals_live.py)."""

from __future__ import annotations

from pathlib import Path

from groundstation import formats
from groundstation.autopilot.flightlog import utc_text
from groundstation.autopilot.tlog import session_packets
from groundstation.errors import UserError
from groundstation.session_makers.load import SessionData, pipeline_product
from groundstation.session_makers.pipeline import DEFAULT_FILTERS, Pipeline
from groundstation.session_makers.replay import check_forced

PROGRESS_EVERY = 4096  # packets


def load(path, filters=None, forced=None, progress=None) -> SessionData:
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as error:
        raise UserError(f"{path}: cannot read ({error.strerror})") from None
    log = session_packets(data)
    if not log.packets:
        raise UserError(f"{path}: no MAVLink messages found; not a .tlog, or damaged from the start")
    filters = tuple(DEFAULT_FILTERS if filters is None else filters)
    check_forced(filters, forced)
    pipeline = Pipeline(filters, None, forced, protocol="mavlink")
    total = len(log.packets)
    for i, (t_host_ns, packet) in enumerate(log.packets):
        pipeline.feed(t_host_ns, packet)
        if progress is not None and i % PROGRESS_EVERY == 0:
            progress(i, total)
    if progress is not None:
        progress(total, total)
    notes, compressed = log.notes(), log.compressed
    del data, log  # the file's bytes and places go before the product is made of the pipeline's tables
    if pipeline.front.vehicle.sender is None:
        raise UserError(f"{path}: no autopilot found (no heartbeat naming ArduPilot or PX4, no IMU or attitude message)")
    metadata = {"source": f"{formats.FORMATS['tlog'].description} {path.name}", "protocol": "mavlink",
                "filters": list(filters)}
    if pipeline.t0_host_ns is not None:  # the receive clock is UTC: the session's start on it
        metadata["start_utc"] = utc_text(pipeline.t0_host_ns // 1000)
        metadata["start_utc_source"] = (".tlog receive time of the first packet, then the autopilot's clock (the "
                                        "receive times are compressed)" if compressed else ".tlog receive time")
    if notes:
        metadata["notes"] = "; ".join(notes)
    return pipeline_product(metadata, pipeline, notes)
