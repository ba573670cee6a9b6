"""Crash-safe recordings of a flight's raw link bytes (``.gsrec``); ``docs/recording-format.md``.

    with RecordingWriter(new_recording_path(default_recordings_dir(), start), metadata) as writer:
        writer.write_chunk(t_host_ns, data)
    recording = open_recording(path)   # .metadata, .chunks(), .events, .samples, .damage

A live session records through a ``Recorder``, which survives a failing disk (``recorder.py``).
"""

import importlib

# Each name's module, imported on first use: the reader imports numpy, which a command's ``--help``
# (it names the recording's suffix and magic) need not wait for.
_MODULES = {
    "EXTENSION": "format", "FORMAT_VERSION": "format", "RecordingError": "format",
    "default_recordings_dir": "paths", "new_recording_path": "paths", "Recording": "reader",
    "open_recording": "reader", "Recorder": "recorder", "RecordingWriter": "writer",
}


def __getattr__(name: str):
    if name not in _MODULES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"groundstation.recording.{_MODULES[name]}"), name)


__all__ = [
    "EXTENSION",
    "FORMAT_VERSION",
    "Recorder",
    "Recording",
    "RecordingError",
    "RecordingWriter",
    "default_recordings_dir",
    "new_recording_path",
    "open_recording",
]
