"""The simulated aircraft speaking MAVLink as an ArduPilot copter would (pymavlink's encoder), for the
live MAVLink path: the same truth profiles as the rest of the simulator, the same link impairments.

It sends ``HEARTBEAT`` (ArduPilot, quadrotor, disarmed STABILIZE) and ``SYS_STATUS`` at 1 Hz,
``RAW_IMU`` and ``ATTITUDE`` at a telemetry-link rate until the ground station asks for more,
``SCALED_PRESSURE`` at 10 Hz and ``GPS_RAW_INT`` at 5 Hz, and ``RADIO_STATUS`` at 1 Hz from a SiK radio
(system 51, component 68). ``texts`` are said as ArduPilot says them, in ``STATUSTEXT`` at their times:
one message for up to 50 characters, else 50-character chunks sharing an ``id`` (MAVLink 2's rule;
MAVLink 1 has no ``id``, so a long text is cut at 50 characters there). ``RAW_IMU`` is in ArduPilot's units (mG, mrad/s, mgauss): an ideal IMU on the
body axes (FRD) from the truth plus white noise, rounded to those integers. ``ATTITUDE`` is the truth, so
the onboard estimate it carries is exact.

Uplink: ``REQUEST_DATA_STREAM`` (RAW_SENSORS: RAW_IMU and SCALED_PRESSURE; EXTRA1: ATTITUDE) and
``MAV_CMD_SET_MESSAGE_INTERVAL`` change rates (up to ``base_rate_hz``) and are listed in ``requests``;
every other command is refused (``COMMAND_ACK`` DENIED) and listed in ``refused`` — the ground station
must never send one.

It has the interface of ``SimStream`` (``link``, ``advance``, ``flush``, ``next_event_s``, ``receive``,
``end_s``), so ``PtyBridge`` and ``UdpBridge`` carry it unchanged.
"""

from __future__ import annotations

import math

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation import geodesy
from groundstation import quaternion as quat
from groundstation.autopilot.decoder import new_parser
from groundstation.autopilot.streams import pack_next
from groundstation.sim.extra_sensors import origin
from groundstation.sim.firmware import SentFrame
from groundstation.sim.link import Chunk, InFlight, Link
from groundstation.sim.profiles import make_profile
from groundstation.sim.seeds import stream
from groundstation.sim.stream import Scenario
from groundstation.units import STANDARD_GRAVITY_M_S2

ACC_NOISE_G = 0.004  # σ per sample: about the MPU-6000 class at a 100 Hz bandwidth
GYR_NOISE_RAD_S = 0.0012
DEFAULT_INTERVALS_S = {"HEARTBEAT": 1.0, "SYS_STATUS": 1.0, "RADIO_STATUS": 1.0, "SCALED_PRESSURE": 0.1, "GPS_RAW_INT": 0.2}
STREAM_GROUP_MESSAGES = {mavlink.MAV_DATA_STREAM_RAW_SENSORS: ("RAW_IMU", "SCALED_PRESSURE"), mavlink.MAV_DATA_STREAM_EXTRA1: ("ATTITUDE",)}
MESSAGE_NAMES = {mavlink.MAVLINK_MSG_ID_RAW_IMU: "RAW_IMU", mavlink.MAVLINK_MSG_ID_ATTITUDE: "ATTITUDE",
                 mavlink.MAVLINK_MSG_ID_SCALED_PRESSURE: "SCALED_PRESSURE", mavlink.MAVLINK_MSG_ID_GPS_RAW_INT: "GPS_RAW_INT"}  # fmt: skip
BLOCK_S = 0.1  # truth is evaluated for this much time at once
# What the simulated SiK radio pair and battery report (RADIO_STATUS in the radio's units, SYS_STATUS)
RADIO_STATUS = {"rssi": 180, "remrssi": 175, "txbuf": 95, "noise": 40, "remnoise": 42, "rxerrors": 3, "fixed": 0}
BATTERY = {"voltage_battery": 12_600, "current_battery": 150, "battery_remaining": 80}  # mV, cA, %


class MavlinkAircraft:
    def __init__(self, scenario: Scenario = Scenario(), base_rate_hz: float = 200.0, telemetry_rate_hz: float = 4.0,
                 mavlink1: bool = False, texts: tuple[tuple[float, int, str], ...] = ()):  # fmt: skip
        self.scenario = scenario
        self.profile = make_profile(scenario.profile, scenario.duration_s, scenario.seed)
        self.link = Link(scenario.link, scenario.seed)
        self.base_rate_hz = base_rate_hz
        self.mavlink1 = mavlink1
        self.intervals_s = {**DEFAULT_INTERVALS_S, "RAW_IMU": 1.0 / telemetry_rate_hz, "ATTITUDE": 1.0 / telemetry_rate_hz}
        self._due_s = dict.fromkeys(self.intervals_s, 0.0)
        self._autopilot = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self._radio = mavlink.MAVLink(None, srcSystem=51, srcComponent=68)
        self._rng = stream(scenario.seed, "mavlink_imu")
        self._uplink = new_parser()
        self._next = 0  # the next base sample to send
        self._in_flight = InFlight()
        self._replies: list[SentFrame] = []
        self.requests: list[tuple[str, float]] = []  # (message, interval s) as asked by the ground
        self.refused: list[int] = []  # MAV_CMD numbers of commands that were not stream requests
        self.texts = sorted(texts)  # (time s, MAV_SEVERITY, text) still to say
        self._text_id = 0

    @property
    def end_s(self) -> float:
        return self.profile.duration_s

    def advance(self, t_s: float) -> list[Chunk]:
        frames, self._replies = self._replies, []
        while self._next / self.base_rate_hz <= t_s:
            frames += self._block(min(t_s, self._next / self.base_rate_hz + BLOCK_S))
        self._in_flight.add(self.link.carry(frames))
        return self._in_flight.due(t_s)

    def flush(self) -> list[Chunk]:
        return self._in_flight.flush()

    def next_event_s(self) -> float:
        next_sample = self._next / self.base_rate_hz
        return self._in_flight.next_arrival_s(next_sample)

    def receive(self, data: bytes) -> None:
        """Uplink bytes: stream-rate requests are honoured; every other command is refused."""
        for msg in self._uplink.parse_buffer(data) or ():
            kind = msg.get_type()
            if kind == "REQUEST_DATA_STREAM":
                for name in STREAM_GROUP_MESSAGES.get(msg.req_stream_id, ()):
                    self._set_interval(name, 1.0 / msg.req_message_rate if msg.start_stop and msg.req_message_rate > 0 else math.inf)
            elif kind == "COMMAND_LONG":
                self._replies.append(self._frame(self._autopilot, self._autopilot.command_ack_encode(msg.command, self._command(msg)),
                                                 self._next / self.base_rate_hz, None))  # fmt: skip
            elif kind in ("COMMAND_INT", "SET_MODE", "MANUAL_CONTROL", "SET_POSITION_TARGET_LOCAL_NED", "SET_ATTITUDE_TARGET"):
                self.refused.append(getattr(msg, "command", -1))

    def _command(self, msg) -> int:
        """The MAV_RESULT of a COMMAND_LONG: rates are set (or unsupported, for messages we do not send)."""
        if msg.command != mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
            self.refused.append(msg.command)
            return mavlink.MAV_RESULT_DENIED
        name = MESSAGE_NAMES.get(int(msg.param1))
        if name is None:
            return mavlink.MAV_RESULT_UNSUPPORTED
        self._set_interval(name, msg.param2 / 1e6 if msg.param2 > 0 else math.inf)
        return mavlink.MAV_RESULT_ACCEPTED

    def _frame(self, encoder, msg, t_s: float, t_us: int | None) -> SentFrame:
        return SentFrame(t_s, pack_next(encoder, msg, self.mavlink1), t_us)

    def _set_interval(self, name: str, interval_s: float) -> None:
        interval_s = max(interval_s, 1.0 / self.base_rate_hz)
        self.intervals_s[name] = interval_s
        self._due_s[name] = min(self._due_s[name], self._next / self.base_rate_hz + interval_s)
        self.requests.append((name, interval_s))

    def _block(self, until_s: float) -> list[SentFrame]:
        """The frames of the base samples up to ``until_s``."""
        stop = int(math.floor(until_s * self.base_rate_hz)) + 1
        k = np.arange(self._next, stop)
        self._next = stop
        t_s = k / self.base_rate_hz
        truth = self.profile.truth(t_s)
        acc_mg = np.rint((truth.specific_force_body_m_s2() / STANDARD_GRAVITY_M_S2 + self._rng.normal(0, ACC_NOISE_G, (len(k), 3))) * 1000)
        gyr_mrad = np.rint((truth.rate_body_rad_s + self._rng.normal(0, GYR_NOISE_RAD_S, (len(k), 3))) * 1000)
        aux = self.scenario.extra
        mag_mgauss = np.rint(quat.rotate(quat.conjugate(truth.q_body_to_ned), np.array(aux.mag_field_ned_ut)) * 10)
        yaw, pitch, roll = quat.to_euler_zyx(truth.q_body_to_ned).T
        frames = []
        for i, t in enumerate(t_s.tolist()):
            while self.texts and self.texts[0][0] <= t:
                frames += self._statustext(t, *self.texts.pop(0)[1:])
            for name, interval in self.intervals_s.items():
                if t + 1e-9 < self._due_s[name]:
                    continue
                self._due_s[name] = max(self._due_s[name] + interval, t + 0.5 / self.base_rate_hz)
                encoder, msg = self._message(name, i, t, truth, acc_mg, gyr_mrad, mag_mgauss, (yaw, pitch, roll))
                frames.append(self._frame(encoder, msg, t, int(round(t * 1e6))))
        return frames

    def _statustext(self, t_s: float, severity: int, text: str) -> list[SentFrame]:
        chunks = [text[at : at + 50] for at in range(0, max(len(text), 1), 50)]
        if len(chunks) > 1 and self.mavlink1:
            chunks = chunks[:1]
        if len(chunks) > 1:
            self._text_id = self._text_id % 65535 + 1
            if len(chunks[-1]) == 50:
                chunks.append("")  # the NUL that ends the text needs a chunk of its own
        text_id = self._text_id if len(chunks) > 1 else 0
        a = self._autopilot
        return [self._frame(a, a.statustext_encode(severity, chunk.encode(), text_id, seq), t_s, None) for seq, chunk in enumerate(chunks)]

    def _message(self, name, i, t, truth, acc_mg, gyr_mrad, mag_mgauss, euler):
        a = self._autopilot
        boot_ms = int(round(t * 1000))
        if name == "RAW_IMU":
            return a, a.raw_imu_encode(int(round(t * 1e6)), *acc_mg[i].astype(int).tolist(), *gyr_mrad[i].astype(int).tolist(),
                                       *mag_mgauss[i].astype(int).tolist(), 0, 3500)  # fmt: skip
        if name == "ATTITUDE":
            yaw, pitch, roll = (float(e[i]) for e in euler)
            p, q, r = truth.rate_body_rad_s[i].tolist()
            return a, a.attitude_encode(boot_ms, roll, pitch, yaw, p, q, r)
        if name == "HEARTBEAT":
            return a, a.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                         mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 0, mavlink.MAV_STATE_STANDBY)  # fmt: skip
        if name == "SYS_STATUS":
            return a, a.sys_status_encode(0, 0, 0, 150, **BATTERY, drop_rate_comm=0, errors_comm=0, errors_count1=0,
                                          errors_count2=0, errors_count3=0, errors_count4=0)
        if name == "RADIO_STATUS":
            return self._radio, self._radio.radio_status_encode(**RADIO_STATUS)
        aux = self.scenario.extra
        if name == "SCALED_PRESSURE":
            pressure_pa = float(geodesy.pressure_pa(-truth.pos_ned_m[i, 2], aux.ground_pressure_pa, aux.ground_temperature_c))
            return a, a.scaled_pressure_encode(boot_ms, pressure_pa / 100.0, 0.0, 2500)
        lat, lon, alt = (float(v) for v in geodesy.geodetic_from_ned(truth.pos_ned_m[i], origin(aux)))
        vel_n, vel_e, _ = truth.vel_ned_m_s[i].tolist()
        speed_cm_s = int(round(math.hypot(vel_n, vel_e) * 100))
        course_cdeg = int(round(math.degrees(math.atan2(vel_e, vel_n)) % 360 * 100))
        return a, a.gps_raw_int_encode(int(round(t * 1e6)), 3, int(round(lat * 1e7)), int(round(lon * 1e7)), int(round(alt * 1000)),
                                       80, 120, speed_cm_s, course_cdeg, aux.gps_satellites)  # fmt: skip
