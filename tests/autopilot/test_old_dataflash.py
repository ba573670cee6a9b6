"""A DataFlash log in the layout before 2015 (``TimeMS`` stamps; ``PARM``, ``MSG``, ``MODE`` and ``EV`` with
no time of their own) has its parameters, messages and modes as a new log does, each at the boot time
of the stamped record before it; pymavlink's DFReader, reading the same file, is the oracle."""

import struct

import numpy as np
import pytest
from pymavlink import DFReader, mavutil

from groundstation.session_makers.load import load_session

from mavlink_helpers import dataflash_record

# ArduPlane 3.0 (2014), libraries/DataFlash/LogStructure.h and ArduPlane/Log.pde: id, format, labels
OLD_FORMATS = {
    "PARM": (129, "Nf", "Name,Value"),
    "MSG": (133, "Z", "Message"),
    "MODE": (134, "BB", "Mode,ModeNum"),
    "EV": (135, "B", "Id"),
    "IMU": (131, "Iffffff", "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
    "IMU2": (136, "Iffffff", "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
    "ATT": (132, "IccccCC", "TimeMS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw"),
}
STRUCT = {"I": "I", "f": "f", "B": "B", "c": "h", "C": "H", "N": "16s", "Z": "64s"}
PARAMETERS = {"RLL2SRV_P": 0.4, "PTCH2SRV_P": 0.6, "THR_MAX": 75.0}
MODES = ((2.0, 0), (6.0, 5), (12.0, 10))  # (s from boot, ArduPlane mode number): MANUAL, FBWA, AUTO
ARMED_S = 4.0


def record(name: str, *values) -> bytes:
    msg_id, fmt, _ = OLD_FORMATS[name]
    return dataflash_record(msg_id, struct.pack("<" + "".join(STRUCT[c] for c in fmt), *values))


@pytest.fixture(scope="module")
def old_log(tmp_path_factory):
    out = bytearray()
    for name, (msg_id, fmt, labels) in OLD_FORMATS.items():
        length = 3 + struct.calcsize("<" + "".join(STRUCT[c] for c in fmt))
        out += dataflash_record(128, struct.pack("<BB4s16s64s", msg_id, length, name.encode(), fmt.encode(), labels.encode()))
    out += record("MSG", b"ArduPlane V3.0.3 (1234abcd)")
    for name, value in PARAMETERS.items():
        out += record("PARM", name.encode(), value)
    rng = np.random.default_rng(4)
    said = {**{s: ("MODE", m, m) for s, m in MODES}, ARMED_S: ("EV", 10)}
    for k in range(150):  # 15 s at 10 Hz
        t_s = 1.0 + k / 10
        out += record("IMU", int(t_s * 1000), *np.zeros(6))  # a first IMU that reads nothing: the second is the IMU
        out += record("IMU2", int(t_s * 1000), *rng.normal(0, 0.01, 3), *(rng.normal(0, 0.05, 3) + (0, 0, -9.80665)))
        out += record("ATT", int(t_s * 1000), 0, 0, 0, 0, 0, 0)
        for at_s in [s for s in said if t_s <= s < t_s + 0.1]:
            out += record(*said[at_s])
            if said[at_s][0] == "MODE":
                out += record("MSG", f"mode {said[at_s][2]}".encode())
    out += record("PARM", b"THR_MAX", 80.0)  # changed in flight
    path = tmp_path_factory.mktemp("old") / "plane_2014.bin"
    path.write_bytes(bytes(out))
    return path


def oracle(path) -> dict:
    """In file order, as DFReader reads them: each PARM, MSG, MODE, EV with the TimeMS of the stamped record before it."""
    reader = DFReader.DFReader_binary(str(path), zero_time_base=False)
    last_ms, first_imu_ms, out = None, None, []
    while (msg := reader.recv_match(type=["IMU", "ATT", "PARM", "MSG", "MODE", "EV"])) is not None:
        if msg.get_type() in ("IMU", "ATT"):
            last_ms = msg.TimeMS
            first_imu_ms = first_imu_ms if first_imu_ms is not None or msg.get_type() != "IMU" else msg.TimeMS
        else:
            out.append((msg.get_type(), msg.to_dict(), last_ms))
    return {"records": out, "t0_ms": first_imu_ms}


def test_parameters_messages_and_modes_of_a_timems_log(old_log):
    data = load_session(old_log, ["ahf"])
    truth = oracle(old_log)
    parameters = {}
    for kind, fields, _ in truth["records"]:
        if kind == "PARM":
            parameters[fields["Name"]] = fields["Value"]
    assert data.parameters == pytest.approx(parameters) and data.parameters["THR_MAX"] == 80.0
    texts = [fields["Message"] for kind, fields, _ in truth["records"] if kind == "MSG"]
    assert [e["message"] for e in data.events if e["kind"] == "message" and e["source"] == "MSG"] == texts
    plane_modes = mavutil.mode_mapping_bynumber(mavutil.mavlink.MAV_TYPE_FIXED_WING)
    timed = [(plane_modes[fields["ModeNum"]], (ms - truth["t0_ms"]) / 1000) for kind, fields, ms in truth["records"] if kind == "MODE"]
    status = [e for e in data.events if e["kind"] == "vehicle_status"]
    changes = [(e["mode"], e["t_s"]) for i, e in enumerate(status) if i == 0 or e["mode"] != status[i - 1]["mode"]]
    assert [m for m, _ in changes] == [m for m, _ in timed] == ["MANUAL", "FBWA", "AUTO"]
    np.testing.assert_allclose([t for _, t in changes], [t for _, t in timed], atol=1e-9)
    (armed,) = [ms for kind, fields, ms in truth["records"] if kind == "EV" and fields["Id"] == 10]
    assert [e["t_s"] for e in status if e["armed"] and not status[status.index(e) - 1]["armed"]] == [pytest.approx((armed - truth["t0_ms"]) / 1000)]
    change = [e for e in data.events if e["kind"] == "parameter"]
    assert [(e["name"], e["previous"], e["value"]) for e in change] == [("THR_MAX", 75.0, 80.0)]


def test_every_stamped_type_of_a_timems_log_is_a_table(old_log):
    data = load_session(old_log, ["ahf"])
    reader = DFReader.DFReader_binary(str(old_log), zero_time_base=False)
    att_ms, imu_ms = [], []
    while (msg := reader.recv_match(type=["ATT", "IMU"])) is not None:
        (att_ms if msg.get_type() == "ATT" else imu_ms).append(msg.TimeMS)
    np.testing.assert_allclose(data.tables["att"]["time_s"], (np.array(att_ms) - imu_ms[0]) / 1000, atol=1e-9)
    assert len(data.tables["imu_log"]["time_s"]) == len(imu_ms)


def test_a_timems_logs_second_imu_is_taken_when_the_first_reads_nothing(old_log):
    data = load_session(old_log, ["ahf"])
    reader = DFReader.DFReader_binary(str(old_log), zero_time_base=False)
    acc = []
    while (msg := reader.recv_match(type="IMU2")) is not None:
        acc.append((msg.AccX, msg.AccY, msg.AccZ))
    np.testing.assert_allclose(data.tables["imu"]["acc_z_g"], np.array(acc)[:, 2] / 9.80665)
    assert "IMU2" in data.metadata["imu_choice"] and any("not IMU[0]" in w for w in data.warnings), data.warnings
