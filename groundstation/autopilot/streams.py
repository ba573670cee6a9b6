"""The only uplink a MAVLink session sends: requests for stream rates (and, on ``udpout``, a GCS
heartbeat so the vehicle learns our address). Nothing here arms, changes mode or moves the aircraft.

Two requests, because autopilots honour different ones: ``REQUEST_DATA_STREAM`` (ArduPilot; groups
RAW_SENSORS = RAW_IMU, SCALED_PRESSURE, ... and EXTRA1 = ATTITUDE) and ``MAV_CMD_SET_MESSAGE_INTERVAL``
per message (PX4 and current ArduPilot). The ground station sends as system 255, component 190
(MAV_COMP_ID_MISSIONPLANNER), as GCSs do.

``ImuRateMonitor`` says when the IMU arrives too slowly for host filtering to mean anything (many
telemetry links send RAW_IMU at 2–10 Hz; the host filters integrate the gyro between samples).
"""

from __future__ import annotations

from collections import deque

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation.autopilot.records import ImuSample, VehicleStatus
from groundstation.autopilot.vehicle import AUTOPILOTS, Vehicle
from groundstation.session_parts.figures import rate_hz

GCS_SYSTEM, GCS_COMPONENT = 255, 190
MIN_FILTER_RATE_HZ = 20.0  # below: the gyro is integrated over > 50 ms steps; host estimates are display only
REQUESTED_RATE_HZ = 50.0  # what a session asks an autopilot for unless the user asks otherwise
IMU_RATE = "imu_rate"  # the ``about`` of a live slow-IMU warning event: a product names the whole session's rate instead
MAX_REQUEST_RATE_HZ = 400.0  # the fastest IMU loop ArduPilot and PX4 stream; REQUEST_DATA_STREAM takes whole Hz
STREAMED_MESSAGES = (mavlink.MAVLINK_MSG_ID_RAW_IMU, mavlink.MAVLINK_MSG_ID_HIGHRES_IMU,
                     mavlink.MAVLINK_MSG_ID_ATTITUDE, mavlink.MAVLINK_MSG_ID_ATTITUDE_QUATERNION)  # fmt: skip
STREAM_GROUPS = (mavlink.MAV_DATA_STREAM_RAW_SENSORS, mavlink.MAV_DATA_STREAM_EXTRA1)


def gcs_encoder() -> mavlink.MAVLink:
    return mavlink.MAVLink(None, srcSystem=GCS_SYSTEM, srcComponent=GCS_COMPONENT)


def pack_next(encoder: mavlink.MAVLink, msg, mavlink1: bool = False) -> bytes:
    """``msg`` packed with the sender's next sequence number (``MAVLink.send`` counts it; ``pack`` does not)."""
    data = msg.pack(encoder, mavlink1)
    encoder.seq = (encoder.seq + 1) % 256
    return data


def gcs_heartbeat(encoder: mavlink.MAVLink | None = None) -> bytes:
    """A ground station's HEARTBEAT (MAV_TYPE_GCS): how a UDP peer learns where to send."""
    encoder = encoder or gcs_encoder()
    return pack_next(encoder, encoder.heartbeat_encode(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, mavlink.MAV_STATE_ACTIVE))


def stream_requests(target_system: int, target_component: int, rate_hz: float, encoder: mavlink.MAVLink | None = None) -> bytes:
    """Bytes asking the autopilot for the IMU and attitude at ``rate_hz`` (both request kinds), packed
    with ``encoder``'s sequence numbers (pass the session's own to keep them counting)."""
    encoder = encoder or gcs_encoder()
    messages = [encoder.request_data_stream_encode(target_system, target_component, group, int(round(rate_hz)), 1) for group in STREAM_GROUPS]
    messages += [encoder.command_long_encode(target_system, target_component, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                                             msg_id, 1e6 / rate_hz, 0, 0, 0, 0, 0) for msg_id in STREAMED_MESSAGES]  # fmt: skip
    return b"".join(pack_next(encoder, msg) for msg in messages)


class StreamRequester:
    """Asks the vehicle (``vehicle.Vehicle``: picked by the user, else the first autopilot heard) for the
    IMU and attitude at ``rate_hz``, and asks again every ``retry_s`` while its IMU stays slower than
    ``MIN_FILTER_RATE_HZ`` (a request can be lost on a radio link, and ArduPilot's SRx_ parameters may
    override it). No other sender is ever asked: another autopilot or a spoofer on the link gets nothing."""

    def __init__(self, rate_hz: float = REQUESTED_RATE_HZ, retry_s: float = 5.0, vehicle: Vehicle | None = None):
        self.rate_hz = rate_hz
        self.retry_ns = int(retry_s * 1e9)
        self.vehicle = vehicle or Vehicle()
        self.monitor = ImuRateMonitor()  # the vehicle's IMU
        self._asked_ns: int | None = None  # when the vehicle was last asked
        self._encoder = gcs_encoder()

    def update(self, records, t_host_ns: int) -> bytes:
        """The request bytes to send now (often none), given the records just decoded."""
        out = b""
        for r in records:
            self.vehicle.choose(r)
            if not self.vehicle.sent(r):
                continue
            if isinstance(r, ImuSample):
                self.monitor.add(r.time_us)
            elif isinstance(r, VehicleStatus) and r.autopilot in AUTOPILOTS:
                slow = not self.monitor.rate_hz >= MIN_FILTER_RATE_HZ
                if self._asked_ns is None or (slow and t_host_ns - self._asked_ns >= self.retry_ns):
                    self._asked_ns = t_host_ns
                    out += stream_requests(*self.vehicle.sender, self.rate_hz, self._encoder)
        return out

    def request_now(self, rate_hz: float, t_host_ns: int) -> bytes:
        """The user's request: the vehicle, if asked before, asked for ``rate_hz`` now, and at that rate
        from now on (not yet: its first HEARTBEAT gets it)."""
        if not 0.0 < rate_hz <= MAX_REQUEST_RATE_HZ:
            raise ValueError(f"a stream rate must be above 0 and at most {MAX_REQUEST_RATE_HZ:g} Hz, not {rate_hz:g}")
        self.rate_hz = rate_hz
        if self._asked_ns is None:
            return b""
        self._asked_ns = t_host_ns
        return stream_requests(*self.vehicle.sender, rate_hz, self._encoder)


class ImuRateMonitor:
    """IMU rate from the autopilot's own timestamps (median interval of the last ``window`` samples)."""

    def __init__(self, window: int = 50):
        self._times_us: deque[int] = deque(maxlen=window)
        self._rate_hz: float | None = None  # of the samples held (None: to be taken again)

    def add(self, time_us: int) -> None:
        if not self._times_us or time_us > self._times_us[-1]:
            self._times_us.append(time_us)
            self._rate_hz = None

    @property
    def rate_hz(self) -> float:
        """Asked after every chunk the front-end is fed: the median is taken again only when a sample came."""
        if len(self._times_us) < 3:
            return float("nan")
        if self._rate_hz is None:
            self._rate_hz = rate_hz(np.array(self._times_us, dtype=float) / 1e6)
        return self._rate_hz

    @property
    def too_slow(self) -> bool:
        return too_slow(self.rate_hz)


def too_slow(rate_hz: float) -> bool:
    """Whether an IMU at ``rate_hz`` is too slow for host filtering: the one rule the requester, the warnings
    and the window (the onboard estimate as the attitude, no fused position) follow; NaN (no rate yet): not."""
    return rate_hz < MIN_FILTER_RATE_HZ


def slow_imu_note(rate_hz: float) -> str | None:
    """The message the window, the importer and evaluate show; None when the rate is fine."""
    if not too_slow(rate_hz):
        return None
    return (f"IMU at {rate_hz:.1f} Hz: too slow for host filtering (needs >= {MIN_FILTER_RATE_HZ:.0f} Hz); "
            "the host estimates are shown but mean little; compare with the onboard attitude instead")
