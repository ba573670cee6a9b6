"""The pipeline's MAVLink front-end: an autopilot's bytes into the session's stages and tables.

``MavlinkDecoder`` (groundstation/autopilot) gives records already in this project's units and body
axes (FRD). They go where the project's own frames go:

- ``ImuSample`` -> the IMU stage (the same ``EstimatorBank``, table ``imu``), ``dt`` from the
  autopilot's ``time_us``; only the vehicle's first IMU stream with real samples (``imu_choice``: ``RAW_IMU``,
  ``HIGHRES_IMU``, not ArduSub's all-zero ``SCALED_IMU2``) feeds the estimators, and its magnetometer the
  compass; any other gets a table of its own (a warning says when one was passed over);
- ``OnboardAttitude`` -> ``onboard`` (no λ or flags: NaN);
- ``MagReading`` / ``BaroReading`` / ``GpsReading`` -> ``mag_raw`` / ``baro`` / ``gps`` and Aiding
  (GPS velocity aids only when all three NED components are known: GPS_RAW_INT has no vertical speed);
- ``VehicleStatus`` / ``Battery`` / ``LinkHealth`` -> ``heartbeat`` / ``sys_status`` / ``radio_status``
  (the mode and arming are a ``vehicle_status`` event when they change, ``modes``);
- ``StatusText`` -> a ``message`` event per whole text (chunks joined), ``ParamValue`` -> the pipeline's
  ``parameters`` and a ``parameter`` event when a known one changes (``messages``); their numbers also
  reach the ``statustext`` and ``param_value`` tables as generic rows, as ``GPS_RAW_INT``'s reach ``gps_raw_int``
  (its HDOP, which ``gps`` does not keep);
- ``GenericMessage`` -> one table per message type, added to the catalogue when the first one
  arrives (a message from another sender than the vehicle: ``<type>_<system>_<component>``).

The vehicle (``autopilot/vehicle.py``): the system the user picked (``mavlink:...?system=N``) or the
first autopilot heard, one (system, component); it alone feeds the estimators, the vehicle's tables,
arm and mode events and the lost count (its sequence numbers: a spoofer's cannot inflate it), and it
alone gets stream requests. Every other system id is an ``other_vehicle`` event, once. Tables of other
senders stop at ``OTHER_TABLES_MAX`` tables or ``OTHER_COLUMNS_MAX`` columns (a warning once; their
later messages counted in ``unplaced_messages``): 5,000 fake senders would otherwise make 5,000 tables,
past what a workbook can hold. The vehicle's own are bounded by the dialect (301 message types, 7,628
numeric columns), so a session stays within Excel's 16,384 columns.

Time: host times count from the arrival of the first whole message (a ``.tlog`` keeps no bytes
before it). The vehicle's timestamps (µs since boot) of IMU, attitude, magnetometer and barometer go
through the session's ``SessionClock``, so an autopilot reboot is a ``device_reset`` as for the
project's aircraft. GPS and generic messages take the current session time: their ``time_usec`` is
often GPS or UNIX time, not time since boot.

Uplink: ``StreamRequester``'s stream-rate requests only (``take_uplink``); when the IMU is still
slower than host filtering needs ``SLOW_WARNING_S`` after the first request, a warning event
(``slow_imu_note``) — in the pipeline's events, so a replay shows it at the same point. A session's
product names its whole IMU table's rate instead (``SessionData.warnings``): one rate, as its figures give it.
"""

from __future__ import annotations

import math

from firmware_protocol import DecoderStats
from groundstation.autopilot import records as rec
from groundstation.autopilot.decoder import MavlinkDecoder
from groundstation.autopilot.imu_choice import ImuChoice
from groundstation.autopilot.messages import StatusTexts, message_event, parameter_change
from groundstation.autopilot.modes import status_event
from groundstation.autopilot.imu_rate import IMU_RATE, slow_imu_note
from groundstation.autopilot.streams import REQUESTED_RATE_HZ, StreamRequester
from groundstation.autopilot.vehicle import Vehicle
from groundstation.session_parts.catalogue import Catalogue, message_table

SLOW_WARNING_S = 5.0  # the requester's retry interval: one retry's chance before the warning
OTHER_TABLES_MAX = 256  # tables of senders other than the vehicle
OTHER_COLUMNS_MAX = 4096  # and their columns: with the vehicle's 7,628 at most, well inside Excel's 16,384
KEPT_TABLES = ("imu", "onboard", "mag_raw", "baro", "gps", "position")  # the project's tables a MAVLink session fills
_NAN = math.nan
IMU_UNITS = {"acc_x": "g", "acc_y": "g", "acc_z": "g", "gyr_x": "rad/s", "gyr_y": "rad/s", "gyr_z": "rad/s"}


class MavlinkFrontEnd:
    def __init__(self, pipeline, rate_hz: float = REQUESTED_RATE_HZ, vehicle_system: int | None = None):
        self.pipeline = pipeline
        self.mavlink = MavlinkDecoder()
        self.decoder = self  # the pipeline's ``decoder``: ``stats`` in the project's counters
        self.stats = DecoderStats()
        self.vehicle = Vehicle(vehicle_system)
        self.requester = StreamRequester(rate_hz, vehicle=self.vehicle)
        self.other_tables: set[str] = set()  # tables made for senders other than the vehicle
        self.other_columns = 0
        self.unplaced_messages = 0  # of other senders, past the bound on their tables
        self.imu_choice = ImuChoice()  # which of the vehicle's IMU streams feeds the estimators
        self._uplink = b""
        self._first_request_ns: int | None = None
        self._slow_warned = False
        self._status: tuple | None = None  # (mode, armed) last seen
        self._texts = StatusTexts()
        self._route = {rec.ImuSample: self._imu, rec.OnboardAttitude: self._attitude, rec.MagReading: self._mag,
                       rec.BaroReading: self._baro, rec.GpsReading: self._gps, rec.GenericMessage: self._generic,
                       rec.VehicleStatus: self._vehicle_status, rec.Battery: self._record_row, rec.LinkHealth: self._record_row,
                       rec.StatusText: self._text, rec.ParamValue: self._parameter}  # fmt: skip

    @staticmethod
    def catalogue(catalogue: Catalogue) -> Catalogue:
        """The project's tables a MAVLink session fills, and the tables of the mapped records."""
        tables = {name: catalogue[name] for name in KEPT_TABLES}
        for record_type in rec.RECORD_TABLES:
            name, label, fields, units = rec.table_fields(record_type)
            tables[name] = message_table(name, label, fields, units)
        return Catalogue(tables)

    def feed(self, t_host_ns: int, data: bytes) -> None:
        before = self.mavlink.stats.messages
        records = self.mavlink.feed(data, t_host_ns)
        if before == 0 and self.mavlink.stats.messages:
            # Host times start at the first whole message, not the first bytes (the tail of a packet sent
            # before the port opened): a .tlog keeps messages only, and opens to the same host times.
            self.pipeline.t0_host_ns = t_host_ns
        self._count()
        self.pipeline.link.on_chunk(t_host_ns, self.stats, len(records))
        for record in records:
            self._route[type(record)](t_host_ns, record)
            if self.vehicle.newly_other(record):
                self.pipeline.events.append(other_vehicle_event(t_host_ns, record, self.vehicle))
        uplink = self.requester.update(records, t_host_ns)
        if uplink:
            self._uplink += uplink
            self._first_request_ns = self._first_request_ns or t_host_ns
        self._check_rate(t_host_ns)

    def request_streams(self, rate_hz: float, t_host_ns: int) -> None:
        """The user asked for the IMU and attitude at ``rate_hz``: queued for ``take_uplink``."""
        self._uplink += self.requester.request_now(rate_hz, t_host_ns)
        self._first_request_ns = t_host_ns  # the slow-IMU warning gives this request its time too
        self._slow_warned = False

    def take_uplink(self) -> bytes:
        uplink, self._uplink = self._uplink, b""
        return uplink

    def _count(self) -> None:
        """The MAVLink decoder's counters as the project's link counters (``LinkStats``, the link panel)."""
        m, s = self.mavlink.stats, self.stats
        s.bytes_in, s.frames, s.bytes_skipped = m.bytes_in, m.messages, m.bad_bytes
        s.crc_errors = m.bad_runs  # runs of bytes that were no valid message: CRC failures and junk
        s.frame_bytes = m.bytes_in - m.bad_bytes
        counts = self.mavlink.senders.get(self.vehicle.sender)
        s.frames_lost = counts.lost if counts is not None else 0  # the vehicle's: other senders' are not its losses

    def _check_rate(self, t_host_ns: int) -> None:
        if self._first_request_ns is None:
            return
        note = slow_imu_note(self.requester.monitor.rate_hz)
        if note is None:
            self._slow_warned = False
        elif not self._slow_warned and t_host_ns - self._first_request_ns >= SLOW_WARNING_S * 1e9:
            self._slow_warned = True
            self.pipeline._warn(t_host_ns, note, about=IMU_RATE)

    # -- records ----------------------------------------------------------------------------------

    def _from_vehicle(self, record) -> bool:
        """Whether ``record`` comes from the vehicle (which it may choose: ``Vehicle.choose``)."""
        self.vehicle.choose(record)
        return self.vehicle.sent(record)

    def _place(self, t_host_ns: int, record) -> None:
        if record.time_us is not None:
            self.pipeline.place(t_host_ns, record.time_us)

    def _imu(self, t_host_ns: int, r: rec.ImuSample) -> None:
        vehicle = self._from_vehicle(r)
        choice = self.imu_choice
        chosen_before = choice.chosen
        if not vehicle or not choice.take(r.source, r.acc_g):  # not the IMU: <source>_<system>
            label = f"{r.source} of system {r.system}, component {r.component} (not the IMU the estimators use)"
            name = f"{r.source}_{r.system}" + ("" if vehicle else f"_{r.component}")
            self._table_row(t_host_ns, name.lower(), label, list(IMU_UNITS), IMU_UNITS, (*r.acc_g, *r.gyr_rad_s), vehicle)
            return
        if chosen_before is None and (warning := choice.warning()):  # a stream the autopilot names but that has no sensor
            self.pipeline._warn(t_host_ns, warning)
        p = self.pipeline
        self._place(t_host_ns, r)
        p.imu_stage(t_host_ns, p._time_s, p._device_us, r.acc_g, r.gyr_rad_s, r.temperature_c, 1.0 / self.requester.rate_hz)

    def _attitude(self, t_host_ns: int, r: rec.OnboardAttitude) -> None:
        if self._from_vehicle(r):
            self._place(t_host_ns, r)
            self.pipeline.onboard_stage(r.q, _NAN, _NAN)

    def _mag(self, t_host_ns: int, r: rec.MagReading) -> None:
        if self._from_vehicle(r) and r.source == self.imu_choice.chosen:  # the compass that comes with the IMU
            self._place(t_host_ns, r)
            self.pipeline.magnetometer_stage(r.mag_uT, r.mag_uT)  # already body axes

    def _baro(self, t_host_ns: int, r: rec.BaroReading) -> None:
        if self._from_vehicle(r):
            self._place(t_host_ns, r)
            self.pipeline.barometer_stage(r.pressure_hpa * 100.0, r.temperature_c)

    def _gps(self, t_host_ns: int, r: rec.GpsReading) -> None:
        if not self._from_vehicle(r):
            return
        velocity = (r.vel_n_m_s, r.vel_e_m_s, r.vel_d_m_s)
        values = {"time_us": r.time_us, "lat": r.lat_deg, "lon": r.lon_deg, "alt": r.alt_m, "vel_n": r.vel_n_m_s,
                  "vel_e": r.vel_e_m_s, "vel_d": r.vel_d_m_s, "heading": _NAN, "fix_type": r.fix_type,
                  "satellites": r.satellites}  # fmt: skip
        if all(map(math.isfinite, velocity)):
            self.pipeline.gps_stage(values)
        else:  # no aiding from an incomplete velocity: the row only
            self.pipeline.tables["gps"].append([self.pipeline._time_s, *list(values.values())[1:]])

    def _vehicle_status(self, t_host_ns: int, r: rec.VehicleStatus) -> None:
        vehicle = self._from_vehicle(r)
        self._record_row(t_host_ns, r)  # another sender's in a table of its own
        if not vehicle:
            return
        self.pipeline.bank.armed = r.armed  # the rest calibrator refuses while armed
        if (r.mode, r.armed) != self._status:
            self._status = (r.mode, r.armed)
            self.pipeline.events.append(status_event(r.mode, r.armed, **self._times(t_host_ns)))

    def _text(self, t_host_ns: int, r: rec.StatusText) -> None:
        """The vehicle's texts (another sender's, such as a test driver's chatter, stay out of the events)."""
        if self._from_vehicle(r):
            for severity, text in self._texts.add(r):
                self.pipeline.events.append(message_event(text, severity, "STATUSTEXT", **self._times(t_host_ns)))

    def _parameter(self, t_host_ns: int, r: rec.ParamValue) -> None:
        if self._from_vehicle(r):
            change = parameter_change(self.pipeline.parameters, r.name, r.value, **self._times(t_host_ns))
            if change is not None:
                self.pipeline.events.append(change)

    def _times(self, t_host_ns: int) -> dict:
        """An event's times: the host's, and the session time reached (the plots' axis) once there is one."""
        t_s = self.pipeline._time_s
        return {"t_host_ns": t_host_ns, "session_time_s": t_s} if math.isfinite(t_s) else {"t_host_ns": t_host_ns}

    def _record_row(self, t_host_ns: int, r) -> None:
        """A mapped record's row: the vehicle's table, another sender's own (any radio's: ``radio_status``)."""
        name, label, fields, units = rec.table_fields(type(r))
        name, vehicle = (name, True) if isinstance(r, rec.LinkHealth) else self._table_of(r, name)
        values = tuple(float(getattr(r, a)) for a in rec.RECORD_TABLES[type(r)][2])
        self._table_row(t_host_ns, name, label, fields, units, values, vehicle)

    def _generic(self, t_host_ns: int, r: rec.GenericMessage) -> None:
        name, vehicle = self._table_of(r, r.msg_type)
        self._table_row(t_host_ns, name, f"MAVLink {r.msg_type} from system {r.system}, component {r.component}",
                        list(r.fields), r.units, tuple(r.fields.values()), vehicle)

    def _table_of(self, r, name: str) -> tuple[str, bool]:
        """The table of ``r``'s message ``name`` and whether it is the vehicle's: the vehicle's own (also before
        one is chosen, from the picked system if any), else ``<name>_<system>_<component>``."""
        v = self.vehicle
        vehicle = v.sent(r) or (v.sender is None and v.picked in (None, r.system))
        return (name if vehicle else f"{name}_{r.system}_{r.component}").lower(), vehicle

    def _table_row(self, t_host_ns: int, name: str, label: str, fields: list, units: dict, values: tuple, vehicle: bool = True) -> None:
        """A row of table ``name``, catalogued on its first row (copy on write: readers in other threads
        keep a consistent catalogue and table dictionary); another sender's new table only within the bound."""
        p = self.pipeline
        table = p.tables.get(name)
        if table is None:
            if not vehicle and not self._other_table_fits(t_host_ns, name, len(fields)):
                self.unplaced_messages += 1
                return
            info = message_table(name, label, fields, units)
            p.catalogue = Catalogue({**p.catalogue.tables, name: info})
            table = p.new_table(info.column_names)
            p.tables = {**p.tables, name: table}
        table.append((p._time_s, *values))

    def _other_table_fits(self, t_host_ns: int, name: str, columns: int) -> bool:
        """Whether another sender's new table ``name`` of ``columns`` fits the bound (then it counts); a
        warning the first time one does not."""
        if len(self.other_tables) < OTHER_TABLES_MAX and self.other_columns + columns <= OTHER_COLUMNS_MAX:
            self.other_tables.add(name)
            self.other_columns += columns
            return True
        if not self.unplaced_messages:
            self.pipeline._warn(t_host_ns, f"{len(self.other_tables)} tables ({self.other_columns} columns) of senders other "
                                "than the vehicle: the most a session keeps; their further message types are counted, not kept")
        return False


def other_vehicle_event(t_host_ns: int, record, vehicle: Vehicle) -> dict:
    """The event of the first message from another system id than the vehicle's."""
    system, component = record.system, record.component
    chosen = f"system {vehicle.sender[0]}" if vehicle.sender else f"the picked system {vehicle.picked}"
    return {"t_host_ns": t_host_ns, "kind": "other_vehicle", "system": system, "component": component,
            "message": f"MAVLink system {system} (component {component}) is also on this link (another vehicle, a "
                       f"radio, a ground station?): listed, never used as the vehicle, which is {chosen} "
                       f"(?system={system} on the mavlink: spec picks {system} instead)"}

