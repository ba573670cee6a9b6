"""Sessions from a source spec: what the app, ``app --port``, ``record`` and the tests start.

``open_session(spec)`` opens the source (``groundstation.sources.open_source``) and gives a
``LiveSession`` (not started) with the pipeline that fits it: a live link runs every live estimator
(``estimation.live_estimators``) and
is recorded; a recording is fed through the live path (paced by ``ReplaySource``) with the estimators
and settings it was recorded with, as the live session computed it (what the live-path benchmarks
and tests reproduce). The app and ``groundstation replay`` open files whole instead
(``session.playback``). The demo is ``sim:``. No Qt here.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from groundstation import formats
from groundstation.formats import IMU_STREAMS

if TYPE_CHECKING:
    from groundstation.session_makers.live import LiveSession
    from groundstation.session_makers.load import Loading
    from groundstation.sources import ReplaySource

# The makers are imported when a session is opened, not with this module: the window takes ``Sessions``
# before its first paint, which need not wait for numba, pandas or scipy (bench/bench_first_frame.py).

DEMO_SPEC = "sim:"


def open_session(spec: str, *, filters=None, settings: dict | None = None, record: bool = True,
                 recordings_dir: Path | None = None, **defaults) -> LiveSession:
    """The session on ``spec`` (SourceError/UserError with a message fit for the user).

    ``filters`` (default: every live estimator) and ``settings`` (estimator name -> overrides) apply to
    live sources; a replay takes the recorded ones. ``defaults`` are source options the spec may
    override (``baud=``, ``speed=``).
    """
    from groundstation.estimation import live_estimators
    from groundstation.session_makers.live import LiveSession
    from groundstation.session_makers.pipeline import Pipeline
    from groundstation.session_parts.table import LIVE_KEEP_ROWS
    from groundstation.sources import ReplaySource, SourceError, open_source

    source = open_source(spec, **defaults)
    if source.is_replay:
        if not isinstance(source, ReplaySource):  # mavlink:FILE.tlog: a flight log, opened whole
            source.close()
            raise SourceError(f"{spec}: a .tlog is a flight log, not a link: open it whole (groundstation app FILE, "
                              "the app's File > Open, or replay, export and evaluate FILE)")
        return replay_session(source)
    vehicle_system = getattr(source, "vehicle_system", None)  # MAVLink: the vehicle the user picked
    # Bounded tables (``table.LIVE_KEEP_ROWS``): a flight of hours must not grow the app; the recording keeps every byte.
    pipeline = Pipeline(live_estimators() if filters is None else filters, settings, protocol=getattr(source, "protocol", "gs"),
                        vehicle_system=vehicle_system, keep_rows=LIVE_KEEP_ROWS,  # MAVLink sources say so
                        compile_in_background=True)  # data from the first second, also on a first start
    metadata = {"source_spec": spec, **({"vehicle_system": vehicle_system} if vehicle_system is not None else {})}
    return LiveSession(source, pipeline, record=record, recordings_dir=recordings_dir, metadata=metadata)


def replay_session(source: ReplaySource) -> LiveSession:
    """A recording through the live path with its recorded estimators and settings (every one of
    live estimator for the app's recordings), as the live session computed it."""
    from groundstation.session_makers.live import LiveSession
    from groundstation.session_makers.replay import pipeline_for

    return LiveSession(source, pipeline_for(source.recording), record=False)


class Sessions:
    """How the window opens sessions, handed to it (``ui.main_window.MainWindow``) so that the window
    imports no maker of sessions: a source live (``open``), a file computed whole in a worker
    (``load``, then ``playback.RevealSession``), and the loader an export runs."""

    demo_spec = DEMO_SPEC
    open = staticmethod(open_session)
    def __init__(self, imu: str = IMU_STREAMS[0]):
        self.imu = imu  # the IMU stream a flight log's estimators run on (File > "Full-rate IMU", ``--imu``)

    def load(self, path, filters=None, forced=None, compile_in_background: bool = True) -> Loading:
        """``path`` computed in a worker; a flight log that can hold a full-rate IMU on the stream ``imu`` names.
        ``compile_in_background``: its estimators not compiled yet are left out and compiled in another
        process (``Loading``; the window adds them when compiled)."""
        from groundstation.session_makers.flight_log_session import FAST_IMU_FORMATS
        from groundstation.session_makers.load import Loading

        fast_possible = getattr(formats.sniff(path), "name", None) in FAST_IMU_FORMATS
        return Loading(path, filters, forced, self.imu if fast_possible else IMU_STREAMS[0], compile_in_background)

    @staticmethod
    def load_session(*args, **kwargs):
        """``session_makers.load.load_session``: what an export or a report loads its file with."""
        from groundstation.session_makers.load import load_session

        return load_session(*args, **kwargs)
