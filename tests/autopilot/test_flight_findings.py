"""The report's findings match the flight: what the autopilot logged about an emergency stop, a crash, its
failsafes, power, GPS, EKF, compass and clipping is each a finding with its time, severity and evidence,
the times checked against pymavlink's DFReader; a crash is the first finding of a crash log (one written
here); a block-copied log's short tail is a note, not damage."""

import numpy as np
import pytest
from pymavlink import DFReader

from groundstation.export.report_findings import findings
from groundstation.session_makers.load import load_session
from groundstation.units import STANDARD_GRAVITY_M_S2

from mavlink_helpers import flightlog, write_dataflash

COPTER = "arducopter_cubeorange_2023-07-06_10-12-18.bin"
BOOT_US = 50_000_000
IMU_HZ = 25.0


def dfreader_times_s(path, msg_type, keep=lambda m: True) -> list[float]:
    """Session times (s from the first IMU sample) of ``msg_type`` records ``keep`` accepts, as pymavlink reads them."""
    reader = DFReader.DFReader_binary(str(path), zero_time_base=False)
    first_imu, out = None, []
    while (msg := reader.recv_match(type=["IMU", msg_type])) is not None:
        if msg.get_type() == "IMU" and first_imu is None:
            first_imu = msg.TimeUS
        if msg.get_type() == msg_type and keep(msg):
            out.append(msg.TimeUS)
    return [(t - first_imu) / 1e6 for t in out]


@pytest.fixture(scope="module")
def copter_findings():
    data = load_session(flightlog(COPTER), filters=())
    return data, findings(data, None)


def test_the_shared_copters_emergency_stop_is_a_finding_at_its_time(copter_findings):
    data, found = copter_findings
    stops = [f for f in found if f.kind == "emergency_stop"]
    (expected,) = dfreader_times_s(flightlog(COPTER), "EV", lambda m: m.Id == 54)  # MOTORS_EMERGENCY_STOPPED
    assert len(stops) == 1 and stops[0].severity == "high", found
    assert stops[0].t_s == pytest.approx(expected, abs=1e-3) and expected == pytest.approx(78.1, abs=0.05)
    assert "armed" in stops[0].title and "RTL" in stops[0].title and "MotorEStop" in stops[0].detail


def test_a_block_copied_logs_short_tail_is_a_note_not_damage(copter_findings):
    data, found = copter_findings
    assert flightlog(COPTER).stat().st_size % 512 == 0  # copied off the card in whole blocks
    assert not data.damage and not [f for f in found if f.kind == "damage"], found
    assert "35 bytes" in data.metadata["notes"]


def test_a_log_cut_anywhere_else_is_still_damaged(tmp_path):
    cut = tmp_path / "cut.bin"
    cut.write_bytes(flightlog(COPTER).read_bytes()[:1_000_003])  # inside a record, off any block
    data = load_session(cut, filters=())
    assert any("ends inside a record" in d for d in data.damage), data.damage


CRASH_S, RADIO_FS_S, GLITCH_S, BROWNOUT_S, CLIP_S, EKF_S, MAG_S = 30.0, 12.0, 15.0, 18.0, 21.0, 24.0, 26.0


@pytest.fixture(scope="module")
def crash_bin(tmp_path_factory):
    """A DataFlash log of a copter that loses control and crashes at ``CRASH_S`` (ArduCopter's crash check:
    ERR CRASH_CHECK 1, "Crash: Disarming", the attitude far from its demand), after a radio failsafe, a GPS
    glitch, a brownout, clipping, an EKF variance and a compass disturbance, each at its own time."""
    rng = np.random.default_rng(7)
    t = np.arange(int(40 * IMU_HZ)) / IMU_HZ
    us = lambda s: int(BOOT_US + s * 1e6)  # noqa: E731
    imu = [(us(s), 0, *rng.normal(0, 0.01, 3), *(rng.normal(0, 0.05, 3) + (0, 0, -STANDARD_GRAVITY_M_S2))) for s in t]
    roll = np.where(t < CRASH_S - 2.5, 0.0, np.minimum((t - (CRASH_S - 2.5)) * 60.0, 120.0))  # rolls over from 27.5 s
    att = [(us(s), 0.0, r, 0.0, 0.0, 0.0, 0.0) for s, r in zip(t[::2], roll[::2])]
    err = [(us(RADIO_FS_S), 5, 1), (us(RADIO_FS_S + 3), 5, 0), (us(GLITCH_S), 11, 2), (us(GLITCH_S + 1), 11, 0),
           (us(CRASH_S), 12, 1)]
    msg = [(us(CRASH_S) + 5, b"Crash: Disarming"), (us(GLITCH_S) + 5, b"GPS Glitch")]
    powr = [(us(s), 4.2 if abs(s - BROWNOUT_S) < 0.3 else 5.1, 3 if abs(s - BROWNOUT_S) < 0.3 else 3) for s in np.arange(0, 40, 0.1)]
    vibe = [(us(s), 0, 3.0, 3.0, 5.0, 0 if s < CLIP_S else 40) for s in np.arange(0, 40, 0.1)]
    xkf4 = [(us(s), 0, 1.2 if abs(s - EKF_S) < 0.5 else 0.1, 0.1, 0.1, 0.1) for s in np.arange(0, 40, 0.1)]
    mag = [(us(s), 0, 200.0, 0.0, 400.0 * (3.0 if abs(s - MAG_S) < 0.5 else 1.0)) for s in np.arange(0, 40, 0.1)]
    path = tmp_path_factory.mktemp("crash") / "crash.bin"
    write_dataflash(path, {
        "IMU": ("QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ", imu),
        "ATT": ("Qffffff", "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw", att),
        "MODE": ("QBB", "TimeUS,Mode,ModeNum", [(us(0.5), 5, 5)]),
        "EV": ("QB", "TimeUS,Id", [(us(1.0), 10), (us(CRASH_S) + 10, 11)]),
        "ERR": ("QBB", "TimeUS,Subsys,ECode", err),
        "MSG": ("QZ", "TimeUS,Message", msg),
        "POWR": ("QfH", "TimeUS,Vcc,Flags", powr),
        "VIBE": ("QBfffI", "TimeUS,IMU,VibeX,VibeY,VibeZ,Clip", vibe),
        "XKF4": ("QBffff", "TimeUS,C,SV,SP,SH,SM", xkf4),
        "MAG": ("QBfff", "TimeUS,I,MagX,MagY,MagZ", mag),
    })  # fmt: skip
    return path


@pytest.fixture(scope="module")
def crash_findings(crash_bin):
    data = load_session(crash_bin, filters=())
    return findings(data, None)


def test_a_crash_is_the_first_finding_of_a_crash_log_at_its_time(crash_bin, crash_findings):
    first = crash_findings[0]
    (logged,) = dfreader_times_s(crash_bin, "ERR", lambda m: m.Subsys == 12)
    assert first.kind == "crash" and first.severity == "critical", crash_findings
    assert first.t_s == pytest.approx(logged, abs=1e-3)
    assert "Crash: Disarming" in first.detail and "CRASH_CHECK" in first.detail


@pytest.mark.parametrize("kind, msg_type, keep", [
    ("failsafe", "ERR", lambda m: m.Subsys == 5 and m.ECode == 1),
    ("gps_glitch", "ERR", lambda m: m.Subsys == 11 and m.ECode == 2),
    ("brownout", "POWR", lambda m: m.Vcc < 4.5),
    ("clipping", "VIBE", lambda m: m.Clip > 0),
    ("ekf_variance", "XKF4", lambda m: m.SV > 0.8),
    ("compass", "MAG", lambda m: m.MagZ > 600),
])  # fmt: skip
def test_each_kind_of_trouble_is_a_finding_at_its_first_logged_time(crash_bin, crash_findings, kind, msg_type, keep):
    found = [f for f in crash_findings if f.kind == kind]
    first_logged = dfreader_times_s(crash_bin, msg_type, keep)[0]
    assert found, [(f.kind, f.title) for f in crash_findings]
    assert found[0].t_s == pytest.approx(first_logged, abs=1e-3), (found[0], first_logged)
    assert found[0].severity in ("high", "medium") and found[0].detail


def test_the_crash_log_has_no_emergency_stop_and_the_copter_no_crash(crash_findings, copter_findings):
    assert not [f for f in crash_findings if f.kind == "emergency_stop"]
    assert not [f for f in copter_findings[1] if f.kind in ("crash", "failsafe", "brownout", "gps_glitch")], copter_findings[1]


@pytest.mark.parametrize("text, what", [
    ("MotorEStop HIGH", "motors emergency-stopped"), ("MotorEStop LOW", None),  # ArduPilot's RC switch engaged / released
    ("MOTORS_EMERGENCY_STOPPED", "motors emergency-stopped"), ("MOTORS_EMERGENCY_STOP_CLEARED", None),
    ("CRASH_CHECK: error 1", "crash"), ("CRASH_CHECK: resolved", None), ("Crash: Disarming", "crash"),
    ("FAILSAFE_RADIO: error 1", "radio failsafe"), ("FAILSAFE_RADIO: resolved", None),
    ("[commander] Dangerous battery level!, please land!", "battery failsafe"), ("GPS Glitch", "GPS glitch"),
])  # fmt: skip
def test_what_the_autopilot_says_is_evidence_only_of_trouble_begun(text, what):
    from groundstation.export.report_findings import incident_of

    entry = incident_of({"kind": "message", "message": text})
    assert (entry[2] if entry else None) == what


def test_a_mavlink_link_gives_the_power_ekf_and_clipping_findings_a_log_does(tmp_path):
    """POWER_STATUS (Vcc in mV, MAV_POWER_STATUS flags, the bits of POWR's), EKF_STATUS_REPORT and VIBRATION
    on a link: a dip of the board's supply, a peripheral overcurrent, a velocity variance over 0.8 and the
    clip counter rising, each at the session time of the IMU sample before it (pymavlink's reading)."""
    import struct

    from pymavlink import mavutil

    from mavlink_helpers import Sender, ardupilot_heartbeat

    autopilot, rng, out = Sender(), np.random.default_rng(3), bytearray()
    for k in range(100):  # 10 s at 10 Hz
        t_us = BOOT_US + k * 100_000
        packets = [ardupilot_heartbeat(autopilot)] if k % 10 == 0 else []
        packets.append(autopilot.raw_imu(t_us, *np.rint(rng.normal(0, 5, 2)).astype(int), -1000, 0, 0, 0, 200, 0, 400, 0, 2500))
        if k % 5 == 0:
            packets.append(autopilot.power_status(4200 if k == 60 else 5100, 0, 3 | (8 if k >= 80 else 0)))
            packets.append(autopilot.ekf_status_report(0, 0.9 if k == 40 else 0.1, 0.1, 0.1, 0.1, 0.0))
            packets.append(autopilot.vibration(t_us, 5.0, 5.0, 5.0, 0 if k < 70 else 12, 0, 0))
        out += b"".join(struct.pack(">Q", 1_700_000_000_000_000 + t_us) + p for p in packets)
    path = tmp_path / "power.tlog"
    path.write_bytes(bytes(out))
    log, imu_us, expected = mavutil.mavlink_connection(str(path)), [], {}
    while (msg := log.recv_match(type=["RAW_IMU", "POWER_STATUS", "EKF_STATUS_REPORT", "VIBRATION"])) is not None:
        kind = msg.get_type()
        happened = {"POWER_STATUS": {"brownout": msg.Vcc < 4500 if kind == "POWER_STATUS" else False,
                                     "power": bool(msg.flags & 8) if kind == "POWER_STATUS" else False},
                    "EKF_STATUS_REPORT": {"ekf_variance": kind == "EKF_STATUS_REPORT" and msg.velocity_variance > 0.8},
                    "VIBRATION": {"clipping": kind == "VIBRATION" and msg.clipping_0 > 0}}.get(kind, {})
        if kind == "RAW_IMU":
            imu_us.append(msg.time_usec)
        for what, now in happened.items():
            if now and what not in expected:
                expected[what] = ((imu_us[-1] - imu_us[0]) / 1e6, kind)
    found = {f.kind: f for f in findings(load_session(path, ["ahf"]), None)}
    assert set(expected) == {"brownout", "power", "ekf_variance", "clipping"}
    for what, (t_s, kind) in expected.items():
        assert found[what].t_s == pytest.approx(t_s, abs=1e-3) and kind in found[what].detail, found
    assert found["brownout"].severity == "high" and "4.20 V" in found["brownout"].detail
