"""Flight logs crafted to break a reader (issue 37): valid records with hostile content. Each is read
correctly or refused with one clear line (exit status 2), never a traceback."""

import struct

import numpy as np
import pytest

from groundstation.cli import main
from groundstation.session_makers.load import load_session

from mavlink_helpers import Sender, ardupilot_heartbeat, dataflash_fmt, dataflash_record, px4_flight, write_ulog

T0_US = 1_700_000_000_000_000  # 2023-11-14


def one_line_refusal(argv, capfd) -> str:
    status = main([str(a) for a in argv])
    err = capfd.readouterr().err
    assert status == 2 and "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.startswith("groundstation")]
    assert len(lines) == 1, err
    return lines[0]


def test_a_tlog_whose_receive_clock_runs_backwards_at_every_packet_is_timed_by_the_autopilot(tmp_path):
    """Every packet received 1 ms before the one before it: no receive time can be trusted, and the
    packets are timed by the autopilot's own clock (RAW_IMU's time_usec), in order."""
    ap = Sender()
    imu_us = 10_000_000 + 20_000 * np.arange(199)  # 50 Hz
    packets = [ardupilot_heartbeat(ap)] + [ap.raw_imu(int(t), 0, 0, -1000, 10 * (i % 7), 0, 0, 1, 2, 3)
                                           for i, t in enumerate(imu_us)]
    path = tmp_path / "backwards.tlog"
    path.write_bytes(b"".join(struct.pack(">Q", T0_US - 1000 * i) + p for i, p in enumerate(packets)))
    data = load_session(path, ["ahf"])
    assert any("timed by the autopilot clock" in w for w in data.warnings)
    times = data.tables["imu"]["time_s"]
    assert len(times) == len(imu_us)
    np.testing.assert_allclose(np.diff(times), np.diff(imu_us) * 1e-6, atol=1e-6)


def test_mcap_export_of_a_ulog_whose_boot_times_near_2_to_the_63_us_is_refused_in_one_line(tmp_path, capfd):
    """The attitude topics' boot times near 2^63 µs (292,000 years after the IMU's): session times no MCAP
    log time (ns since 1970 in 64 bits) holds."""
    topics, _ = px4_flight(duration_s=2.0)
    attitude = topics["vehicle_attitude"][1]  # the ground truth's columns too (the same arrays)
    attitude["timestamp"] = (2**63 - 10**7) + (attitude["timestamp"] - attitude["timestamp"][0])
    path = tmp_path / "far.ulg"
    write_ulog(path, topics, {"sys_name": "PX4"})
    said = one_line_refusal(["export", path, "--out", tmp_path / "far.mcap"], capfd)
    assert "MCAP" in said and "CSV or Parquet" in said
    assert not (tmp_path / "far.mcap").exists()


def test_a_dataflash_log_defining_every_type_with_a_wrong_length_is_refused_in_one_line(tmp_path, capfd):
    """Every type from 129 to 255 declared 5 bytes long with a 15-byte format: none of their records fits,
    and pymavlink's reader recurses once per record that does not (beyond Python's limit)."""
    out = bytearray(dataflash_fmt(128, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns"))
    for msg_id in range(129, 256):
        out += dataflash_record(128, struct.pack("<BB4s16s64s", msg_id, 5, f"T{msg_id}".encode(), b"Qf", b"TimeUS,V"))
    for i in range(20):
        for msg_id in range(129, 256):
            out += dataflash_record(msg_id, struct.pack("<Qf", 1000 * i + msg_id, 1.0))
    path = tmp_path / "every_type.bin"
    path.write_bytes(bytes(out))
    said = one_line_refusal(["evaluate", path], capfd)
    assert "do not fit" in said and "recursion" not in said
