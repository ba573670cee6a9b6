"""What the window reads of a session, live or played back from a file: one view, two makers.

A live session (``live.LiveSession``) shows its pipeline's product as it grows; a file
(``playback.RevealSession``) shows a computed ``SessionData`` up to the playback clock. Both give
the window a ``Session`` whose ``view`` is a ``ProductView``: the same tables, events and figures, so
the window never asks which kind it holds, and never reads a pipeline. No Qt here.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Protocol

from groundstation.session_parts.catalogue import Catalogue


class LinkView(Protocol):
    """Link figures (``session_parts.link.LinkStats`` live, ``playback.RevealedLink`` from a file)."""

    per_second: object  # a table of ``link.PER_SECOND_COLUMNS``
    last_chunk_ns: int | None

    def clock(self) -> dict[str, float]: ...
    def rates(self) -> dict[str, float]: ...
    def since_last_frame_s(self, now_ns: int) -> float: ...


class ProductView(Protocol):
    """The product so far: tables (``len``, ``tail``, ``column``, ``to_dict``) as ``catalogue`` describes them."""

    tables: dict
    catalogue: Catalogue
    filters: tuple[str, ...]
    imu: object
    onboard: object
    events: list[dict]
    parameters: dict[str, float]  # an autopilot's, name -> value (``SessionData.parameters``)
    parameter_defaults: dict[str, float]  # name -> default where the log says it (``SessionData.parameter_defaults``)
    config: dict | None
    protocol: str | None
    t0_host_ns: int | None  # None: every event carries its ``session_time_s``
    link: LinkView | None  # None: a file with no link in it (a flight log, a dataset)

    def counters(self) -> dict[str, int]: ...  # the decoder's totals: frames, crc_errors, frames_lost, bytes_skipped
    def settings(self) -> dict[str, dict[str, float]]: ...
    def uncompiled(self) -> tuple[str, ...]: ...  # estimators whose compiled kernels are not there yet (a first start)


def event_session_time_s(view: ProductView, event: dict) -> float:
    """Seconds into the session: the clock's own when the event carries it, else the host time since
    the session's first chunk (to a few ms the session time of the samples that came with it)."""
    if "session_time_s" in event:
        return float(event["session_time_s"])
    t0_ns = view.t0_host_ns
    if t0_ns is None or not event.get("t_host_ns"):
        return 0.0
    return max((event["t_host_ns"] - t0_ns) / 1e9, 0.0)


class Session(Protocol):
    """What the window holds. ``seekable``: a file's playback (``seek`` moves its clock; its ``data``, the
    whole file's product, ``playback.RevealSession``; live: never);
    ``setup``: the estimators and forced settings a file was computed with (live: ``(None, None)``)."""

    view: ProductView
    source: object  # ``description``, ``is_replay``, ``can_send``
    lock: threading.Lock
    connected: bool
    error: str | None
    recorder: object | None
    seekable: bool
    setup: tuple
    heard_protocol: str | None  # "mavlink": a source opened for the project's bridge hears an autopilot instead

    @property
    def running(self) -> bool: ...
    @property
    def recording_path(self) -> Path | None: ...
    def advance(self) -> None: ...
    def seek(self, t_s: float) -> bool: ...
    def file(self) -> tuple[Path, float] | None: ...
    def stop(self) -> None: ...
    def held_config(self) -> str | None: ...  # what a CONFIG awaiting the user's answer changes (``ConfigGuard``)
    def resolve_config(self, accept: bool) -> None: ...
