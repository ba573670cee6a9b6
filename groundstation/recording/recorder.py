"""A live session's recording, which never stops the session it records.

When a write fails (a full disk, a removed USB stick, a quota), the recorder closes the file, which
keeps everything written before the failure and still opens, reports a ``recording_failed`` event,
and goes on accepting chunks without writing them: decoding and display are not its business and
go on. It resumes into a new file (a ``recording_resumed`` event, also written into that file) on
``start()`` (the user's "Resume recording") or by itself once the folder has room again.

Not locked on its own: the live session calls it under the session's lock. Other threads may read
``state``, ``path``, ``bytes_written`` and ``error`` at any time.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable
from datetime import datetime, timezone
from pathlib import Path

from groundstation.recording.format import RecordingError
from groundstation.recording.paths import new_recording_path
from groundstation.recording.writer import RecordingWriter

RETRY_INTERVAL_S = 5.0  # how often a failed recorder looks for room again
# Resume only with this much free room: a disk with a few kB left would fail again at once,
# leaving a trail of tiny files.
RESUME_MIN_FREE_BYTES = 8 * 1024 * 1024


class Recorder:
    """Records into ``folder`` (a new file per start); ``metadata()`` gives each file's header.

    ``state``: "off" (not started, or stopped), "recording", or "failed" (``error`` says why);
    ``path``: the current file, or the last one; ``paths``: every file, in order; ``bytes_written``:
    the bytes in ``path``. ``on_event(event)`` receives ``recording_failed`` and ``recording_resumed``.
    ``retry_interval_s=None`` leaves resuming to ``start()``.
    """

    def __init__(self, folder, metadata: Callable[[], dict], on_event: Callable[[dict], None] = lambda event: None,
                 retry_interval_s: float | None = RETRY_INTERVAL_S, min_free_bytes: int = RESUME_MIN_FREE_BYTES):
        self.folder = Path(folder)
        self.metadata = metadata
        self.on_event = on_event
        self.retry_interval_s = retry_interval_s
        self.min_free_bytes = min_free_bytes
        self.state = "off"
        self.path: Path | None = None
        self.paths: list[Path] = []
        self.error: str | None = None
        self._writer: RecordingWriter | None = None
        self._bytes_of_last_file = 0
        self._last_attempt_ns = 0
        self._t_host_ns = 0  # the newest time seen, for the events

    @property
    def bytes_written(self) -> int:
        writer = self._writer
        return writer.bytes_written if writer is not None else self._bytes_of_last_file

    def start(self) -> bool:
        """Starts recording into a new file (after a failure: resumes); False, with ``error``, if it cannot."""
        if self.state == "recording":
            return True
        self._last_attempt_ns = time.monotonic_ns()
        failed_path, failure = (self.path, self.error) if self.state == "failed" else (None, None)
        try:
            path = new_recording_path(self.folder, datetime.now(timezone.utc))
            self._writer = RecordingWriter(path, self.metadata())
        except (RecordingError, OSError) as error:
            message = str(error) if isinstance(error, RecordingError) else f"cannot record into {self.folder}: {error.strerror}"
            if self.state != "failed":  # one event per failure, not one per attempt to resume
                self._fail(message)
            self.error = message
            return False
        self.path = path
        self.paths.append(path)
        self.state, self.error = "recording", None
        if failed_path is not None or failure is not None:
            event = {"kind": "recording_resumed", "t_host_ns": self._t_host_ns, "path": str(path),
                     "previous_path": None if failed_path is None else str(failed_path), "failure": failure}
            self.write_event(self._t_host_ns, event)
            self.on_event(event)
        return True

    def stop(self) -> None:
        """Closes the file (its END record says it was closed); the state is "off" afterwards."""
        writer, self._writer = self._writer, None
        if writer is not None:
            self._bytes_of_last_file = writer.bytes_written
            try:
                writer.close()
            except RecordingError as error:
                self.error = str(error)
                self.on_event(self._failure_event(str(error)))
        self.state = "off"

    def write_chunk(self, t_host_ns: int, data: bytes) -> None:
        self._t_host_ns = t_host_ns
        if self.state == "failed" and self._time_to_resume():
            self.start()
        if self._writer is None:
            return
        try:
            self._writer.write_chunk(t_host_ns, data)
        except RecordingError as error:
            self._fail(str(error))

    def write_event(self, t_host_ns: int, event: dict) -> None:
        if self._writer is None:
            return
        try:
            self._writer.write_event(t_host_ns, event)
        except RecordingError as error:
            self._fail(str(error))

    def _fail(self, message: str) -> None:
        """Keeps what the file holds (closing it as well as the disk allows) and says why it stopped."""
        writer, self._writer = self._writer, None
        if writer is not None:
            self._bytes_of_last_file = writer.bytes_written
            try:
                writer.close()
            except RecordingError:
                pass  # the same cause as ``message``; whatever reached the file stays readable
        self.state, self.error = "failed", message
        self._last_attempt_ns = time.monotonic_ns()
        self.on_event(self._failure_event(message))

    def _failure_event(self, message: str) -> dict:
        return {"kind": "recording_failed", "t_host_ns": self._t_host_ns, "message": message,
                "path": None if self.path is None else str(self.path), "bytes_written": self.bytes_written}

    def _time_to_resume(self) -> bool:
        if self.retry_interval_s is None or time.monotonic_ns() - self._last_attempt_ns < self.retry_interval_s * 1e9:
            return False
        self._last_attempt_ns = time.monotonic_ns()
        try:
            return shutil.disk_usage(self.folder).free >= self.min_free_bytes
        except OSError:
            return False  # the folder is gone (an unplugged stick): try again later
