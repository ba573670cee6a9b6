"""Where a session's bytes come from: a serial port, a recording being replayed, the simulated bridge.

Every source yields ``Chunk``s: the raw bytes as they arrived, stamped with the host's monotonic
clock at arrival (the I/O edge). Nothing downstream knows which source it reads.
"""

from groundstation.sources.base import Chunk, Source, SourceClosed, SourceError
from groundstation.sources.mavlink import open_mavlink
from groundstation.sources.replay import ReplaySource
from groundstation.sources.serial_port import SerialSource, list_ports

__all__ = ["Chunk", "ReplaySource", "SerialSource", "Source", "SourceClosed", "SourceError", "list_ports", "open_mavlink"]
