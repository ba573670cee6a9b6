"""Crash-safe recordings of a flight's raw link bytes (``.gsrec``); ``docs/recording-format.md``.

    with RecordingWriter(new_recording_path(default_recordings_dir(), start), metadata) as writer:
        writer.write_chunk(t_host_ns, data)
    recording = open_recording(path)   # .metadata, .chunks(), .events, .samples, .damage

A live session records through a ``Recorder``, which survives a failing disk (``recorder.py``).
"""

from groundstation.recording.format import EXTENSION, FORMAT_VERSION, RecordingError
from groundstation.recording.paths import default_recordings_dir, new_recording_path
from groundstation.recording.reader import Recording, open_recording
from groundstation.recording.recorder import Recorder
from groundstation.recording.writer import RecordingWriter

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
