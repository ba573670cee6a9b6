"""The only uplink a MAVLink session sends: requests for stream rates (and, on ``udpout``, a GCS
heartbeat so the vehicle learns our address). Nothing here arms, changes mode or moves the aircraft.

Two requests, because autopilots honour different ones: ``REQUEST_DATA_STREAM`` (ArduPilot; groups
RAW_SENSORS = RAW_IMU, SCALED_PRESSURE, ... and EXTRA1 = ATTITUDE) and ``MAV_CMD_SET_MESSAGE_INTERVAL``
per message (PX4 and current ArduPilot). The ground station sends as system 255, component 190
(MAV_COMP_ID_MISSIONPLANNER), as GCSs do.

The requester asks again while the IMU arrives too slowly for host filtering to mean anything (many
telemetry links send RAW_IMU at 2–10 Hz; the host filters integrate the gyro between samples): the rule is
``imu_rate``'s.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation.autopilot.imu_rate import MIN_FILTER_RATE_HZ, ImuRateMonitor
from groundstation.autopilot.records import ImuSample, VehicleStatus
from groundstation.autopilot.vehicle import AUTOPILOTS, Vehicle

GCS_SYSTEM, GCS_COMPONENT = 255, 190
REQUESTED_RATE_HZ = 50.0  # what a session asks an autopilot for unless the user asks otherwise
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
