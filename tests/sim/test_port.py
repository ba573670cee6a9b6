"""The in-process port (the simulator on Windows): real-time pacing and the uplink, no pty."""

import time

import firmware_protocol as fp
from groundstation.sim.port import SimulatedPort
from groundstation.sim.stream import Scenario, SimStream

ENUM = {name: enum.values for name, enum in fp.SPEC.enums.items()}


def test_in_process_port_streams_in_real_time_and_answers_commands():
    with SimulatedPort(SimStream(Scenario("hover", 60.0, seed=9)), timeout=0.1) as port:
        decoder = fp.StreamDecoder()
        started = time.monotonic()
        frames = []
        while time.monotonic() - started < 2.0:
            frames += decoder.feed(port.read(port.in_waiting or 1))
        imu = [f for f in frames if f.name == "IMU_RAW"]
        # 100 Hz after the 1 s boot calibration: never ahead of real time; a loaded machine may read fewer
        assert 50 <= len(imu) <= 102
        port.write(fp.encode(fp.make_frame("COMMAND", seq=5, command=ENUM["command"]["request_config"], param=0, value=0.0)))
        later = []
        while time.monotonic() - started < 2.3:
            later += decoder.feed(port.read(port.in_waiting or 1))
    names = [f.name for f in later]
    ack = names.index("ACK")  # after the frames already due when the command arrived (more on a loaded machine)
    assert names[ack + 1] == "CONFIG" and later[ack]["command_seq"] == 5
    assert decoder.stats.frames_lost == 0 and decoder.stats.crc_errors == 0
