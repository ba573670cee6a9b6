"""The simulated firmware: onboard AHF = host AHF, commands obeyed and acknowledged, timing."""

import dataclasses

import numpy as np

import firmware_protocol as fp
from groundstation import mounting, units
from groundstation import quaternion as quat
from groundstation.estimation.ahf import Ahf
from groundstation.sim.firmware import FirmwareSettings
from groundstation.sim.stream import Scenario, SimStream

from sim_helpers import stream_bytes

ENUM = {name: enum.values for name, enum in fp.SPEC.enums.items()}


def decode(data: bytes) -> list:
    return fp.StreamDecoder().feed(data)


def test_onboard_attitude_agrees_with_the_host_ahf_on_the_same_raw_frames():
    fw = FirmwareSettings(mounting=13)  # a mounting other than the default: both sides must apply it
    frames = decode(stream_bytes(Scenario("flight", 30.0, seed=2, firmware=fw))[0])
    raw = [f for f in frames if f.name == "IMU_RAW"]
    att = [f for f in frames if f.name == "ATTITUDE"]
    assert [f["t_us"] for f in raw] == [f["t_us"] for f in att] and len(raw) > 2800
    counts = np.array([f.raw[1:7] for f in raw], dtype=float)
    m = mounting.matrix(13)
    acc_g = units.accel_counts_to_g(counts[:, :3], fw.accel_fs_g) @ m.T
    gyr = units.gyro_counts_to_rad_s(counts[:, 3:], fw.gyro_fs_dps) @ m.T
    t_us = np.array([f.device_time_us for f in raw])
    dt_s = np.diff(t_us, prepend=t_us[0] - 10_000) * 1e-6
    onboard_q = np.array([[f["q_w"], f["q_x"], f["q_y"], f["q_z"]] for f in att]) / 16384.0
    # The host's AHF in float32 on the decoded frames is the onboard filter to within the Q2.14
    # rounding of the ATTITUDE frame (half an LSB).
    host32_q, host32_diag = Ahf(dtype=np.float32).run(gyr, acc_g, dt_s)
    assert np.abs(onboard_q - host32_q).max() <= 0.5 / 16384.0 + 1e-7
    onboard_lambda = np.array([f["lambda_gain"] for f in att]) * 1e-3
    assert np.abs(onboard_lambda - host32_diag["lam"]).max() <= 0.5e-3 + 1e-7
    # In float64 it agrees closely most of the time; the normalised gradient step (eq. 18) has a
    # fixed size λΔt whatever the error, so near zero error its direction follows rounding noise
    # and the two runs can chatter apart by about λΔt (1.1°) for a while.
    host64_q, _ = Ahf().run(gyr, acc_g, dt_s)
    angle_deg = np.degrees(quat.angle_between(quat.normalise(onboard_q), host64_q))
    assert np.median(angle_deg) < 0.05


def command(seq, name, param=0, value=0.0) -> bytes:
    return fp.encode(fp.make_frame("COMMAND", seq=seq, command=ENUM["command"][name], param=param, value=value))


def test_commands_change_the_firmware_and_are_acknowledged():
    stream = SimStream(Scenario("static", 30.0, seed=3))
    before = decode(b"".join(c.data for c in stream.advance(3.0)))
    assert {"CONFIG", "STATUS", "IMU_RAW", "ATTITUDE"} <= {f.name for f in before}
    decoder = fp.StreamDecoder()
    decoder.feed(b"".join(c.data for c in stream.advance(3.0)))
    stream.receive(command(40, "set_mode", ENUM["mode"]["raw"]) + command(41, "set_mode", 9))
    stream.receive(command(42, "set_filter_param", ENUM["filter_param"]["lambda_max"], 1.0))
    after = decoder.feed(b"".join(c.data for c in stream.advance(5.0)))
    acks = [(f["command_seq"], f["result"]) for f in after if f.name == "ACK"]
    assert acks == [(40, ENUM["ack_result"]["ok"]), (41, ENUM["ack_result"]["bad_value"]), (42, ENUM["ack_result"]["ok"])]
    assert [f["mode"] for f in after if f.name == "CONFIG"] == [ENUM["mode"]["raw"]]
    assert "ATTITUDE" not in {f.name for f in after} and sum(f.name == "IMU_RAW" for f in after) == 200
    stream.receive(command(43, "set_mode", ENUM["mode"]["estimated"]))
    later = decoder.feed(b"".join(c.data for c in stream.advance(6.0)))
    assert "IMU_RAW" not in {f.name for f in later}
    assert max(f["lambda_gain"] for f in later if f.name == "ATTITUDE") <= 1000  # λ_max is now 1.0
    assert decoder.stats.frames_lost == 0


def test_gyro_calibration_command_removes_a_bias_that_grew_after_boot():
    # A board without boot calibration streams the turn-on bias until commanded.
    fw = FirmwareSettings(boot_calibration_s=0.0, mode="raw")
    stream = SimStream(Scenario("static", 60.0, seed=4, firmware=fw))
    decoder = fp.StreamDecoder()

    def mean_gyro_dps(until_s):
        frames = decoder.feed(b"".join(c.data for c in stream.advance(until_s)))
        counts = np.array([f.raw[4:7] for f in frames if f.name == "IMU_RAW"], dtype=float)
        return units.gyro_counts_to_dps(counts, fw.gyro_fs_dps).mean(axis=0), frames

    bias, _ = mean_gyro_dps(5.0)
    assert np.abs(bias).max() > 1.0  # the datasheet's turn-on bias (σ 6.7 °/s)
    stream.receive(command(7, "calibrate_gyro", value=2.0))
    _, during = mean_gyro_dps(7.0)
    assert [f["result"] for f in during if f.name == "ACK"] == [ENUM["ack_result"]["ok"]]
    assert all(f["flags"] & 1 for f in during if f.name == "STATUS")
    residual, after = mean_gyro_dps(12.0)
    assert np.abs(residual).max() < 0.05
    assert not any(f["flags"] & 1 for f in after if f.name == "STATUS")


def test_timestamps_carry_the_configured_jitter_and_one_frame_sequence():
    fw = dataclasses.replace(FirmwareSettings(), sample_jitter_us=50.0, mode="raw")
    frames = decode(stream_bytes(Scenario("static", 60.0, seed=5, firmware=fw))[0])
    t_us = np.array([f.device_time_us for f in frames if f.name == "IMU_RAW"])
    gaps = np.diff(t_us)
    assert abs(gaps.mean() - 10_000) < 1.0
    assert abs(gaps.std() - 50.0 * np.sqrt(2)) < 5.0  # difference of two independent jitters
    assert [f.seq for f in frames[:300]] == [k & 0xFF for k in range(300)]


def test_extra_sensors_report_the_truth_at_their_rates():
    fw = FirmwareSettings(mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=5, mode="raw")
    scenario = Scenario("flight", 40.0, seed=8, firmware=fw)
    stream = SimStream(scenario)
    frames = decode(b"".join(c.data for c in stream.advance(40.0)))
    counts = {name: sum(f.name == name for f in frames) for name in ("IMU_RAW", "MAG_RAW", "BARO", "GPS")}
    for name, every in (("MAG_RAW", 2), ("BARO", 4), ("GPS", 20)):
        assert abs(counts[name] * every - counts["IMU_RAW"]) < every, counts
    mag = np.array([[f.scaled()[k] for k in ("mag_x", "mag_y", "mag_z")] for f in frames if f.name == "MAG_RAW"])
    field_ut = np.linalg.norm(scenario.extra.mag_field_ned_ut)
    assert abs(np.median(np.linalg.norm(mag, axis=1)) - field_ut) < 10.0  # the hard-iron offset is a few µT
    gps = [f.scaled() for f in frames if f.name == "GPS"]
    baro = [f for f in frames if f.name == "BARO"]
    truth = stream.profile.truth(np.array([f.device_time_us for f in baro]) * 1e-6)
    altitude_m = -truth.pos_ned_m[:, 2]
    pressure = np.array([f.scaled()["pressure"] for f in baro])
    # ISA near the ground: about -12 Pa per metre.
    assert abs(np.polyfit(altitude_m, pressure, 1)[0] + 12.0) < 0.5
    assert np.std([g["alt"] - scenario.extra.origin_alt_m for g in gps]) > 1.0  # it climbs


def test_the_boot_calibration_is_used_only_when_the_craft_was_still():
    """Issue 21: a board reset in flight re-ran its gyro calibration while moving, +16.7 deg/s on x after it.
    Now it sees the motion (gyro and accelerometer spread over the window) and keeps its stored one."""
    calibration = ENUM["gyro_calibration"]
    stream = SimStream(Scenario("flight", 30.0, seed=1, firmware=FirmwareSettings(reboot_after_s=20.0)))
    board = stream.firmware
    stream.advance(19.0)
    before_dps = board.imu.gyro_offset_dps.copy()
    assert board.gyro_calibration == calibration["boot"]
    # the offset registers read the bias the part has (turn-on + warm-up + walk), to the noise of 1 s
    assert np.abs(before_dps - board.imu.gyro_turn_on_bias_dps).max() < 0.1
    frames = decode(b"".join(c.data for c in stream.advance(30.0)))
    assert [f["gyro_calibration"] for f in frames if f.name == "CONFIG"] == [calibration["stored"]]
    assert np.array_equal(board.imu.gyro_offset_dps, before_dps)  # before: 16.7 deg/s off on x

    # At rest the board measures again; one that never calibrated has nothing stored and says so.
    at_rest = SimStream(Scenario("static", 30.0, seed=1, firmware=FirmwareSettings(reboot_after_s=20.0)))
    frames = decode(b"".join(c.data for c in at_rest.advance(30.0)))
    assert [f["gyro_calibration"] for f in frames if f.name == "CONFIG"] == [calibration["boot"]] * 2
    never = SimStream(Scenario("flight", 30.0, seed=1, firmware=FirmwareSettings(boot_calibration_s=8.0)))  # past the rest
    frames = decode(b"".join(c.data for c in never.advance(30.0)))
    assert [f["gyro_calibration"] for f in frames if f.name == "CONFIG"] == [calibration["none"]]
    assert not never.firmware.imu.gyro_offset_dps.any()
