"""A live session: a reader thread takes chunks from a source, records them, and feeds the pipeline.

Consumers (the UI, the CLI's one-line summary) pull from ``pipeline``'s tables whenever they like;
the reader never waits for them. Each chunk is written to the recording before it is decoded, so
a crash of the decoder or the estimators loses nothing that came before it; such a crash stops the
reader with ``error`` set (the window's red banner, ``record``'s exit status 1), never silently.
"""

from __future__ import annotations

import threading
import time
import traceback
from pathlib import Path

from firmware_protocol import SPEC, encode, make_frame
from groundstation.recording import Recorder, default_recordings_dir
from groundstation.session_makers.pipeline import Pipeline
from groundstation.session_makers.replay import SettingsSchedule
from groundstation.sources.base import Source, SourceClosed, SourceError
from groundstation.sources.sniff import ForeignBytes

RECONNECT_INTERVAL_S = 0.5
COMMANDS = SPEC.enums["command"].values


def reader_failure(error: BaseException) -> str:
    """What stopped the reader: the exception and where it was raised (the window's banner and ``record``'s exit say it)."""
    where = traceback.extract_tb(error.__traceback__)[-1] if error.__traceback__ else None
    place = f" in {Path(where.filename).name}:{where.lineno}" if where else ""
    return f"decoding stopped on an internal error ({type(error).__name__}: {error}{place}); the recording ends here"


class PipelineView:
    """What the window reads of a live pipeline (``view.ProductView``): its product so far, nothing
    that feeds it. Attributes are read through, as the pipeline replaces some (a MAVLink session adds
    tables as their first message arrives)."""

    def __init__(self, pipeline: Pipeline):
        self._pipeline = pipeline

    tables = property(lambda self: self._pipeline.tables)
    catalogue = property(lambda self: self._pipeline.catalogue)
    filters = property(lambda self: self._pipeline.filters)
    imu = property(lambda self: self._pipeline.imu)
    onboard = property(lambda self: self._pipeline.onboard)
    events = property(lambda self: self._pipeline.events)
    parameters = property(lambda self: self._pipeline.parameters)
    parameter_defaults = property(lambda self: {})  # MAVLink's PARAM_VALUE carries none
    config = property(lambda self: self._pipeline.config)
    protocol = property(lambda self: self._pipeline.protocol)
    t0_host_ns = property(lambda self: self._pipeline.t0_host_ns)
    link = property(lambda self: self._pipeline.link)

    def counters(self) -> dict[str, int]:
        return self._pipeline.decoder.stats.as_dict()

    def settings(self) -> dict[str, dict[str, float]]:
        return self._pipeline.settings()

    def uncompiled(self) -> tuple[str, ...]:
        """The estimators whose compiled kernels are not there yet (a first start: ``EstimatorBank``)."""
        return self._pipeline.bank.uncompiled()


class LiveSession:
    """``source`` through ``pipeline`` (``session_makers.factory.open_session`` makes both from a spec); the
    window reads ``view`` (``view.Session``).

    ``record``: write a recording into ``recordings_dir`` (default: ``default_recordings_dir()``)
    through ``recorder``, which never stops the session: a failing disk stops the recording, not the
    decoding (``groundstation.recording.recorder``).
    Replays are not re-recorded, and their recorded settings changes are re-applied as they pass.
    """

    seekable = False  # live: the clock is the aircraft's
    setup = (None, None)  # the estimators and settings of the session itself

    def __init__(self, source: Source, pipeline: Pipeline, record: bool = True,
                 recordings_dir: Path | None = None, metadata: dict | None = None):
        self.source = source
        self.pipeline = pipeline
        self.view = PipelineView(pipeline)
        self.lock = threading.Lock()
        self.error: str | None = None  # why the reader stopped, when it was not asked to (a lost source, a defect)
        self.connected = True
        self._schedule = SettingsSchedule(source.recording) if source.is_replay else None
        self._stop = threading.Event()
        self._last_chunk_ns = 0
        self._uplink_seq = 0
        self._config_wanted = False
        # Until a frame of the project's protocol decodes, what the bytes are instead (MAVLink?): ``heard_protocol``.
        self._foreign = ForeignBytes() if pipeline.protocol == "gs" else None
        self._reopened_as: str | None = None  # the port reopened, its data not yet back: the "reconnected" to note
        self.recorder = Recorder(
            recordings_dir if recordings_dir is not None else default_recordings_dir(),
            lambda: {  # each file's header has the settings in force when it starts
                "source": source.description,
                "protocol": self.pipeline.protocol,  # how a replay decodes the chunks
                **(metadata or {}),
                "filters": list(self.pipeline.filters),
                "aiding_estimator": self.pipeline.bank.aiding,
                "estimator_settings": self.pipeline.settings_json(),
            },
            self._recorder_event,
        )
        if record and self._schedule is None:
            self.recorder.start()
        self._thread = threading.Thread(target=self._read_loop, name="groundstation-reader", daemon=True)

    def start(self) -> LiveSession:
        self._thread.start()
        self._request_config()  # the full scales, in case the start-up CONFIG was missed
        return self

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        self.source.close()
        with self.lock:
            self.recorder.stop()

    def __enter__(self) -> LiveSession:
        return self.start()

    def __exit__(self, *exc_info) -> None:
        self.stop()

    @property
    def running(self) -> bool:
        return self._thread.is_alive()

    @property
    def recording_path(self) -> Path | None:
        """The file being recorded (or the last one); None for a session that never recorded."""
        return self.recorder.path

    def advance(self) -> None:
        """Nothing to move: the reader thread brings the rows."""

    @property
    def heard_protocol(self) -> str | None:
        """"mavlink" when a session opened for the project's bridge hears an autopilot's MAVLink instead
        (its bytes, or a UDP source's refused datagrams); None while its own frames decode or nothing is known."""
        foreign = self._foreign
        return foreign.protocol(bytes(getattr(self.source, "refused", b""))) if foreign is not None else None

    def seek(self, t_s: float) -> bool:
        return False

    def file(self) -> tuple[Path, float] | None:
        """The recording being made and how far it has come (s); None when not recording."""
        if self.recording_path is None:
            return None
        last = self.pipeline.imu.tail(1)
        return self.recording_path, float(last[0][0]) if len(last) else 0.0

    def resume_recording(self) -> bool:
        """The user's "Resume recording": a new file now; False (``recorder.error`` says why) if it cannot."""
        with self.lock:
            return self.recorder.start()

    # -- the reader thread ------------------------------------------------------------------------

    def _read_loop(self) -> None:
        try:
            self._read_until_stopped()
        except Exception as error:  # a defect in decoding or estimating: said, never a dead thread behind a live display
            self.error = reader_failure(error)
            self._note({"kind": "error", "message": self.error})

    def _read_until_stopped(self) -> None:
        while not self._stop.is_set():
            try:
                chunk = self.source.read()
            except SourceClosed:
                return
            except SourceError as error:
                if not self._reconnect(str(error)):
                    return
                continue
            if chunk is not None:
                self._take(chunk.t_host_ns, chunk.data)
            if self._config_wanted:  # a resumed recording needs a CONFIG frame of its own to replay
                self._config_wanted = False
                self._request_config()

    def _take(self, t_host_ns: int, data: bytes) -> None:
        with self.lock:
            if self._reopened_as is not None:  # "reconnected" when the data is back, not when the port reopened
                self._note_locked({"kind": "reconnected", "source": self._reopened_as, "t_host_ns": t_host_ns})
                self._reopened_as = None
            self.recorder.write_chunk(t_host_ns, data)
            if self._schedule is not None:
                self._schedule.apply_before(self.pipeline, t_host_ns)
            self.pipeline.feed(t_host_ns, data)
            self._last_chunk_ns = t_host_ns
            if self._foreign is not None:
                if self.pipeline.decoder.stats.frames:
                    self._foreign = None  # the project's own frames: nothing to guess
                else:
                    self._foreign.add(data)
            uplink = self.pipeline.take_uplink()  # MAVLink stream-rate requests: nothing that arms or moves it
        if uplink and self.source.can_send:
            self._send(uplink)

    def _request_config(self) -> None:
        if self.source.can_send and self.pipeline.protocol == "gs":  # an autopilot gets stream requests instead
            self.send_command("request_config")

    def _send(self, data: bytes) -> None:
        try:
            self.source.write(data)
        except SourceError as error:
            self._note({"kind": "warning", "message": str(error)})

    def _reconnect(self, reason: str) -> bool:
        """Keep trying to reopen a port that went away; False when it cannot be reopened at all."""
        self._note({"kind": "disconnected", "message": reason})
        if not self.source.can_reopen:
            self.error = reason
            return False
        self.connected = False
        while not self._stop.wait(RECONNECT_INTERVAL_S):
            try:
                self.source.reopen()
            except SourceError:
                continue
            self.connected = True
            self._reopened_as = self.source.description  # perhaps a new name; noted with the first chunk (``_take``)
            self._request_config()
            return True
        return False

    # -- from other threads -----------------------------------------------------------------------

    def change_settings(self, name: str, overrides: dict[str, float]) -> None:
        """Change a host estimator's settings now; recorded, so a replay changes them at the same point."""
        with self.lock:
            self.pipeline.change_settings(name, overrides, self._last_chunk_ns)
            self.recorder.write_event(self._last_chunk_ns, self.pipeline.events[-1])

    def held_config(self) -> str | None:
        """The ``config_conflict`` message of a CONFIG held for the user's answer; None when none is held."""
        with self.lock:
            if self.pipeline.config_guard.held is None:
                return None
            return next(e["message"] for e in reversed(self.pipeline.events) if e["kind"] == "config_conflict")

    def resolve_config(self, accept: bool) -> None:
        """The user's answer to a held CONFIG (``pipeline.config_guard.held``: it changes the scales without a
        device restart): its scales from now on, or the ones in use; the answer is recorded as an event."""
        with self.lock:
            before = len(self.pipeline.events)
            self.pipeline.resolve_config(accept, self._last_chunk_ns)
            for event in self.pipeline.events[before:]:
                self.recorder.write_event(self._last_chunk_ns, event)

    def send_command(self, command: str, param: int = 0, value: float = 0.0) -> int:
        """Send a COMMAND to the aircraft; returns its seq (the ACK carries it back). An autopilot on
        MAVLink gets none (a warning event says so; returns -1): this project's commands are not its own."""
        if self.pipeline.protocol != "gs":
            self._note({"kind": "warning", "message": f"command {command} not sent: the aircraft speaks MAVLink, "
                        "and this ground station sends an autopilot only stream-rate requests"})
            return -1
        with self.lock:
            seq = self._uplink_seq
            self._uplink_seq = (seq + 1) & 0xFF
            frame = make_frame("COMMAND", seq, command=COMMANDS[command], param=param, value=value)
            self._note_locked({"kind": "command", "command": command, "param": param, "value": value, "seq": seq})
        self._send(encode(frame))
        return seq

    def request_streams(self, rate_hz: float) -> None:
        """Ask an autopilot on MAVLink for its IMU and attitude at ``rate_hz`` (the only uplink it gets;
        ValueError for a rate it cannot stream, or on the project's own protocol)."""
        if self.pipeline.protocol != "mavlink":
            raise ValueError("stream-rate requests are for an autopilot on MAVLink")
        with self.lock:
            self.pipeline.front.request_streams(rate_hz, self._last_chunk_ns)
            self._note_locked({"kind": "command", "command": "request_streams", "rate_hz": rate_hz})
            uplink = self.pipeline.take_uplink()
        if uplink and self.source.can_send:
            self._send(uplink)

    def _note(self, event: dict) -> None:
        with self.lock:
            self._note_locked(event)

    def _note_locked(self, event: dict) -> None:
        event = {"t_host_ns": self._last_chunk_ns, **event, "wall_time": time.time()}
        self.pipeline.events.append(event)
        self.recorder.write_event(event["t_host_ns"], event)

    def _recorder_event(self, event: dict) -> None:
        """``recording_failed``/``recording_resumed``; the recorder is only called under ``lock``."""
        self.pipeline.events.append({**event, "wall_time": time.time()})
        self._config_wanted |= event["kind"] == "recording_resumed"
