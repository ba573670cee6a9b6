"""The source interface."""

from __future__ import annotations

from typing import NamedTuple, Protocol

from groundstation.errors import UserError


class Chunk(NamedTuple):
    t_host_ns: int  # host monotonic clock (time.monotonic_ns) when the bytes arrived
    data: bytes


class SourceError(UserError):
    """The source cannot be opened or read (no such port, permission, unplugged): say which and why."""


class SourceClosed(Exception):
    """The source has ended (a replay reached its end, or close() was called)."""


class Source(Protocol):
    description: str  # for the user: port name and baud, recording path, "simulated bridge"

    def read(self) -> Chunk | None:
        """The next chunk, or None when nothing arrived within a short wait (≤ 0.1 s).

        Raises SourceError when the device is gone and SourceClosed at the end.
        """

    def write(self, data: bytes) -> None:
        """Send uplink bytes (commands); sources without an uplink ignore them."""

    def close(self) -> None: ...
