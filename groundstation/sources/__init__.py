"""Where a session's bytes come from: a serial port, a UDP or TCP bridge, the simulated bridge, a
recording being replayed. ``open_source(spec)`` turns the string the user typed into one
(``spec.py`` holds the registry of schemes; docs/sources.md the table of forms).

Every source yields ``Chunk``s: the raw bytes as they arrived, stamped with the host's monotonic
clock at arrival (the I/O edge), and declares what it can do (``is_replay``, ``can_reopen``,
``can_send``). Nothing downstream knows which source it reads.
"""

import importlib

# Each name's module, imported on first use: a replay imports numpy, which a command's ``--help`` (it lists
# the source forms, ``spec.source_forms``) need not wait for.
_MODULES = {
    "Chunk": "base", "Source": "base", "SourceClosed": "base", "SourceError": "base", "ReplaySource": "replay",
    "SerialSource": "serial_port", "list_ports": "serial_port", "SCHEMES": "spec", "open_source": "spec",
    "parse_spec": "spec", "source_forms": "spec", "whole_file": "spec",
}


def __getattr__(name: str):
    if name not in _MODULES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"groundstation.sources.{_MODULES[name]}"), name)


__all__ = ["SCHEMES", "Chunk", "ReplaySource", "SerialSource", "Source", "SourceClosed", "SourceError", "list_ports",
           "open_source", "parse_spec", "source_forms", "whole_file"]
