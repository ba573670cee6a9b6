"""Stream-rate requests: only REQUEST_DATA_STREAM and SET_MESSAGE_INTERVAL go up, addressed to the
autopilot that sent the heartbeat, repeated while its IMU stays slow; the slow-IMU note."""

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation.autopilot.decoder import MavlinkDecoder
from groundstation.autopilot.records import ImuSample, VehicleStatus
from groundstation.autopilot.imu_rate import MIN_FILTER_RATE_HZ, slow_imu_note
from groundstation.autopilot.streams import StreamRequester
from groundstation.session_parts.figures import rate_hz as figures_rate_hz

ARDUPILOT = VehicleStatus(1, 1, 0, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 2, "STABILIZE", False, 3, 0)
CAMERA = VehicleStatus(1, 100, 0, mavlink.MAV_AUTOPILOT_INVALID, 30, "Mode(0x00000000)", False, 3, 0)


def imu(t_us):
    return ImuSample(1, 1, 0, t_us, "RAW_IMU", (0, 0, 0), (0, 0, -1), 25.0)


def sent(data: bytes) -> list:
    return MavlinkDecoder().messages(data)


def test_requests_go_to_the_autopilot_only_and_repeat_while_the_imu_stays_slow():
    requester = StreamRequester(rate_hz=50.0, retry_s=5.0)
    first = sent(requester.update([CAMERA, ARDUPILOT], 0))
    assert {m.get_type() for m in first} == {"REQUEST_DATA_STREAM", "COMMAND_LONG"}
    assert all((m.target_system, m.target_component) == (1, 1) for m in first)
    assert all(m.command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL and m.param2 == 20_000 for m in first if m.get_type() == "COMMAND_LONG")
    assert {m.param1 for m in first if m.get_type() == "COMMAND_LONG"} >= {mavlink.MAVLINK_MSG_ID_RAW_IMU, mavlink.MAVLINK_MSG_ID_ATTITUDE}
    slow = [imu(i * 250_000) for i in range(10)]  # 4 Hz
    assert requester.update([*slow, ARDUPILOT], 4_000_000_000) == b""  # not yet: retry after 5 s
    again = requester.update([ARDUPILOT], 5_000_000_000)
    assert again
    fast = [imu(3_000_000 + i * 20_000) for i in range(60)]  # 50 Hz now
    assert requester.update([*fast, ARDUPILOT], 20_000_000_000) == b""
    assert requester.monitor.rate_hz == pytest.approx(50.0, rel=1e-12) and not requester.monitor.too_slow
    decoder = MavlinkDecoder()
    decoder.feed(b"".join(m.get_msgbuf() for m in first) + again)
    assert decoder.senders[(255, 190)].lost == 0  # the GCS's sequence numbers keep counting
    assert decoder.senders[(255, 190)].received == 2 * len(first)


def test_slow_imu_note():
    assert slow_imu_note(50.0) is None and slow_imu_note(float("nan")) is None
    note = slow_imu_note(2.0)
    assert "2.0 Hz" in note and f"{MIN_FILTER_RATE_HZ:.0f} Hz" in note


def test_the_users_request_goes_to_the_vehicle_and_sets_the_rate_for_later():
    import pytest

    requester = StreamRequester(rate_hz=50.0)
    assert requester.request_now(10.0, 0) == b""  # none heard yet: the first heartbeat gets 10 Hz
    first = sent(requester.update([ARDUPILOT], 1))
    assert {m.req_message_rate for m in first if m.get_type() == "REQUEST_DATA_STREAM"} == {10}
    asked = sent(requester.request_now(25.0, 2))
    assert {m.req_message_rate for m in asked if m.get_type() == "REQUEST_DATA_STREAM"} == {25}
    assert {m.param2 for m in asked if m.get_type() == "COMMAND_LONG"} == {40_000}  # µs between messages
    assert all((m.target_system, m.target_component) == (1, 1) for m in asked)
    for bad in (0.0, -5.0, float("nan"), 1e4):
        with pytest.raises(ValueError, match="stream rate"):
            requester.request_now(bad, 3)


def test_the_imu_rate_is_computed_once_per_new_sample_not_each_time_it_is_asked(monkeypatch):
    """Issue 35: the front-end asks the rate after every chunk it is fed (a .tlog: every packet); the median
    was taken each time (27 % of opening a .tlog). It is taken again only when a sample has come since."""
    from groundstation.autopilot import imu_rate

    taken = []
    monkeypatch.setattr(imu_rate, "rate_hz", lambda times: taken.append(len(times)) or figures_rate_hz(times))
    monitor = imu_rate.ImuRateMonitor()
    for i in range(10):
        monitor.add(i * 20_000)
    rates = [monitor.rate_hz for _ in range(100)]
    assert rates == [50.0] * 100 and len(taken) == 1
    monitor.add(9 * 20_000)  # not later than the last: not kept, the rate stands
    monitor.add(10 * 20_000 + 5_000)
    assert monitor.rate_hz == 50.0 and monitor.too_slow is False and len(taken) == 2

