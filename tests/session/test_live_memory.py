"""A live session's tables are bounded (defect 13: memory grew 7 MiB a minute), yet nothing is lost:
the recording holds every byte, and export and replay read the file, not the live tables."""

import time

import numpy as np

from groundstation.cli import main
from groundstation.session_makers.live import LiveSession
from groundstation.session_makers.load import load_session
from groundstation.session_makers.replay import pipeline_for
from groundstation.recording import open_recording
from groundstation.sources.replay import open_replay
from groundstation.session_makers.factory import open_session
from groundstation.session_parts.table import LIVE_KEEP_ROWS


class Unpaced:
    """A recording's chunks as fast as they can be read, presented as a live link: the session records
    them again, as it records a port."""

    is_replay = False
    can_reopen = False
    can_send = False
    protocol = "gs"

    def __init__(self, path):
        self._replay = open_replay(path, speed=None)
        self.description = f"{path.name}, unpaced"

    def read(self):
        return self._replay.read()

    def close(self):
        self._replay.close()


def test_bounded_live_tables_and_a_lossless_recording(tmp_path):
    flight = tmp_path / "flight.gsrec"
    assert main(["simulate", "--scenario", "flight", "--duration", "40", "--seed", "5", "--sensors", "mag,baro,gps",
                 "--out", str(flight)]) == 0
    # A bound far under the 4000 IMU rows: the bound is what is tested, not its size.
    pipeline = pipeline_for(open_recording(flight), keep_rows=700)
    session = LiveSession(Unpaced(flight), pipeline, recordings_dir=tmp_path / "live")
    with session:
        deadline = time.monotonic() + 120
        while session.running and time.monotonic() < deadline:
            time.sleep(0.05)
    assert session.error is None
    whole = load_session(flight, exact=True)  # the estimators' columns as the live pipeline computed them, float64
    assert len(pipeline.imu) == len(whole.tables["imu"]["time_s"]) > 3000  # every row counted
    for name, table in pipeline.tables.items():
        kept = table.array()
        assert len(kept) < 700 + 2 * 700, name
        if len(kept):  # the newest rows, as the whole session has them
            newest = np.column_stack([whole.tables[name][c] for c in table.columns])[-len(kept):]
            assert np.array_equal(kept, newest, equal_nan=True), name
    again = load_session(session.recording_path, exact=True)  # what export and replay read: the file
    for name, columns in whole.tables.items():
        for column, values in columns.items():
            assert np.array_equal(again.tables[name][column], values, equal_nan=True), (name, column)


def test_a_live_link_opens_with_bounded_tables():
    session = open_session("sim:?duration=5", record=False)
    try:
        assert session.pipeline.keep_rows == LIVE_KEEP_ROWS
        assert all(t.keep_rows == LIVE_KEEP_ROWS for t in (*session.pipeline.tables.values(), session.pipeline.link.per_second))
    finally:
        session.source.close()
