"""open_session(spec): a live source gets the given estimators and a recording that replays to the
same numbers; a recording replays through its recorded pipeline, is not recorded again, and has no uplink."""

import time
from pathlib import Path

import numpy as np

from groundstation.recording import open_recording
from groundstation.estimation import live_estimators
from groundstation.session_makers.factory import open_session
from groundstation.session_makers.live import LiveSession
from groundstation.session_makers.pipeline import Pipeline
from groundstation.session_makers.replay import replay
from groundstation.sources import open_source
from tests.waiting import wait_for

SAMPLE = Path(__file__).resolve().parents[2] / "recordings" / "samples" / "hover-raw.gsrec"


def test_a_sim_session_records_what_replays_to_its_estimates_bit_for_bit(tmp_path):
    session = open_session("sim:?scenario=hover&seed=2&sensors=", filters=("ahf", "hf"), recordings_dir=tmp_path)
    assert session.recording_path.parent == tmp_path and session.pipeline.filters == ("ahf", "hf")
    with session:
        wait_for(lambda: len(session.pipeline.imu) >= 150, what="150 IMU rows")
    recording = open_recording(session.recording_path)
    assert recording.metadata["source_spec"] == "sim:?scenario=hover&seed=2&sensors="
    assert any(e["kind"] == "ack" and e["command_seq"] == 0 for e in session.pipeline.events)  # start's request_config
    np.testing.assert_array_equal(replay(recording).imu.array(), session.pipeline.imu.array())


def test_the_app_filters_are_the_default():
    session = open_session("loop://", record=False)
    assert session.pipeline.filters == live_estimators() and session.recording_path is None
    session.source.close()


def test_a_recording_replays_through_its_recorded_pipeline_without_uplink_or_new_recording(tmp_path):
    session = open_session(f"{SAMPLE}?speed=max", recordings_dir=tmp_path)
    assert session.source.is_replay and session.recording_path is None
    with session:
        while session.running:
            time.sleep(0.05)
        session.send_command("request_config")
    assert list(tmp_path.iterdir()) == []  # not recorded again
    kinds = [e["kind"] for e in session.pipeline.events]
    assert "command" in kinds and kinds.count("command") == 1  # only ours: start() sent nothing to a recording
    warning = next(e for e in session.pipeline.events if e["kind"] == "warning")
    assert "has no uplink" in warning["message"]
    expected = replay(open_recording(SAMPLE))
    assert session.pipeline.filters == expected.filters
    np.testing.assert_array_equal(session.pipeline.imu.array(), expected.imu.array())


def test_a_session_keeps_the_pipeline_it_was_given():
    pipeline = Pipeline(("ahf",))
    session = LiveSession(open_source("loop://"), pipeline, record=False)
    assert session.pipeline is pipeline
    session.source.close()
