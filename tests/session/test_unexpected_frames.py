"""No frame the spec knows stops a session (issue 22): an uplink frame that comes down (a loopback, a
radio echoing, another sender) is counted and said, live, in replay and on the batch path; and a
failure in the live reader is an error the window and ``record`` show, never a dead thread."""

import time
from pathlib import Path

import pytest

from firmware_protocol import SPEC, encode, make_frame
from groundstation import cli
from groundstation.recording import open_recording
from groundstation.session_makers.live import LiveSession
from groundstation.session_makers.pipeline import Pipeline
from groundstation.session_makers.replay import replay
from groundstation.sources import open_source
from tests.cli_in_process import run_in_process
from tests.session.test_batch import assert_same_session
from tests.simulated import simulated_chunks, write_recording

GOLDEN = Path(__file__).parents[2] / "firmware_protocol" / "golden"


def with_commands(chunks: list, every: int = 40) -> list:
    """Every ``every``-th chunk followed by one of its own holding a COMMAND frame (as loop:// echoes one)."""
    command = encode(make_frame("COMMAND", 0, command=SPEC.enums["command"].values["request_config"], param=0, value=0.0))
    out = []
    for i, (t, data) in enumerate(chunks):
        out.append((t, data))
        if i % every == every // 2:
            out.append((t, command))
    return out


def test_every_frame_type_of_the_spec_reaches_a_handler():
    """One golden frame of each type the spec knows, uplink types included, through a pipeline."""
    pipeline = Pipeline(("ahf",))
    for frame_type in SPEC.frames:
        pipeline.feed(1_000_000, (GOLDEN / f"{frame_type.name.lower()}.bin").read_bytes())
    uplink = [t.name for t in SPEC.frames if t.direction == "up"]
    assert uplink and pipeline.unexpected_frames == {name: 1 for name in uplink}


def test_an_uplink_frame_on_the_downlink_is_counted_and_said_once_and_the_session_goes_on():
    chunks = simulated_chunks(4.0)
    pipeline = Pipeline(("ahf",))
    clean = Pipeline(("ahf",))
    for t, data in with_commands(chunks):
        pipeline.feed(t, data)
    for t, data in chunks:
        clean.feed(t, data)
    assert pipeline.unexpected_frames == {"COMMAND": len(with_commands(chunks)) - len(chunks)}
    said = [e for e in pipeline.events if "unexpected COMMAND frame" in e.get("message", "")]
    assert len(said) == 1 and said[0]["kind"] == "warning"
    assert len(pipeline.imu) == len(clean.imu) > 200  # every IMU sample still decoded


def test_the_batch_path_counts_and_says_them_as_the_pipeline_does(tmp_path):
    chunks = simulated_chunks(4.0, mag_rate_hz=50)
    path = tmp_path / "commands.gsrec"
    write_recording(path, with_commands(chunks), {"filters": ["ahf"]})
    incremental, batch = assert_same_session(path, ("ahf",))
    assert batch.unexpected_frames == incremental.unexpected_frames == {"COMMAND": len(with_commands(chunks)) - len(chunks)}


def test_record_on_a_loopback_port_records_without_a_traceback(tmp_path, capsys):
    """loop:// echoes the request for CONFIG that the session sends at its start: the reader used to die
    on ``KeyError: 16`` while ``record`` said nothing and exited 0."""
    done = run_in_process(capsys, "record", "--port", "loop://", "--duration", "2", "--recordings", tmp_path)  # a reader's traceback in its stderr
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    path = next(tmp_path.glob("*.gsrec"))
    replayed = replay(open_recording(path))
    assert replayed.unexpected_frames == {"COMMAND": 1}
    assert any("unexpected COMMAND frame" in e.get("message", "") for e in replayed.events)


class FailingPipeline(Pipeline):
    """A stand-in for any defect in decoding or estimating (none is left to trigger from input): the
    third chunk raises."""

    chunks = 0

    def feed(self, t_host_ns, data):
        self.chunks += 1
        if self.chunks == 3:
            raise ZeroDivisionError("float division by zero")
        return super().feed(t_host_ns, data)


def test_a_failure_in_the_reader_is_the_session_error_not_a_dead_thread(tmp_path):
    session = LiveSession(open_source("sim:"), FailingPipeline(("ahf",)), recordings_dir=tmp_path)
    with session:
        deadline = time.monotonic() + 20
        while session.running and time.monotonic() < deadline:
            time.sleep(0.02)
        assert not session.running
    assert "ZeroDivisionError: float division by zero" in session.error
    assert session.pipeline.events[-1]["kind"] == "error" and session.pipeline.events[-1]["message"] == session.error


def test_record_exits_non_zero_with_the_reason_when_the_reader_fails(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr("groundstation.session_makers.pipeline.Pipeline", FailingPipeline)  # open_session imports it when it runs
    status = cli.main(["record", "--port", "sim:", "--duration", "10", "--recordings", str(tmp_path)])
    assert status == 1
    assert "ZeroDivisionError: float division by zero" in capsys.readouterr().err


@pytest.mark.parametrize("name", [t.name for t in SPEC.frames if t.direction == "up"])
def test_the_event_names_the_frame_type(name):
    frame_type = SPEC.frame(name)
    pipeline = Pipeline(("ahf",))
    pipeline.feed(0, (GOLDEN / f"{frame_type.name.lower()}.bin").read_bytes())
    assert [e["message"].split(" frame")[0] for e in pipeline.events] == [f"unexpected {name}"]
