"""Gyro bias measured at rest in the pipeline: a board that skips its boot calibration streams its
turn-on bias (up to ±20 °/s); the session measures it while the craft is still, records it as an event,
and the estimators that do not estimate their own bias get the gyro without it."""

import numpy as np

from groundstation import mounting
from groundstation.session_makers.pipeline import Pipeline
from groundstation.sim.firmware import FirmwareSettings
from groundstation.sim.stream import Scenario, SimStream


def test_the_turn_on_bias_is_measured_at_rest_recorded_and_removed():
    stream = SimStream(Scenario("static", 20.0, seed=5, firmware=FirmwareSettings(mode="raw", boot_calibration_s=0)))
    pipeline = Pipeline(("hf", "ecf"))
    for chunk in stream.advance(20.0) + stream.flush():
        pipeline.feed(round(chunk.t_s * 1e9), chunk.data)

    events = [e for e in pipeline.events if e["kind"] == "gyro_bias"]
    assert len(events) == 1
    measured = np.array(events[0]["bias_rad_s"])
    # The simulator's own turn-on bias, turned from the chip's axes onto the body axes.
    true_body = mounting.matrix(pipeline.sensor.mounting) @ np.radians(stream.firmware.imu.gyro_turn_on_bias_dps)
    assert np.abs(true_body).max() > np.radians(1.0)  # a bias worth removing
    np.testing.assert_allclose(measured, true_body, atol=np.radians(0.1))

    # hf has no bias state of its own: with the bias removed its yaw stays put at rest (drift < 1°
    # over the rest of the run, where 1 °/s of bias alone would turn it by tens of degrees).
    imu = pipeline.imu.to_dict()
    after = imu["time_s"] > imu["time_s"][0] + 5.0
    qw, qz = imu["hf_qw"][after], imu["hf_qz"][after]
    yaw_deg = np.degrees(2 * np.arctan2(qz, qw))
    assert np.ptp(yaw_deg) < 1.0

