"""The source interface: what every input declares about itself, so callers never guess."""

from __future__ import annotations

from typing import NamedTuple, Protocol

from groundstation.errors import UserError


class Chunk(NamedTuple):
    t_host_ns: int  # host monotonic clock (time.monotonic_ns) when the bytes arrived
    data: bytes


class SourceError(UserError):
    """The source cannot be opened, read or written (no such port, permission, unplugged, no uplink):
    say which and why."""


class SourceClosed(Exception):
    """The source has ended (a replay reached its end, or close() was called)."""


class Source(Protocol):
    description: str  # for the user: port name and baud, recording path, "simulated bridge"
    is_replay: bool  # a recording played back (it has ``recording``; a session does not record it again)
    can_reopen: bool  # after a SourceError from read(), reopen() may bring it back (a re-plugged adapter)
    can_send: bool  # write() reaches an aircraft; False: write() raises SourceError (the UI disables uplink)

    def read(self) -> Chunk | None:
        """The next chunk, or None when nothing arrived within a short wait (≤ 0.1 s).

        Raises SourceError when the device is gone and SourceClosed at the end.
        """

    def write(self, data: bytes) -> None:
        """Send uplink bytes (commands); SourceError when they cannot be sent."""

    def reopen(self) -> None:
        """Open again after a SourceError from read(); SourceError while it is still gone."""

    def close(self) -> None: ...


def refuse_uplink(source: Source) -> None:
    """``write`` of a source with ``can_send`` False: one clear message for all of them."""
    raise SourceError(f"{source.description} has no uplink: commands cannot be sent to it")


def refuse_reopen(source: Source) -> None:
    """``reopen`` of a source with ``can_reopen`` False."""
    raise SourceError(f"{source.description} cannot be reopened")
