"""Append-only, crash-safe writing of a recording.

Crash safety: every record reaches the operating system within ``FLUSH_INTERVAL_NS`` of being
written (a flush on write once that much time has passed, and a background flush for when the
link goes quiet), so a ``kill -9`` loses at most the last ~0.25 s. The OS writes its cache out
even if the process dies; only power loss needs ``fsync=True``, which syncs at every flush.
"""

from __future__ import annotations

import json
import os
import threading
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from firmware_protocol import SPEC
from groundstation import __version__
from groundstation.recording import samples
from groundstation.recording.format import (
    FORMAT_VERSION,
    MAX_PAYLOAD_BYTES,
    Kind,
    RecordingError,
    encode_preamble,
    encode_record,
)

FLUSH_INTERVAL_NS = 250_000_000
CHUNK_SPLIT_BYTES = MAX_PAYLOAD_BYTES - 8  # a bigger read becomes several chunks, same t_host_ns


def utc_now_iso() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def full_metadata(metadata: dict) -> dict:
    """The caller's metadata plus the fields every recording carries (these override the caller's)."""
    if not isinstance(metadata, dict):
        raise TypeError(f"recording metadata must be a dict, not {type(metadata).__name__}")
    out = {"start_utc": utc_now_iso(), **metadata}
    out.update(
        format="groundstation recording",
        format_version=FORMAT_VERSION,
        app_version=__version__,
        protocol_version=SPEC.protocol_version,
        protocol_fingerprint=SPEC.fingerprint,
    )
    return out


def encode_json(value: dict, what: str) -> bytes:
    if not isinstance(value, dict):
        raise TypeError(f"a recording {what} must be a dict, not {type(value).__name__}")
    # allow_nan=False: NaN is not JSON, and other readers of the file would choke on it.
    payload = json.dumps(value, ensure_ascii=False, allow_nan=False, separators=(",", ":")).encode()
    if len(payload) > MAX_PAYLOAD_BYTES:
        raise ValueError(f"a recording {what} must stay under {MAX_PAYLOAD_BYTES} bytes of JSON")
    return payload


class RecordingWriter:
    """Writes a new recording at ``path`` (never overwrites); use as a context manager.

    ``metadata``: what the caller knows at the start (port, baud, mounting, estimator settings,
    ...); ``start_utc`` (ISO 8601) defaults to now. Thread-safe: one thread may write chunks while
    another writes events.
    """

    def __init__(self, path, metadata: dict, *, fsync: bool = False):
        self.path = Path(path)
        self.fsync = fsync
        header = encode_json(full_metadata(metadata), "metadata")
        try:
            self._file = open(self.path, "xb")
        except FileExistsError:
            raise RecordingError(f"{self.path} already exists; a recording is never overwritten") from None
        except OSError as error:
            raise RecordingError(f"cannot create the recording {self.path}: {error.strerror}") from None
        self._lock = threading.Lock()
        self._closed = threading.Event()
        self._background_error: RecordingError | None = None
        self.bytes_written = self._bytes_flushed = 0
        try:
            self._write(encode_preamble())
            self._write(encode_record(Kind.METADATA, time.monotonic_ns(), header))
            self._flush()  # the header is on disk before the first byte of the flight
        except RecordingError:
            # Without its header the file holds nothing of the flight: leave no empty file behind
            # (a full disk would otherwise collect one at every attempt to resume).
            self._close_file_quietly()
            self.path.unlink(missing_ok=True)
            raise
        self._flusher = threading.Thread(target=self._flush_periodically, name="recording-flush", daemon=True)
        self._flusher.start()

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def write_chunk(self, t_host_ns: int, data: bytes) -> None:
        """Raw link bytes as received, stamped with the host monotonic clock on arrival."""
        data = bytes(data)
        for start in range(0, max(len(data), 1), CHUNK_SPLIT_BYTES):  # an empty read is kept too
            self._append(encode_record(Kind.CHUNK, int(t_host_ns), data[start:start + CHUNK_SPLIT_BYTES]))

    def write_event(self, t_host_ns: int, event: dict) -> None:
        """A JSON object: a change of settings, a connection event, a note."""
        self._append(encode_record(Kind.EVENT, int(t_host_ns), encode_json(event, "event")))

    def write_samples(self, columns: dict[str, np.ndarray]) -> None:
        """Named 1-D numeric columns of equal length, stored as float64 bit for bit (imports)."""
        t_host_ns = time.monotonic_ns()
        records = [encode_record(Kind.SAMPLES, t_host_ns, p) for p in samples.encode_blocks(samples.as_float64_columns(columns))]
        self._append(b"".join(records))

    def close(self) -> None:
        """Writes the END record and flushes (and syncs); safe to call twice."""
        with self._lock:
            if self._closed.is_set():
                return
            self._closed.set()
            try:
                self._raise_background_error()
                self._write(encode_record(Kind.END, time.monotonic_ns(), b""))
                self._flush()
            finally:
                self._close_file_quietly()
        self._flusher.join()

    def _close_file_quietly(self) -> None:
        """Closes the file even when its last buffered bytes cannot be written (a full disk): those
        are lost either way, what reached the file stays readable, and the caller gets a RecordingError."""
        try:
            self._file.close()
        except OSError:
            pass

    def _append(self, record: bytes) -> None:
        with self._lock:
            if self._closed.is_set():
                raise ValueError(f"the recording {self.path} is closed")
            self._raise_background_error()
            self._write(record)
            # Also here, not only in the background thread: a busy process may starve that thread.
            if time.monotonic_ns() - self._last_flush_ns >= FLUSH_INTERVAL_NS:
                self._flush()

    def _write(self, data: bytes) -> None:
        try:
            self._file.write(data)
        except OSError as error:
            raise RecordingError(f"writing the recording {self.path} failed: {error.strerror}") from None
        self.bytes_written += len(data)

    def _flush(self) -> None:
        """The caller holds the lock, or is the constructor before the flusher thread exists."""
        try:
            self._file.flush()
            if self.fsync:
                os.fsync(self._file.fileno())
        except OSError as error:
            raise RecordingError(f"writing the recording {self.path} failed: {error.strerror}") from None
        self._last_flush_ns = time.monotonic_ns()
        self._bytes_flushed = self.bytes_written

    def _flush_periodically(self) -> None:
        while not self._closed.wait(FLUSH_INTERVAL_NS / 1e9):
            with self._lock:
                if self._closed.is_set() or self._background_error:
                    return
                if self._bytes_flushed == self.bytes_written:
                    continue
                try:
                    self._flush()
                except RecordingError as error:
                    self._background_error = error

    def _raise_background_error(self) -> None:
        if self._background_error is not None:
            raise self._background_error
