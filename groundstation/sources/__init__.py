"""Where a session's bytes come from: a serial port, a UDP or TCP bridge, the simulated bridge, a
recording being replayed. ``open_source(spec)`` turns the string the user typed into one
(``spec.py`` holds the registry of schemes; docs/sources.md the table of forms).

Every source yields ``Chunk``s: the raw bytes as they arrived, stamped with the host's monotonic
clock at arrival (the I/O edge), and declares what it can do (``is_replay``, ``can_reopen``,
``can_send``). Nothing downstream knows which source it reads.
"""

from groundstation.sources.base import Chunk, Source, SourceClosed, SourceError
from groundstation.sources.replay import ReplaySource
from groundstation.sources.serial_port import SerialSource, list_ports
from groundstation.sources.spec import SCHEMES, open_source, parse_spec, whole_file

__all__ = ["SCHEMES", "Chunk", "ReplaySource", "SerialSource", "Source", "SourceClosed", "SourceError", "list_ports",
           "open_source", "parse_spec", "whole_file"]
