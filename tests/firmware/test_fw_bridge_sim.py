"""Firmware in the loop: ``groundstation bridge-sim --firmware c`` streams what the C core sends, in real
time through a pseudo-terminal, and the core obeys commands sent up the port."""

import os
import signal
import subprocess
import sys

import pytest
import serial

import firmware_protocol as fp
from groundstation.sim.stream import Scenario, SimStream
from tests.sim.sim_helpers import ENUM, read_for

pytestmark = pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals are POSIX only")


def test_the_bridge_runs_the_c_core_live_and_it_obeys_commands(c_core):
    process = subprocess.Popen([sys.executable, "-m", "groundstation", "bridge-sim", "--firmware", "c", "--scenario", "hover",
                                "--seed", "3", "--duration", "20"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        first_line = process.stdout.readline()
        assert "c firmware" in first_line, process.stderr.read()
        with serial.Serial(first_line.split()[-1], baudrate=115200, timeout=0.05) as port:
            decoder = fp.StreamDecoder()
            frames = read_for(port, decoder, 2.5)
            port.write(fp.encode(fp.make_frame("COMMAND", seq=42, command=ENUM["command"]["set_mode"],
                                               param=ENUM["mode"]["estimated"], value=0.0)))
            after = read_for(port, decoder, 1.0)
    finally:
        process.send_signal(signal.SIGTERM)
        _, err = process.communicate(timeout=10)
    assert process.returncode == 0 and "Traceback" not in err, err

    # Before the command: the bytes of the same scenario offline (the Python model's, so also the core's).
    offline = SimStream(Scenario("hover", 20.0, seed=3))
    expected = [bytes(fp.encode(f)) for f in fp.StreamDecoder().feed(b"".join(c.data for c in offline.advance(4.0)))]
    got = [bytes(fp.encode(f)) for f in frames]
    assert len(got) > 200 and decoder.stats.crc_errors == 0
    start = expected.index(got[0])
    assert got == expected[start : start + len(got)]

    acks = [f for f in after if f.name == "ACK"]
    assert [(f["command_seq"], f["result"]) for f in acks] == [(42, ENUM["ack_result"]["ok"])]
    tail = after[after.index(acks[0]) :]
    assert [f["mode"] for f in tail if f.name == "CONFIG"] == [ENUM["mode"]["estimated"]]
    assert not any(f.name == "IMU_RAW" for f in tail) and sum(f.name == "ATTITUDE" for f in tail) > 50


def test_extra_sensors_with_the_c_core_are_a_clear_error(c_core):
    result = subprocess.run([sys.executable, "-m", "groundstation", "bridge-sim", "--firmware", "c", "--sensors", "mag"],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2 and "MPU-6050 only" in result.stderr and "Traceback" not in result.stderr
