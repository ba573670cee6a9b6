"""What an autopilot says and how it is set: its texts as ``message`` events, its parameters.

Texts, each one ``message`` event (``message_event``: ``message``, ``severity`` by name or None,
``source``), live and logged alike:

- MAVLink ``STATUSTEXT`` (severity ``MAV_SEVERITY``). MAVLink 2 splits a text longer than 50 characters
  into chunks sharing a non-zero ``id``, numbered by ``chunk_seq``; a chunk shorter than 50 characters
  (its text ended in a NUL) is the last (``StatusTexts``). A text whose last chunk never came is lost
  with it, as on any ground station.
- DataFlash ``MSG`` (no severity), ``ERR`` (subsystem and code: ArduPilot's ``LogErrorSubsystem``,
  severity ERROR, or INFO for code 0, "resolved"), ``EV`` (ArduPilot's ``LogEvent``; arming is also a
  ``vehicle_status`` event, ``modes``).
- ULog logged messages (their ``log_level`` is a syslog level, as ``MAV_SEVERITY`` is).

Parameters: name -> value, as last set (``SessionData.parameters``); a value that changes after the
first one known is a ``parameter`` event (``parameter_change``). MAVLink ``PARAM_VALUE`` carries every
value in a float: ArduPilot converts integers to it, PX4 copies an integer's bytes into it
(``mapping.param_value``).
"""

from __future__ import annotations

from groundstation.autopilot.modes import PX4_ARMED_STATES, ardupilot_mode, px4_nav_state_mode, status_event
from groundstation.autopilot.records import StatusText

MESSAGE_KIND, PARAMETER_KIND = "message", "parameter"
SEVERITIES = ("EMERGENCY", "ALERT", "CRITICAL", "ERROR", "WARNING", "NOTICE", "INFO", "DEBUG")  # MAV_SEVERITY, syslog
ALARM_SEVERITIES = frozenset(SEVERITIES[:4])  # what the event console shows in red
ERROR, INFO = 3, 6  # MAV_SEVERITY
DATAFLASH_SAID = ("MSG", "ERR", "EV", "MODE", "ARM", "PARM")  # the DataFlash messages ``dataflash_said`` reads
STATUSTEXT_CHARS = 50
# ArduPilot's libraries/AP_Logger/AP_Logger.h: LogEvent (DataFlash EV.Id) and LogErrorSubsystem (ERR.Subsys)
EV_ARMED, EV_DISARMED = 10, 11
LOG_EVENTS = {
    10: "ARMED", 11: "DISARMED", 15: "AUTO_ARMED", 17: "LAND_COMPLETE_MAYBE", 18: "LAND_COMPLETE", 19: "LOST_GPS",
    21: "FLIP_START", 22: "FLIP_END", 25: "SET_HOME", 26: "SET_SIMPLE_ON", 27: "SET_SIMPLE_OFF", 28: "NOT_LANDED",
    29: "SET_SUPERSIMPLE_ON", 30: "AUTOTUNE_INITIALISED", 31: "AUTOTUNE_OFF", 32: "AUTOTUNE_RESTART",
    33: "AUTOTUNE_SUCCESS", 34: "AUTOTUNE_FAILED", 35: "AUTOTUNE_REACHED_LIMIT", 36: "AUTOTUNE_PILOT_TESTING",
    37: "AUTOTUNE_SAVEDGAINS", 38: "SAVE_TRIM", 39: "SAVEWP_ADD_WP", 41: "FENCE_ENABLE", 42: "FENCE_DISABLE",
    43: "ACRO_TRAINER_OFF", 44: "ACRO_TRAINER_LEVELING", 45: "ACRO_TRAINER_LIMITED", 46: "GRIPPER_GRAB",
    47: "GRIPPER_RELEASE", 49: "PARACHUTE_DISABLED", 50: "PARACHUTE_ENABLED", 51: "PARACHUTE_RELEASED",
    52: "LANDING_GEAR_DEPLOYED", 53: "LANDING_GEAR_RETRACTED", 54: "MOTORS_EMERGENCY_STOPPED",
    55: "MOTORS_EMERGENCY_STOP_CLEARED", 56: "MOTORS_INTERLOCK_DISABLED", 57: "MOTORS_INTERLOCK_ENABLED",
    58: "ROTOR_RUNUP_COMPLETE", 59: "ROTOR_SPEED_BELOW_CRITICAL", 60: "EKF_ALT_RESET", 61: "LAND_CANCELLED_BY_PILOT",
    62: "EKF_YAW_RESET", 63: "AVOIDANCE_ADSB_ENABLE", 64: "AVOIDANCE_ADSB_DISABLE", 65: "AVOIDANCE_PROXIMITY_ENABLE",
    66: "AVOIDANCE_PROXIMITY_DISABLE", 67: "GPS_PRIMARY_CHANGED", 71: "ZIGZAG_STORE_A", 72: "ZIGZAG_STORE_B",
    73: "LAND_REPO_ACTIVE", 74: "STANDBY_ENABLE", 75: "STANDBY_DISABLE", 163: "SURFACED", 164: "NOT_SURFACED",
    165: "BOTTOMED", 166: "NOT_BOTTOMED",
}  # fmt: skip
ERROR_SUBSYSTEMS = {
    1: "MAIN", 2: "RADIO", 3: "COMPASS", 4: "OPTFLOW", 5: "FAILSAFE_RADIO", 6: "FAILSAFE_BATT", 7: "FAILSAFE_GPS",
    8: "FAILSAFE_GCS", 9: "FAILSAFE_FENCE", 10: "FLIGHT_MODE", 11: "GPS", 12: "CRASH_CHECK", 13: "FLIP", 14: "AUTOTUNE",
    15: "PARACHUTES", 16: "EKFCHECK", 17: "FAILSAFE_EKFINAV", 18: "BARO", 19: "CPU", 20: "FAILSAFE_ADSB", 21: "TERRAIN",
    22: "NAVIGATION", 23: "FAILSAFE_TERRAIN", 24: "EKF_PRIMARY", 25: "THRUST_LOSS_CHECK", 26: "FAILSAFE_SENSORS",
    27: "FAILSAFE_LEAK", 28: "PILOT_INPUT", 29: "FAILSAFE_VIBE",
}  # fmt: skip


def severity_name(level: int | None) -> str | None:
    """A MAV_SEVERITY or syslog level by name; None when the source gives none (or an out-of-range one)."""
    return SEVERITIES[level] if level is not None and 0 <= level < len(SEVERITIES) else None


def message_event(text: str, severity: int | None, source: str, **times) -> dict:
    """One text the autopilot said. ``times``: a log's ``t_s``/``session_time_s``, the link's ``t_host_ns``."""
    return {**times, "kind": MESSAGE_KIND, "message": text, "severity": severity_name(severity), "source": source}


def parameter_change(parameters: dict[str, float], name: str, value: float, **times) -> dict | None:
    """Sets ``parameters[name]``; the ``parameter`` event when it changes a value already known, else None."""
    previous = parameters.get(name)
    parameters[name] = value
    if previous is None or previous == value or (previous != previous and value != value):  # NaN == NaN here
        return None
    return {**times, "kind": PARAMETER_KIND, "name": name, "value": value, "previous": previous}


class StatusTexts:
    """STATUSTEXT chunks of each sender joined into whole texts (the module's rule)."""

    def __init__(self):
        self._pending: dict[tuple[int, int], tuple[int, int, list[str]]] = {}  # sender -> (id, severity, chunks)

    def add(self, r: StatusText) -> list[tuple[int, str]]:
        """The (severity, text) completed by ``r``: none, its own, or also an earlier text of the sender
        whose last chunk never came (said as far as it got)."""
        sender = (r.system, r.component)
        out = []
        pending = self._pending.get(sender)
        if pending is not None and (r.id == 0 or r.id != pending[0]):
            del self._pending[sender]
            out.append((pending[1], "".join(pending[2])))
            pending = None
        if r.id == 0:
            return out + [(r.severity, r.text)]
        if pending is None:
            pending = self._pending[sender] = (r.id, r.severity, [])
        pending[2].append(r.text)
        if len(r.text) < STATUSTEXT_CHARS:
            del self._pending[sender]
            out.append((pending[1], "".join(pending[2])))
        return out


Said = tuple[list[tuple[int, dict]], dict[str, float]]  # (time µs, event without times) in time order, parameters


def dataflash_said(records, vehicle_type: int) -> Said:
    """The events and parameters of a DataFlash log's ``DATAFLASH_SAID`` records ((boot time µs, DFReader
    message), in log order); ``vehicle_type``: the MAV_TYPE DFReader read from the firmware's message.
    Arming is known from EV ARMED/DISARMED and ARM; a log whose first word on it is a disarm began armed."""
    arming = [_armed(r) for _, r in records if _armed(r) is not None]
    armed = (not arming[0]) if arming else None
    mode, events, parameters = None, [], {}

    def status(t_us: int, new_mode: str | None, new_armed: bool | None) -> None:
        nonlocal mode, armed
        if new_mode is not None and (new_mode, new_armed) != (mode, armed):
            events.append((t_us, status_event(new_mode, new_armed)))
        mode, armed = new_mode, new_armed

    for t_us, r in records:
        kind = r.get_type()
        if kind == "PARM":
            change = parameter_change(parameters, r.Name, float(r.Value))
            events += [(t_us, change)] if change is not None else []
        elif kind == "MSG":
            events.append((t_us, message_event(r.Message, None, "MSG")))
        elif kind == "ERR":
            what = ERROR_SUBSYSTEMS.get(r.Subsys, f"subsystem {r.Subsys}")
            text = f"{what}: resolved" if r.ECode == 0 else f"{what}: error {r.ECode}"
            events.append((t_us, message_event(text, INFO if r.ECode == 0 else ERROR, "ERR")))
        elif kind == "EV":
            events.append((t_us, message_event(LOG_EVENTS.get(r.Id, f"event {r.Id}"), None, "EV")))
        if kind == "MODE":
            status(t_us, ardupilot_mode(vehicle_type, getattr(r, "ModeNum", r.Mode)), armed)
        elif _armed(r) is not None:
            status(t_us, mode, _armed(r))
    return sorted(events, key=lambda pair: pair[0]), parameters


def _armed(record) -> bool | None:
    kind = record.get_type()
    if kind == "ARM":
        return bool(record.ArmState)
    if kind == "EV" and record.Id in (EV_ARMED, EV_DISARMED):
        return record.Id == EV_ARMED
    return None


def ulog_said(ulog, vehicle_status: dict | None) -> Said:
    """The events and parameters of a ULog (pyulog's ``ULog``): its logged messages, its initial parameters
    and their changes, and ``vehicle_status``'s (first instance's columns) navigation and arming states."""
    events = [(int(m.timestamp), message_event(m.message, m.log_level - ord("0"), "ULog")) for m in ulog.logged_messages]
    parameters = {name: float(value) for name, value in ulog.initial_parameters.items()}
    for t_us, name, value in ulog.changed_parameters:
        change = parameter_change(parameters, name, float(value))
        events += [(int(t_us), change)] if change is not None else []
    if vehicle_status is not None:
        last = None
        for t_us, nav_state, arming_state in zip(vehicle_status["timestamp"], vehicle_status["nav_state"], vehicle_status["arming_state"]):
            state = (px4_nav_state_mode(nav_state), int(arming_state) in PX4_ARMED_STATES)
            if state != last:
                events.append((int(t_us), status_event(*state)))
                last = state
    return sorted(events, key=lambda pair: pair[0]), parameters
