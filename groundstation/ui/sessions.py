"""Starting the app's sessions: the simulated bridge, a serial port, a recording.

Each returns a started ``LiveSession`` or raises ``UserError`` with a message fit for the window
(a busy port, a missing permission with the Linux ``dialout`` hint, an unreadable recording).
"""

from __future__ import annotations

import sys
import threading
from pathlib import Path

from groundstation.errors import UserError
from groundstation.recording import Recording, open_recording
from groundstation.session.live import LiveSession
from groundstation.session.replay import pipeline_for
from groundstation.sim.firmware import FirmwareSettings
from groundstation.sim.port import SimulatedPort
from groundstation.sim.stream import Scenario, SimStream
from groundstation.sources import ReplaySource, SerialSource

# The comparison estimators run on every live session (and so on its recording's replays), so showing one is a legend click or
# a check box, not a restart: the IMU filters (HF, ECF), those with the magnetometer (HF+mag, ECF+mag,
# MCF; a few µs per sample each) and the GPS-aided unscented filters (UKF, SSSRUKF; a few hundred µs
# per sample each, in the reader thread). Hidden curves cost the UI nothing per frame.
# The first is the one shown: VQF, the best on the BROAD dev set (bench/bench_estimators.out.md); the
# paper's AHF and AHF2 follow, one "show" click away.
LIVE_FILTERS = ("vqf", "ahf", "ahf2", "hf", "ecf", "hfm", "ecfm", "mcf", "ukf", "sssrukf")
DEMO_DESCRIPTION = "simulated bridge (demo)"
DEMO_PROFILE_S = 3600.0  # after an hour of flight the simulated craft holds still
# The demo craft carries every aiding sensor, so the heading and position tabs have something to show.
DEMO_FIRMWARE = FirmwareSettings(mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=10)
PORT_TIMEOUT_S = 0.05  # the reader's longest wait: it notices a stop request this quickly
DIALOUT_HINT = ("on Linux, add yourself to the 'dialout' group (sudo usermod -aG dialout $USER), "
                "then log out and back in")


def start_demo(recordings_dir: Path | None = None, settings: dict | None = None, seed: int = 1) -> LiveSession:
    port = SimulatedPort(SimStream(Scenario("flight", DEMO_PROFILE_S, seed=seed, firmware=DEMO_FIRMWARE)), timeout=PORT_TIMEOUT_S)
    source = SerialSource(port)
    source.description = DEMO_DESCRIPTION
    return LiveSession(source, LIVE_FILTERS, settings, recordings_dir=recordings_dir, metadata={"demo": True}).start()


def start_serial(port: str, baud: int, recordings_dir: Path | None = None, settings: dict | None = None) -> LiveSession:
    try:
        source = SerialSource(port, baud)
    except UserError as error:
        raise UserError(explain_port_error(str(error))) from None
    return LiveSession(source, LIVE_FILTERS, settings, recordings_dir=recordings_dir).start()


def explain_port_error(message: str) -> str:
    lowered = message.lower()
    if "permission denied" in lowered or "errno 13" in lowered:
        return f"{message}. Permission denied: " + (DIALOUT_HINT if sys.platform.startswith("linux") else
                                                     "another user or program may own the port")
    if "busy" in lowered or "errno 16" in lowered or "access is denied" in lowered:
        return f"{message}. The port is in use by another program (a serial terminal, another ground station?)"
    return message


def start_replay(path, speed: float | None = 1.0) -> LiveSession:
    """A recording played at ``speed`` times real time, through the recorded estimators and settings."""
    recording = open_recording(path)  # RecordingError (a UserError) when nothing can be read
    if recording.chunk_count == 0:
        raise UserError(f"{Path(path).name}: no link data to replay (an imported dataset? export it instead)")
    return replay_session(recording, speed).start()


def replay_session(recording: Recording, speed: float | None) -> LiveSession:
    """Through the recorded estimators (every one of ``LIVE_FILTERS`` for the app's recordings), as the
    headless replay and the export run it, so the window shows what the export writes."""
    session = LiveSession(ReplaySource(recording, speed), record=False)
    session.pipeline = pipeline_for(recording)
    return session


class ReplaySeek:
    """A replay restarted at ``t_s``, prepared in a worker thread: every chunk before ``t_s`` goes
    through a fresh pipeline first (filters have memory, so the estimates there depend on all that
    came before; a long recording takes seconds). ``session`` is ready, not started, once ``done``."""

    def __init__(self, recording: Recording, speed: float | None, paused: bool, t_s: float):
        self.session = replay_session(recording, speed)
        self.session.source.pause(paused)
        self.end = self.session.source.seek(t_s)
        self.fed = 0
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._run, name="groundstation-seek", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        recording = self.session.source.recording
        for index in range(self.end):
            if self._cancel.is_set():
                return
            self.session.feed_chunk(*recording.chunk(index))
            self.fed = index + 1

    @property
    def done(self) -> bool:
        return self.fed == self.end

    @property
    def fraction(self) -> float:
        return self.fed / self.end if self.end else 1.0

    def cancel(self) -> None:
        self._cancel.set()
        self._thread.join()
