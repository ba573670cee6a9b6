"""The gyro bias at rest in a live MAVLink session: bytes from pymavlink's encoder into the pipeline, the
IMU at 4 Hz and then at 50 Hz (as after the stream requests). An armed vehicle loitering at a steady
-13.5 °/s recorded that rate as its gyro bias (and ahf and hf ran away from every heading); armed, nothing
is measured, while a disarmed vehicle standing still gets its bias measured."""

import random

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation.session_makers.pipeline import Pipeline
from mavlink_helpers import Sender, ardupilot_heartbeat

BIAS_MRAD_S = (7, -12, 9)  # RAW_IMU's unit


def disarmed_heartbeat(sender: Sender) -> bytes:
    return sender.heartbeat(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                            mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 5, mavlink.MAV_STATE_STANDBY)


def session(heartbeat, yaw_rate_mrad_s: int) -> Pipeline:
    """20 s: 2 s of RAW_IMU at 4 Hz, then 50 Hz, with one-count noise and a heartbeat each second; the
    magnetometer fields constant (the worst case: nothing but the vehicle's state tells the turn)."""
    autopilot, rng = Sender(), random.Random(1)
    pipeline = Pipeline(("hf",), protocol="mavlink")
    times_us = [i * 250_000 for i in range(8)] + [2_000_000 + i * 20_000 for i in range(900)]
    next_heartbeat_us = 0
    for time_us in times_us:
        data = b""
        if time_us >= next_heartbeat_us:
            data, next_heartbeat_us = heartbeat(autopilot), next_heartbeat_us + 1_000_000
        noise = [rng.choice((-1, 0, 1)) for _ in range(6)]
        gyr = [b + n for b, n in zip(BIAS_MRAD_S, noise[3:])]
        gyr[2] += yaw_rate_mrad_s
        data += autopilot.raw_imu(time_us, noise[0], noise[1], -1000 + noise[2], *gyr, 200, 0, 400, 0, 2500)
        pipeline.feed(1_000_000_000 + time_us * 1000, data)
    return pipeline


def biases(pipeline):
    return [e["bias_rad_s"] for e in pipeline.events if e["kind"] == "gyro_bias"]


def test_an_armed_loitering_vehicle_records_no_gyro_bias():
    assert biases(session(ardupilot_heartbeat, yaw_rate_mrad_s=-236)) == []  # -13.5 °/s


def test_a_disarmed_vehicle_standing_still_gets_its_bias_measured():
    (bias,) = biases(session(disarmed_heartbeat, yaw_rate_mrad_s=0))
    np.testing.assert_allclose(bias, np.array(BIAS_MRAD_S) / 1000.0, atol=0.0005)
