"""Sessions from a source spec: what the app, ``app --port``, ``record`` and the tests start.

``open_session(spec)`` opens the source (``groundstation.sources.open_source``) and gives a
``LiveSession`` (not started) with the pipeline that fits it: a live link runs ``LIVE_FILTERS`` and
is recorded; a recording replays through the estimators and settings it was recorded with, so the
window shows what the export writes. The demo is ``sim:``. No Qt here.
"""

from __future__ import annotations

import threading
from pathlib import Path

from groundstation.recording import Recording
from groundstation.session.live import LiveSession
from groundstation.session.pipeline import Pipeline
from groundstation.session.replay import pipeline_for
from groundstation.sources import ReplaySource, SourceError, open_source

# The comparison estimators run on every live session (and so on its recording's replays), so showing one is a legend click or
# a check box, not a restart: the IMU filters (HF, ECF), those with the magnetometer (HF+mag, ECF+mag,
# MCF; a few µs per sample each) and the GPS-aided unscented filters (UKF, SSSRUKF; a few hundred µs
# per sample each, in the reader thread). Hidden curves cost the UI nothing per frame.
# The first is the one shown: VQF, the best on the BROAD dev set (bench/bench_estimators.out.md); the
# paper's AHF and AHF2 follow, one "show" click away.
LIVE_FILTERS = ("vqf", "ahf", "ahf2", "hf", "ecf", "hfm", "ecfm", "mcf", "ukf", "sssrukf")
DEMO_SPEC = "sim:"


def open_session(spec: str, *, filters=LIVE_FILTERS, settings: dict | None = None, record: bool = True,
                 recordings_dir: Path | None = None, **defaults) -> LiveSession:
    """The session on ``spec`` (SourceError/UserError with a message fit for the user).

    ``filters`` and ``settings`` (estimator name -> overrides) apply to live sources; a replay takes
    the recorded ones. ``defaults`` are source options the spec may override (``baud=``, ``speed=``).
    """
    source = open_source(spec, **defaults)
    if source.is_replay:
        if not isinstance(source, ReplaySource):  # mavlink:FILE.tlog: no recording to pace, seek and re-run
            source.close()
            raise SourceError(f"{spec}: groundstation export and evaluate read a .tlog; "
                              "the app does not open flight logs yet")
        return replay_session(source)
    pipeline = Pipeline(filters, settings, protocol=getattr(source, "protocol", "gs"))  # MAVLink sources say so
    return LiveSession(source, pipeline, record=record, recordings_dir=recordings_dir, metadata={"source_spec": spec})


def replay_session(source: ReplaySource, filters=None, forced=None) -> LiveSession:
    """Through the recorded estimators (every one of ``LIVE_FILTERS`` for the app's recordings), as the
    headless replay and the export run it, so the window shows what the export writes; or through
    ``filters`` with ``forced`` settings (``pipeline_for``), a what-if as the CLI's ``--set``."""
    return LiveSession(source, pipeline_for(source.recording, filters, forced), record=False)


class ReplaySeek:
    """A replay restarted at ``t_s``, prepared in a worker thread: every chunk before ``t_s`` goes
    through a fresh pipeline first (filters have memory, so the estimates there depend on all that
    came before; a long recording takes seconds). ``session`` is ready, not started, once ``done``."""

    def __init__(self, recording: Recording, speed: float | None, paused: bool, t_s: float, filters=None, forced=None):
        self.session = replay_session(ReplaySource(recording, speed), filters, forced)
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
