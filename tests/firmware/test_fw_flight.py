"""The flight board's C core (gs_flight.c): fed the simulator's IMU counts, it sends frames the Python
decoder accepts, its ATTITUDE is the Python float32 AHF's, and it answers commands as the Python
firmware model does: the same bytes, frame for frame."""

import dataclasses
import math

import numpy as np
import pytest

import firmware_protocol as fp
from firmware_protocol.reference import host
from groundstation import mounting, units
from groundstation.estimation.ahf import Ahf, AhfSettings
from groundstation.sim.firmware import FIRMWARE_VERSION, FirmwareSettings
from groundstation.sim.stream import Scenario, SimStream

ENUM = {name: enum.values for name, enum in fp.SPEC.enums.items()}
COMMAND, MODE, PARAM, RESULT = ENUM["command"], ENUM["mode"], ENUM["filter_param"], ENUM["ack_result"]


def streamed_samples(scenario: Scenario):
    """Every sample the Python model streams (after its boot calibration): device µs and registers."""
    samples = []
    stream = SimStream(scenario, on_samples=lambda t_us, truth, raw, *clock: samples.append((t_us, raw)))
    stream.advance(stream.end_s)
    t_us = np.concatenate([t for t, _ in samples])
    acc = np.concatenate([r.acc_counts for _, r in samples])
    gyr = np.concatenate([r.gyr_counts for _, r in samples])
    temp = np.concatenate([units.temperature_c_to_counts(r.temperature_c) for _, r in samples])
    return t_us, acc, gyr, temp


def test_fed_a_whole_flight_the_core_sends_decodable_frames_carrying_the_python_float32_ahf(c_core):
    s = FirmwareSettings(accel_fs_g=8, gyro_fs_dps=1000, mounting=5)
    t_us, acc, gyr, temp = streamed_samples(Scenario("flight", 120.0, seed=4, firmware=s))
    core = host.FlightCore(rate_hz=100, accel_fs_g=8, gyro_fs_dps=1000, mounting=5, mode=MODE["both"],
                           boot_calibration_s=0.0, fw_version=(1, 2, 3), ahf=AhfSettings())
    data = b"".join(core.sample(int(t) & 0xFFFFFFFF, (*a, *g, int(c)), 12.0, 40.0)
                    for t, a, g, c in zip(t_us.tolist(), acc.tolist(), gyr.tolist(), temp.tolist()))
    decoder = fp.StreamDecoder()
    frames = decoder.feed(data)
    stats = decoder.stats
    assert (stats.crc_errors, stats.bytes_skipped, stats.frames_lost, decoder.pending_bytes) == (0, 0, 0, 0)
    assert decoder.schema_matches
    config = frames[0]
    assert config.name == "CONFIG" and (config["fw_major"], config["fw_minor"], config["fw_patch"]) == (1, 2, 3)
    assert (config["accel_fs_g"], config["gyro_fs_dps"], config["rate_hz"], config["mounting"]) == (8, 1000, 100, 5)

    imu = [f for f in frames if f.name == "IMU_RAW"]
    attitude = [f for f in frames if f.name == "ATTITUDE"]
    assert len(imu) == len(attitude) == len(t_us) > 11_800  # 120 s at 100 Hz after the 1 s boot
    assert [f.raw[1:7] for f in imu] == [(*a, *g) for a, g in zip(acc.tolist(), gyr.tolist())]
    # STATUS every 100 samples, the first with the first sample (counted from this core's power-up)
    assert sum(f.name == "STATUS" for f in frames) == math.ceil(len(t_us) / 100) and all(f.scaled()["battery"] == pytest.approx(12.0) for f in frames if f.name == "STATUS")

    # The oracle: the counts converted as the host converts them, through the Python AHF in float32.
    m = mounting.matrix(5)
    gyr_body = units.gyro_counts_to_rad_s(gyr, 1000) @ m.T
    acc_body = units.accel_counts_to_g(acc, 8) @ m.T
    dt_s = np.diff(t_us, prepend=t_us[0] - 10_000) * 1e-6
    ahf = Ahf(AhfSettings(), dtype=np.float32)
    expected = []
    for g, a, d in zip(gyr_body.tolist(), acc_body.tolist(), dt_s.tolist()):
        q, _ = ahf.step(g, a, d)
        expected.append(tuple(int(round(float(v) * 16384)) for v in q))
    got = [(f["q_w"], f["q_x"], f["q_y"], f["q_z"]) for f in attitude]
    assert got == expected
    assert [f["t_us"] for f in attitude] == (t_us & 0xFFFFFFFF).tolist()


def command(seq: int, name: str, param: int = 0, value: float = 0.0) -> fp.Frame:
    return fp.make_frame("COMMAND", seq=seq, command=COMMAND.get(name, name) if isinstance(name, str) else name, param=param, value=value)


# (time s, command): every command, every answer (ok, bad_value, busy, unsupported), in every mode.
SCRIPT = [
    (2.0, command(1, "set_mode", MODE["raw"])),
    (2.5, command(2, "set_mode", 7)),
    (3.0, command(3, "set_mode", MODE["estimated"])),
    (3.5, command(4, "set_filter_param", PARAM["lambda_max"], 1.5)),
    (4.0, command(5, "set_filter_param", PARAM["lambda_min"], 1.8)),
    (4.0, command(6, "set_filter_param", PARAM["lowpass"], 0.8)),
    (4.5, command(7, "set_filter_param", PARAM["error_gain"], 12.5)),
    (5.0, command(8, "set_filter_param", PARAM["gyro_overrange"], 0.5)),
    (5.5, command(9, "set_filter_param", 9, 1.0)),
    (6.0, command(10, "set_filter_param", PARAM["lambda_max"], math.nan)),
    (6.5, command(11, "request_config")),
    (7.0, command(12, "calibrate_gyro", 0, 0.5)),
    (7.2, command(13, "calibrate_gyro", 0, 0.0)),
    (8.0, command(14, "calibrate_gyro", 0, 100.0)),
    (8.5, command(15, 99)),
    (9.0, command(16, "set_filter_param", PARAM["gyro_overrange"], 0.0)),
    (9.5, command(17, "set_mode", MODE["both"])),
    (10.0, command(18, "calibrate_gyro", 0, 0.0)),
]


def session_bytes(scenario: Scenario, script) -> bytes:
    """The stream stepped one sample period at a time, the script's commands sent on the way."""
    stream, data, t, pending = SimStream(scenario), [], 0.0, list(script)
    while t < stream.end_s:
        t = min(t + 0.01, stream.end_s)
        while pending and pending[0][0] <= t:
            stream.receive(fp.encode(pending.pop(0)[1]))
        data += stream.advance(t)
    return b"".join(chunk.data for chunk in data + stream.flush())


CALIBRATION = ENUM["gyro_calibration"]


# scenario, CONFIG.gyro_calibration at power-up, after the reset (None: no reset)
@pytest.mark.parametrize("scenario, at_power_up, after_reset", [
    (Scenario("hover", 14.0, seed=8), "boot", None),
    (Scenario("fast", 14.0, seed=6, firmware=FirmwareSettings(mode="estimated", accel_fs_g=16, gyro_fs_dps=250, mounting=17, rate_hz=200)),
     "boot", None),
    (Scenario("flight", 14.0, seed=7, firmware=FirmwareSettings(boot_calibration_s=0.0, accel_calibrated=False)), "none", None),
    # issue 21: reset in flight, so moving at boot: the calibration kept over the reset (the last commanded one)
    (Scenario("flight", 14.0, seed=7, firmware=FirmwareSettings(reboot_after_s=11.0)), "boot", "stored"),
    # reset at rest: measured again; then the clock jumps
    (Scenario("static", 14.0, seed=9, firmware=FirmwareSettings(reboot_after_s=11.0, clock_jump_after_s=13.0)), "boot", "boot"),
], ids=["hover", "fast-200Hz", "no-boot-calibration", "reset-in-flight", "reset-at-rest"])
def test_with_commands_the_c_core_sends_the_python_models_bytes(c_core, scenario, at_power_up, after_reset):
    python = session_bytes(scenario, SCRIPT)
    c = session_bytes(dataclasses.replace(scenario, firmware_core="c"), SCRIPT)
    assert c == python
    # ... and what they say is what the commands asked for.
    frames = fp.StreamDecoder().feed(c)
    acks = {f["command_seq"]: f["result"] for f in frames if f.name == "ACK"}
    assert acks == {1: RESULT["ok"], 2: RESULT["bad_value"], 3: RESULT["ok"], 4: RESULT["ok"], 5: RESULT["bad_value"],
                    6: RESULT["ok"], 7: RESULT["ok"], 8: RESULT["ok"], 9: RESULT["bad_value"], 10: RESULT["bad_value"],
                    11: RESULT["ok"], 12: RESULT["ok"], 13: RESULT["busy"], 14: RESULT["bad_value"], 15: RESULT["unsupported"],
                    16: RESULT["ok"], 17: RESULT["ok"], 18: RESULT["ok"]}
    configs = [f for f in frames if f.name == "CONFIG"]
    booted = configs[-1] if after_reset else None  # the reset's CONFIG: the commanded mode is forgotten
    commanded = configs[1:-1] if after_reset else configs[1:]
    assert [f["mode"] for f in commanded][-4:] == [MODE["raw"], MODE["estimated"], MODE["estimated"], MODE["both"]]
    calibrating = [f["t_us"] for f in frames if f.name == "STATUS" and f["flags"] & 1]
    assert calibrating  # STATUS says so while the commanded calibration runs
    assert configs[0]["gyro_calibration"] == CALIBRATION[at_power_up]
    assert commanded[-1]["gyro_calibration"] == CALIBRATION["command"]  # after the calibrate_gyro at 7 s
    if after_reset:
        assert (booted["gyro_calibration"], booted["mode"]) == (CALIBRATION[after_reset], MODE["both"])


def test_a_board_moving_through_its_boot_calibration_with_none_stored_streams_uncalibrated_alike(c_core):
    # (no commands: while booting, the core's queue holds 6 frames, the model's any number)
    scenario = Scenario("flight", 14.0, seed=7, firmware=FirmwareSettings(boot_calibration_s=6.0))  # past the rest
    python = session_bytes(scenario, [])
    assert session_bytes(dataclasses.replace(scenario, firmware_core="c"), []) == python
    assert [f["gyro_calibration"] for f in fp.StreamDecoder().feed(python) if f.name == "CONFIG"] == [CALIBRATION["none"]]


def test_a_firmware_with_extra_sensors_is_refused(c_core):
    scenario = Scenario("hover", 5.0, firmware=FirmwareSettings(mag_rate_hz=50), firmware_core="c")
    with pytest.raises(ValueError, match="MPU-6050 only"):
        SimStream(scenario)


def test_the_c_firmware_reports_the_models_version_through_the_simulator(c_core):
    frames = fp.StreamDecoder().feed(session_bytes(dataclasses.replace(Scenario("hover", 2.0), firmware_core="c"), []))
    config = next(f for f in frames if f.name == "CONFIG")
    assert (config["fw_major"], config["fw_minor"], config["fw_patch"]) == FIRMWARE_VERSION
