"""Old and damaged flight logs through every command: what they lost is said (and carried in
``--json`` as "warnings"), the libraries' own chatter is counted, never shown.

The damaged logs are the shared real ones (/work/shared/datasets/flightlogs) damaged here: one 4 KB
block overwritten with random bytes, or the file cut at 55 %. The old log is a DataFlash file written
record by record in the layout ArduPlane used until 2015 (``TimeMS``, centidegree ``ATT``, ``GPS``
with its boot time in ``T``), read back by pymavlink as the oracle.
"""

import json
import struct

import numpy as np
import pytest
from pymavlink import DFReader

from groundstation import quaternion
from groundstation.session_makers.flight_log_session import read_log
from groundstation.cli import main
from groundstation.sim.profiles import make_profile

from mavlink_helpers import dataflash_record, flightlog


BLOCK = 4096
CUT = 0.55
# DataFlash format characters and the struct codes they are stored as (ArduPilot's LogStructure.h).
DF_STRUCT = {"I": "I", "f": "f", "B": "B", "H": "H", "c": "h", "C": "H", "e": "i", "E": "I", "L": "i"}
OLD_FORMATS = {  # ArduPlane 3.0 (2014)
    "IMU": (131, "Iffffff", "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
    "ATT": (132, "IccccCC", "TimeMS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw"),
    "GPS": (130, "BIHBcLLeeEefI", "Status,TimeMS,Week,NSats,HDop,Lat,Lng,RelAlt,Alt,Spd,GCrs,VZ,T"),
}


def df_pack(fmt: str, row) -> bytes:
    return struct.pack("<" + "".join(DF_STRUCT[c] for c in fmt), *row)


def write_old_dataflash(path, rows: list[tuple[str, tuple]]) -> None:
    out = bytearray()
    for name, (msg_id, fmt, labels) in OLD_FORMATS.items():
        length = 3 + struct.calcsize("<" + "".join(DF_STRUCT[c] for c in fmt))
        out += dataflash_record(128, struct.pack("<BB4s16s64s", msg_id, length, name.encode(), fmt.encode(), labels.encode()))
    for name, row in rows:
        msg_id, fmt, _ = OLD_FORMATS[name]
        out += dataflash_record(msg_id, df_pack(fmt, row))
    path.write_bytes(bytes(out))


@pytest.fixture(scope="module")
def old_plane_log(tmp_path_factory):
    """20 s of the simulator's flight logged as a 2014 ArduPlane did: IMU at 10 Hz (a reduced logging
    rate: too slow for host filtering), ATT at 10 Hz in centidegrees, GPS at 5 Hz."""
    profile = make_profile("flight", 20.0, seed=3)
    t_s = np.arange(200) / 10.0
    truth = profile.truth(t_s)
    boot_ms = (60_000 + t_s * 1000).astype(int)
    yaw, pitch, roll = np.degrees(quaternion.to_euler_zyx(truth.q_body_to_ned)).T
    rows = []
    for k, ms in enumerate(boot_ms):
        rows.append(("IMU", (int(ms), *truth.rate_body_rad_s[k], *truth.specific_force_body_m_s2()[k])))
        rows.append(("ATT", (int(ms), 0, round(roll[k] * 100), 0, round(pitch[k] * 100), 0, round(yaw[k] % 360 * 100))))
        if k % 2 == 0:
            rows.append(("GPS", (3, 300_000_000 + int(ms), 1800, 9, 120, 525_000_000, 134_000_000, 1500, 4000, 1200, 9000, -0.5, int(ms))))
    path = tmp_path_factory.mktemp("old") / "arduplane_2014.bin"
    write_old_dataflash(path, rows)
    return path, boot_ms


def test_a_dataflash_log_stamped_in_timems_opens_on_its_boot_clock(old_plane_log):
    path, boot_ms = old_plane_log
    reader = DFReader.DFReader_binary(str(path), zero_time_base=False)
    oracle = {name: [] for name in OLD_FORMATS}
    while (msg := reader.recv_match(type=list(OLD_FORMATS))) is not None:
        oracle[msg.get_type()].append(msg.to_dict())
    log = read_log(path)
    assert np.array_equal(log.imu.time_us, [m["TimeMS"] * 1000 for m in oracle["IMU"]])
    assert np.allclose(log.imu.columns["gyr_x_rad_s"], [m["GyrX"] for m in oracle["IMU"]])
    assert np.array_equal(log.onboard.time_us, boot_ms * 1000)
    q = quaternion.from_euler_zyx(*np.radians([[m["Yaw"], m["Pitch"], m["Roll"]] for m in oracle["ATT"]]).T)
    assert np.degrees(quaternion.angle_between(log.onboard.stack(["qw", "qx", "qy", "qz"]), q)).max() < 1e-6
    # GPS: its boot time is T (ms); TimeMS there is the GPS week's milliseconds
    assert np.array_equal(log.gps.time_us, [m["T"] * 1000 for m in oracle["GPS"]])
    assert log.gps.columns["lat_deg"][0] == pytest.approx(oracle["GPS"][0]["Lat"])
    assert not log.damage


@pytest.mark.parametrize("command", ["replay", "export", "evaluate", "evaluate --json"])
def test_the_slow_imu_warning_is_in_every_output(old_plane_log, command, tmp_path, capsys):
    path, _ = old_plane_log
    extra = ["--out", str(tmp_path / "out.csv")] if command == "export" else []
    assert main([*command.split(), str(path), *extra]) == 0
    out = capsys.readouterr()
    said = out.out + out.err
    assert "warning: IMU at 10.0 Hz: too slow for host filtering" in said
    if command == "evaluate --json":
        assert any("too slow" in w for w in json.loads(out.out)["warnings"])


def damaged_copy(name: str, tmp_path, how: str):
    data = bytearray(flightlog(name).read_bytes())
    if how == "cut":
        data = data[: int(len(data) * CUT)]
    else:
        at = len(data) // 3
        data[at : at + BLOCK] = np.random.default_rng(23).integers(0, 256, BLOCK, dtype=np.uint8).tobytes()
    path = tmp_path / f"{how}_{name}"
    path.write_bytes(bytes(data))
    return path


def warnings_of(argv, capfd) -> tuple[list[str], str]:
    """The warning lines a command printed, and everything it printed (read at the descriptors: what a
    terminal would show, C's fprintf included)."""
    assert main(argv) == 0
    out = capfd.readouterr()
    said = out.out + out.err
    return [line[len("warning: "):] for line in said.splitlines() if line.startswith("warning: ")], said


def test_a_corrupt_block_in_a_bin_is_counted_not_printed(tmp_path, capfd):
    path = damaged_copy("arducopter_cubeorange_2023-07-06_10-12-18.bin", tmp_path, "corrupt")
    warnings, said = warnings_of(["replay", str(path)], capfd)
    assert "bad header" not in said and len(said.split("\n")) < 10  # a progress bar redraws itself on one line ("\r")
    skipped = [w for w in warnings if w.endswith("damaged bytes skipped")]
    assert len(skipped) == 1
    # the block, plus at most the record it cut into (a DataFlash record is at most 255 bytes)
    assert BLOCK - 255 <= int(skipped[0].split()[0]) <= BLOCK + 255
    clean, _ = warnings_of(["replay", str(flightlog("arducopter_cubeorange_2023-07-06_10-12-18.bin"))], capfd)
    assert not any("damaged" in w for w in clean)


@pytest.mark.parametrize("name", ["px4_sitl_quad_groundtruth.ulg", "arduplane_quadplane_sitl.tlog"])
def test_a_cut_log_says_so_in_every_command(name, tmp_path, capfd):
    path = damaged_copy(name, tmp_path, "cut")
    for argv in (["replay", str(path)], ["export", str(path), "--out", str(tmp_path / "o.csv")],
                 ["evaluate", str(path), "--filters", "hf"]):
        warnings, _ = warnings_of(argv, capfd)
        assert any("cut short" in w for w in warnings), (argv, warnings)
    assert main(["evaluate", str(path), "--filters", "hf", "--json"]) == 0
    assert any("cut short" in w for w in json.loads(capfd.readouterr().out)["warnings"])
    whole, _ = warnings_of(["replay", str(flightlog(name))], capfd)
    assert not any("cut short" in w for w in whole)


def test_a_corrupt_block_in_a_ulg_is_said(tmp_path, capfd):
    name = "px4_sitl_quad_groundtruth.ulg"
    path = damaged_copy(name, tmp_path, "corrupt")
    rows = len(read_log(path).imu)
    assert rows < len(read_log(flightlog(name)).imu)  # the block held sensor_combined rows
    for argv in (["replay", str(path)], ["export", str(path), "--out", str(tmp_path / "o.csv")]):
        warnings, _ = warnings_of(argv, capfd)
        assert any("damaged bytes" in w for w in warnings), (argv, warnings)
    whole, _ = warnings_of(["replay", str(flightlog(name))], capfd)
    assert not any("damaged" in w for w in whole)
