"""A board that reboots or whose clock jumps, mid-session: the cases of issue 11, through the simulator.

Before: a reboot after 30 s stepped time_s back 29 s; after 40 min of uptime it made a 60 s session
1,924 s long; a +1 h jump sent time_s to -695 s; onboard_* went NaN in half the rows; no event.
"""

import numpy as np
import pytest

from groundstation.estimation.base import INITIALISED
from groundstation.recording import RecordingWriter
from groundstation.session_makers.load import load_session
from groundstation.session_makers.pipeline import Pipeline
from groundstation.sim.firmware import FirmwareSettings
from groundstation.sim.stream import Scenario, SimStream

DURATION_S = 60.0
CASES = {
    # name: (firmware settings, event kind, device time before the event (s), after it (s))
    "reboot after 30 s": (FirmwareSettings(reboot_after_s=30.0), "device_reset", 30.0, 1.0),
    # up 40 min before the session: a clock jump during the silent boot calibration sets its clock there
    "reboot after 40 min uptime": (FirmwareSettings(clock_jump_after_s=0.5, clock_jump_s=2400.0, reboot_after_s=30.0),
                                   "device_reset", 2430.0, 1.0),
    "clock jump of +1 h": (FirmwareSettings(clock_jump_after_s=30.0, clock_jump_s=3600.0), "clock_jump", 30.0, 3630.0),
}


@pytest.fixture(scope="module", params=list(CASES))
def case(request, tmp_path_factory):
    firmware, kind, before_s, after_s = CASES[request.param]
    path = tmp_path_factory.mktemp("reboot") / "session.gsrec"
    stream = SimStream(Scenario("hover", DURATION_S, seed=5, firmware=firmware))
    with RecordingWriter(path, {"source": "simulated bridge", "filters": ["ahf"]}) as writer:
        for chunk in stream.advance(stream.end_s) + stream.flush():
            writer.write_chunk(round(chunk.t_s * 1e9), chunk.data)
    return load_session(path), kind, before_s, after_s


def test_time_is_monotonic_and_follows_the_wall_clock(case):
    data, *_ = case
    imu = data.tables["imu"]
    assert np.all(np.diff(data.time_s) > 0)
    samples = np.isfinite(imu["device_time_us"])  # all rows but the gap row
    # In wall-clock terms: session time is the host's elapsed time, to within the delivery delay.
    assert np.abs(data.time_s[samples] - imu["host_time_s"][samples]).max() < 0.02
    assert DURATION_S - 1.5 < data.time_s[-1] <= DURATION_S


def test_the_event_is_recorded_with_both_clocks(case):
    data, kind, before_s, after_s = case
    events = [e for e in data.events if e["kind"] in ("device_reset", "clock_jump")]
    assert len(events) == 1 and events[0]["kind"] == kind
    event = events[0]
    assert abs(event["device_time_us_before"] * 1e-6 - before_s) < 0.02
    assert abs(event["device_time_us_after"] * 1e-6 - after_s) < 0.02
    assert event["session_time_before_s"] < event["session_time_s"] < event["session_time_before_s"] + 1.5
    assert data.link.counters["frames_lost"] == 0  # a restart is not a loss


def test_every_table_shows_the_gap_and_the_estimators_start_over(case):
    data, *_ = case
    for name in ("imu", "onboard", "status"):
        rows = np.column_stack(list(data.tables[name].values()))
        gap = np.flatnonzero(np.isnan(rows[:, 1]))
        assert len(gap) == 1, name
        assert np.isnan(rows[gap[0], 1:]).all() and np.isfinite(rows[gap[0], 0])
    imu = data.tables["imu"]
    after_gap = np.flatnonzero(np.isnan(imu["device_time_us"]))[0] + 1
    # The filter started over from its last attitude (EstimatorBank.restart), not waiting for gravity.
    assert not int(imu["ahf_status"][after_gap]) & INITIALISED
    last = np.array([imu[f"ahf_q{c}"][after_gap - 2] for c in "wxyz"])
    first = np.array([imu[f"ahf_q{c}"][after_gap] for c in "wxyz"])
    assert abs(float(last @ first)) > np.cos(np.radians(5.0) / 2)  # within 5 deg: the hover moved over the 1 s boot
    dt = np.diff(imu["device_time_us"][after_gap:]) * 1e-6
    assert np.all((dt > 0.005) & (dt < 0.015))  # the new segment's own device time


def test_the_onboard_estimate_stays_aligned_after_it(case):
    data, *_ = case
    samples = np.isfinite(data.tables["imu"]["device_time_us"])
    assert np.isfinite(data.quaternion("onboard")[samples]).all()  # before: NaN in half the rows after a reboot
    assert np.isnan(data.quaternion("onboard")[~samples]).all()


def simulated_pipeline(firmware: FirmwareSettings, duration_s: float, until_s: float | None = None) -> Pipeline:
    """A pipeline fed a simulated session's chunks (with their arrival times) up to ``until_s``."""
    stream = SimStream(Scenario("hover", duration_s, seed=2, firmware=firmware))
    pipeline = Pipeline()
    for chunk in stream.advance(stream.end_s if until_s is None else until_s):
        pipeline.feed(round(chunk.t_s * 1e9), chunk.data)
    return pipeline


@pytest.mark.parametrize("firmware", [FirmwareSettings(reboot_after_s=20.0),
                                      FirmwareSettings(clock_jump_after_s=20.0, clock_jump_s=3600.0)])
def test_link_latency_and_clock_offset_start_over_with_the_device_clock(firmware):
    """2 s after the restart (inside the 10 s latency window); before: 38,403 ms after a bridge restart."""
    pipeline = simulated_pipeline(firmware, 30.0, until_s=23.0)
    assert [e["kind"] for e in pipeline.events if e["kind"] in ("device_reset", "clock_jump")]
    clock = pipeline.link.clock()
    assert clock["latency_p99_ms"] < 10
    # host - device: the host origin is 0 and the new device time is the boot's (1 s at 21 s) or 3620 s at 20 s
    expected_offset_s = 20.0 if firmware.reboot_after_s else -3600.0
    assert abs(clock["clock_offset_s"] - expected_offset_s) < 0.05


def test_a_reboot_does_not_inflate_the_loss_rate():
    """The loss per second around a reboot stays 0 (before: 61 % for a bridge restart)."""
    pipeline = simulated_pipeline(FirmwareSettings(reboot_after_s=5.0), 10.0)
    lost_per_second = pipeline.link.per_second.column("frames_lost")
    assert len(lost_per_second) >= 8 and not lost_per_second.any()
