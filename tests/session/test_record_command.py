"""``groundstation record`` as a user runs it: real processes, a real pty bridge, real files."""

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from groundstation.recording import open_recording
from tests.cli_in_process import run_in_process
from tests.waiting import LIMIT_S, wait_for

posix_only = pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals and signals are POSIX")


def gs(*args, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "groundstation", *map(str, args)], capture_output=True, text=True,
                          timeout=120, **kwargs)


def recording_of(output: str):
    line = next(line for line in output.splitlines() if line.startswith("recording closed: "))
    return line.removeprefix("recording closed: ").rsplit(" (", 1)[0]


@posix_only
def test_a_recording_of_the_pty_bridge_replays_to_the_same_totals(tmp_path):
    bridge = subprocess.Popen([sys.executable, "-m", "groundstation", "bridge-sim", "--scenario", "hover", "--seed", "4"],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        pty = bridge.stdout.readline().split()[-1]
        done = gs("record", "--port", pty, "--duration", "3", "--recordings", tmp_path, "--filters", "ahf,hf")
    finally:
        bridge.terminate()
        bridge.wait(timeout=10)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f"recording {pty} @ 115200 baud to {tmp_path}")
    totals = done.stdout.splitlines()[-2]
    assert " IMU samples at " in totals and int(totals.split()[0]) > 150  # 3 s at 100 Hz after the 1 s boot
    path = recording_of(done.stdout)
    recording = open_recording(path)
    assert recording.closed_cleanly and recording.damage == [] and recording.metadata["filters"] == ["ahf", "hf"]
    replayed = gs("replay", path)
    assert replayed.returncode == 0 and replayed.stdout.splitlines()[-1] == totals


@posix_only
def test_ctrl_c_stops_cleanly_and_says_where_the_recording_is(tmp_path):
    process = subprocess.Popen([sys.executable, "-m", "groundstation", "record", "--port", "sim:?scenario=hover&sensors=",
                                "--recordings", str(tmp_path), "--filters", "ahf"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    first = process.stdout.readline()
    assert first.startswith("recording simulated bridge (hover, seed 1) to "), process.stderr.read()
    # the file on disk (flushed every 0.25 s) holds the chunks asserted below, however slowly they come
    wait_for(lambda: open_recording(first.split(" to ", 1)[1].strip()).chunk_count > 50, what="50 chunks on disk")
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=LIMIT_S)
    assert process.returncode == 0 and "Traceback" not in err, err
    path = recording_of(out)
    assert path == first.split(" to ", 1)[1].strip()
    recording = open_recording(path)
    assert recording.closed_cleanly and recording.chunk_count > 50


def test_wrong_inputs_get_a_message_exit_2_and_leave_no_file(tmp_path, capsys):
    not_a_folder = tmp_path / "file"
    not_a_folder.write_text("x")
    sample = Path(__file__).resolve().parents[2] / "recordings" / "samples" / "hover-raw.gsrec"
    folder = tmp_path / "recordings"
    cases = [
        (["--port", "garbage"], "no such file or serial port"),
        (["--port", "sim:?scenario=nope"], "invalid choice"),
        (["--port", "sim:", "--duration", "-1"], "--duration must be a positive number of seconds"),
        (["--port", "sim:", "--duration", "nan"], "--duration must be a positive number of seconds"),
        (["--port", "sim:", "--recordings", not_a_folder / "sub"], f"cannot write recordings into {not_a_folder / 'sub'}"),
        (["--port", sample], "is a recording already"),
        (["--port", "sim:", "--filters", "nope"], "nope"),
    ]
    for args, message in cases:
        if "--recordings" not in args:
            args = [*args, "--recordings", folder]
        if "--duration" not in args:  # in this process: one let through would stop after a second, not at Ctrl-C
            args = [*args, "--duration", "1"]
        done = run_in_process(capsys, "record", *args)
        assert done.returncode == 2 and message in done.stderr and "Traceback" not in done.stderr, (args, done.stderr)
        assert not folder.exists() or list(folder.iterdir()) == []


@posix_only
def test_the_summary_says_when_the_port_is_gone_or_silent(tmp_path):
    from groundstation.commands.summary import summary_line
    from groundstation.session_makers.live import LiveSession
    from groundstation.session_makers.pipeline import Pipeline
    from groundstation.sim.stream import Scenario, SimStream
    from groundstation.sources import SerialSource

    master, slave = os.openpty()
    session = LiveSession(SerialSource(os.ttyname(slave)), Pipeline(("ahf",)), recordings_dir=tmp_path)
    os.close(slave)
    stream = SimStream(Scenario("static", 10.0, seed=1))
    with session:
        os.write(master, b"".join(c.data for c in stream.advance(2.0)))  # 1 s of frames after the boot second
        wait_for(lambda: len(session.pipeline.imu) >= 90)
        assert summary_line(session).startswith("t ")
        # the radio goes quiet; the adapter is still there
        wait_for(lambda: re.match(r"NO DATA for \d+ s from /dev/pts/", summary_line(session)), what="NO DATA")
        os.close(master)  # the adapter is pulled out
        wait_for(lambda: not session.connected)
        assert summary_line(session).startswith("PORT GONE: ")


def test_record_on_a_full_disk_exits_non_zero_and_says_how_long_was_not_recorded(tmp_path):
    from tests.session.full_disk import tiny_tmpfs

    with tiny_tmpfs(tmp_path / "full") as folder:
        result = gs("record", "--port", "sim:?scenario=hover", "--duration", "5", "--recordings", folder)
        assert result.returncode == 1, result.stderr
        assert "Traceback" not in result.stderr
        said = re.search(r"the recording failed \d+ time\(s\) \((.*)\): ([\d.]+) s of the session were not recorded",
                         result.stderr)
        assert said and "No space left on device" in said[1]
        assert 0.5 < float(said[2]) < 5.0  # the disk held the first seconds only
        assert open_recording(recording_of(result.stdout)).chunk_count > 0  # what fitted is kept
