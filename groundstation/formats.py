"""The file formats a session is opened from: one registry line each (``FORMATS``), one loader module.

As PlotJuggler's ``DataLoader::compatibleFileExtensions()``: each format says its suffixes, what it is,
the first bytes its files start with (when they have any) and the loader that turns a file into the
session product, ``load(path, filters, forced, progress) -> SessionData`` (``loaders``, or
``session_makers.flight_log_session.load_log`` for flight logs, which also name their reader into a ``FlightLog``).
The app's Open dialog, the CLI's help and ``session_makers.load.load_session`` (which the app, ``export``,
``evaluate`` and ``replay`` open files with) derive from it; so do ``sources`` (which files replay as a
link) and ``session_makers.flight_log_session.read_log`` (which reader a flight log takes). A new format is its loader module
and one ``register`` line here (or a call from anywhere, before the file is opened).

Loaders and readers are named as ``"module:function"`` and imported on first use: this module imports
nothing of the session or the readers (it sits below them), so they can look formats up without an
import circle. The flight-log readers check the first bytes registered here.
"""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Callable
from pathlib import Path

from groundstation.recording.format import MAGIC as RECORDING_MAGIC

# The aiding a file opened whole is counted on to give the estimators: a magnetometer, but no GPS fit for
# aiding (a tlog's GPS has no vertical speed, a dataset none), so the GPS-aided filters (slow tilt filters
# without it, at ~100x the others' cost) run only when asked for (``estimation.runnable``).
FILE_AIDING = frozenset({"mag"})
# What a flight log's estimators run on: its logged IMU, or its full-rate one (``session_makers.flight_log_session``): here,
# where the command line's help can name them without importing the readers.
IMU_STREAMS = ("regular", "fast")


@dataclasses.dataclass(frozen=True)
class FileFormat:
    name: str
    suffixes: tuple[str, ...]  # lower case with the dot; a file takes the format of its longest matching suffix
    description: str  # what the user calls it
    load: str | Callable  # (path, filters, forced, progress) -> SessionData, or "module:function" naming it
    magic: bytes = b""  # what every file of the format starts with (b"": nothing certain)
    replayable: bool = False  # its bytes replay as a live link (``sources``), and it records its estimators
    read: str | Callable | None = None  # a flight log's reader, (path, progress) -> autopilot.flightlog.FlightLog

    def loader(self) -> Callable:
        return resolve(self.load)

    def reader(self) -> Callable | None:
        return None if self.read is None else resolve(self.read)

    def patterns(self) -> str:
        return " ".join(f"*{suffix}" for suffix in self.suffixes)


FORMATS: dict[str, FileFormat] = {}


def register(file_format: FileFormat) -> FileFormat:
    FORMATS[file_format.name] = file_format
    return file_format


register(FileFormat("recording", (".gsrec",), "recording", "groundstation.session_makers.loaders.recording:load",
                    magic=RECORDING_MAGIC, replayable=True))
register(FileFormat("dataset", (".csv", ".csv.gz", ".gz"), "dataset CSV", "groundstation.session_makers.loaders.dataset_csv:load"))
register(FileFormat("tlog", (".tlog",), "MAVLink telemetry log", "groundstation.session_makers.loaders.tlog:load",
                    read="groundstation.autopilot.tlog:read_tlog"))
register(FileFormat("dataflash", (".bin",), "ArduPilot DataFlash log", "groundstation.session_makers.flight_log_session:load_log",
                    magic=b"\xa3\x95", read="groundstation.autopilot.dataflash:read_dataflash"))
register(FileFormat("ulog", (".ulg",), "PX4 ULog", "groundstation.session_makers.flight_log_session:load_log",
                    magic=b"ULog\x01\x12\x35", read="groundstation.autopilot.ulog:read_ulog"))


def sniff(path) -> FileFormat | None:
    """The format of ``path``: by its suffix, else by its first bytes; None when neither tells."""
    name = Path(path).name.lower()
    by_suffix = [(len(s), f) for f in FORMATS.values() for s in f.suffixes if name.endswith(s)]
    if by_suffix:
        return max(by_suffix, key=lambda pair: pair[0])[1]
    try:
        with open(path, "rb") as file:
            head = file.read(max((len(f.magic) for f in FORMATS.values()), default=0))
    except OSError:
        return None
    return next((f for f in FORMATS.values() if f.magic and head.startswith(f.magic)), None)


def flight_logs() -> list[FileFormat]:
    return [f for f in FORMATS.values() if f.read is not None]


def described(formats=None) -> str:
    """``"recording (.gsrec), dataset CSV (.csv, .csv.gz, .gz), …"`` for help texts and messages."""
    return ", ".join(f"{f.description} ({', '.join(f.suffixes)})" for f in (FORMATS.values() if formats is None else formats))


def dialog_filter() -> str:
    """The Open dialog's name filters: every format together, each on its own, any file."""
    every = " ".join(f.patterns() for f in FORMATS.values())
    return ";;".join([f"Recordings and flight logs ({every})", *(f"{f.description} ({f.patterns()})" for f in FORMATS.values()),
                      "All files (*)"])


def resolve(target: str | Callable) -> Callable:
    """``target`` itself, or the function a ``"module:function"`` string names, imported now: how this registry
    and ``export.request.FORMATS`` name their functions, so as to import nothing heavy until one is used."""
    if callable(target):
        return target
    module, _, function = target.partition(":")
    return getattr(importlib.import_module(module), function)
