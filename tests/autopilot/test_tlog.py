"""The .tlog file: what we write, pymavlink's own tlog reader reads back (timestamps and messages);
what we read survives junk and a cut end; the autopilot's clock, not the receive time, is the time base."""

import struct

import numpy as np
import pytest
from pymavlink import mavutil

from groundstation.session_makers.flight_log_session import read_log
from groundstation.autopilot.tlog import packets_of_chunks, write_tlog
from groundstation.errors import UserError

from mavlink_helpers import Sender, ardupilot_heartbeat, flightlog

T0_US = 1_700_000_000_000_000  # 2023-11-14


def imu_packets(n: int, rate_hz: float = 50.0):
    ap = Sender()
    out = [(T0_US, ardupilot_heartbeat(ap))]
    for i in range(n):
        t_us = int(i * 1e6 / rate_hz)
        out.append((T0_US + t_us + 1000, ap.raw_imu(10_000_000 + t_us, 0, 0, -1000, 10 * (i % 7), 0, 0, 1, 2, 3)))
        out.append((T0_US + t_us + 1500, ap.attitude(10_000 + t_us // 1000, 0.01 * (i % 7), 0.0, 1.0, 0, 0, 0)))
    return out


def test_pymavlink_reads_our_tlog_with_the_same_times_and_messages(tmp_path):
    packets = imu_packets(100)
    path = tmp_path / "ours.tlog"
    assert write_tlog(path, packets) == len(packets)
    log = mavutil.mavlogfile(str(path))
    got = []
    while (msg := log.recv_msg()) is not None:
        got.append((round(msg._timestamp * 1e6), bytes(msg.get_msgbuf())))
    log.close()
    assert got == [(t, bytes(p)) for t, p in packets]


def test_write_refuses_to_overwrite(tmp_path):
    path = tmp_path / "x.tlog"
    path.write_bytes(b"")
    with pytest.raises(UserError, match="exists"):
        write_tlog(path, [])


def test_a_byte_stream_saved_as_tlog_keeps_every_packet_and_arrival_time(tmp_path):
    packets = imu_packets(50)
    raw = b"".join(p for _, p in packets)
    # Arbitrary chunks, as a serial port delivers them, each stamped on arrival (host monotonic ns).
    cuts = list(range(0, len(raw), 37)) + [len(raw)]
    chunks = [(5_000_000_000 + i * 1_000_000, raw[a:b]) for i, (a, b) in enumerate(zip(cuts, cuts[1:]))]
    path = tmp_path / "saved.tlog"
    write_tlog(path, packets_of_chunks(chunks, T0_US))
    log = mavutil.mavlogfile(str(path))
    saved = []
    while (msg := log.recv_msg()) is not None:
        saved.append((round(msg._timestamp * 1e6), bytes(msg.get_msgbuf())))
    assert [p for _, p in saved] == [bytes(p) for _, p in packets]
    # Each packet carries the arrival time of the chunk that completed it.
    ends = np.cumsum([len(p) for _, p in packets])
    chunk_of_end = np.searchsorted(cuts[1:], ends)
    assert [t for t, _ in saved] == [T0_US + int(i) * 1000 for i in chunk_of_end]


def test_reading_skips_junk_and_a_truncated_end_and_says_so(tmp_path):
    packets = imu_packets(200)
    clean = b"".join(struct.pack(">Q", t) + p for t, p in packets)
    parts = [struct.pack(">Q", t) + p for t, p in packets]
    junk = b"\x00\x11junk bytes\xfd\x09"  # includes a MAVLink 2 start byte that leads nowhere
    damaged = b"".join(parts[:150]) + junk + b"".join(parts[150:])
    damaged = damaged[:-7]  # the last record cut short, as by a crash
    (tmp_path / "clean.tlog").write_bytes(clean)
    (tmp_path / "damaged.tlog").write_bytes(damaged)
    good, bad = read_log(tmp_path / "clean.tlog"), read_log(tmp_path / "damaged.tlog")
    assert len(good.imu) == 200 and len(good.onboard) == 200 and not any("damaged" in n for n in good.notes)
    assert len(bad.imu) == 200 and len(bad.onboard) == 199  # only the cut ATTITUDE is lost
    assert any("damaged" in n for n in bad.notes)
    assert np.array_equal(bad.imu.time_us, good.imu.time_us)


def test_a_file_that_is_no_tlog_is_a_clear_error(tmp_path):
    path = tmp_path / "text.tlog"
    path.write_text("hello, this is not MAVLink\n" * 20)
    with pytest.raises(UserError, match="no MAVLink messages"):
        read_log(path)


def test_sitl_tlog_uses_the_autopilot_clock_not_the_compressed_receive_time(tmp_path):
    # ArduPilot's autotest ran ~25x faster than real time: 308 s of autopilot time in 12 s of receive
    # time (README). The first 400 kB (a cut file, like a crash) keep the test short.
    trimmed = tmp_path / "rover_start.tlog"
    trimmed.write_bytes(flightlog("ardurover_boat_sitl_autotest.tlog").read_bytes()[:400_000])
    log = read_log(trimmed)
    assert log.autopilot == "ArduPilot" and log.imu.source == "RAW_IMU"
    assert log.imu.rate_hz == pytest.approx(10.0, rel=0.02)  # README: 10 Hz on time_boot_ms / time_usec
    assert log.onboard.rate_hz == pytest.approx(10.0, rel=0.02)
    assert any("damaged" in note for note in log.notes)  # ~2.2 KB of non-packet bytes at the start


def test_a_sitl_tlog_opens_on_the_autopilot_clock_and_a_live_one_on_its_receive_times(tmp_path):
    """The rule of ``autopilot.tlog``: compressed receive times (the autopilot clock runs ~25x faster) are
    replaced by the autopilot's clock, so the session sees no clock jumps; a log at real time keeps its own."""
    from groundstation.autopilot.tlog import session_packets
    from groundstation.session_parts.clock import DISCONTINUITIES
    from groundstation.session_makers.load import load_session

    trimmed = tmp_path / "rover_start.tlog"
    trimmed.write_bytes(flightlog("ardurover_boat_sitl_autotest.tlog").read_bytes()[:400_000])
    data = load_session(trimmed, ("hf",))
    # The log starts with the end of a boot before the autotest's reboot: that one reset, no clock jumps.
    assert [e["kind"] for e in data.events if e["kind"] in DISCONTINUITIES] == ["device_reset"]
    imu = data.tables["imu"]
    last = slice(np.flatnonzero(np.isnan(imu["device_time_us"]))[-1] + 1, None)  # after the reset's gap row
    device_s = (imu["device_time_us"][last] - imu["device_time_us"][last][0]) / 1e6
    assert device_s[-1] > 20  # tens of seconds of autopilot time in ~1 s of receive time
    np.testing.assert_allclose(imu["time_s"][last] - imu["time_s"][last][0], device_s, atol=1e-9)
    host_s = imu["host_time_s"][last] - imu["host_time_s"][last][0]
    np.testing.assert_allclose(host_s, device_s, atol=1e-6)  # receive time = autopilot time
    assert "compressed" in data.metadata["notes"] and any("damaged" in d for d in data.damage)

    # A log at real time, with a burst at the start (a backlog read at once): its receive times are kept.
    ap, t0_us = Sender(), 1_700_000_000_000_000
    packets = [(t0_us, ardupilot_heartbeat(ap))]
    for i in range(200):  # 4 s at 50 Hz; the first second's samples all received at once
        packets.append((t0_us + max(i * 20_000, 1_000_000), ap.raw_imu(3_000_000 + i * 20_000, 0, 0, -1000, 0, 0, 0, 1, 2, 3)))
    path = tmp_path / "real_time.tlog"
    write_tlog(path, packets)
    stamped = session_packets(path.read_bytes())
    assert not stamped.compressed and [t for t, _ in stamped.packets] == [t * 1000 for t, _ in packets]


def test_the_autopilot_clock_decodes_only_the_messages_that_time_it(monkeypatch):
    """Issue 35: the clock's pass decoded every packet, which the session decodes again after it (a third
    of opening a .tlog). It decodes the messages whose records time the clock or choose the vehicle: the
    same clock as every packet decoded (the boat's start: compressed, damaged bytes at its start)."""
    from groundstation.autopilot import tlog
    from groundstation.autopilot.decoder import MavlinkDecoder

    data = flightlog("ardurover_boat_sitl_autotest.tlog").read_bytes()[:400_000]
    fed = []
    feed = MavlinkDecoder.feed
    monkeypatch.setattr(MavlinkDecoder, "feed", lambda self, *args: fed.append(1) or feed(self, *args))
    stamped = tlog.session_packets(data)
    decoded = len(fed)
    monkeypatch.setattr(tlog, "_message_id", lambda packet: mavutil.mavlink.MAVLINK_MSG_ID_HEARTBEAT)  # every one decoded
    every = tlog.session_packets(data)
    assert stamped.compressed and stamped.packets == every.packets
    assert len(fed) - decoded == len(stamped.packets) and decoded < len(stamped.packets) / 3


def test_a_logs_packets_are_kept_as_columns_not_a_list_of_tuples_of_bytes():
    """Issue 35: the packets a session is fed took ~4x the file as a list of (time, bytes) tuples; kept as
    the file's bytes and columns of places and times, they take the file and a few bytes a packet."""
    import tracemalloc

    from groundstation.autopilot.tlog import session_packets

    data = flightlog("ardusub_rov_surface.tlog").read_bytes()
    session_packets(data)  # what it imports on first use, imported
    tracemalloc.start()
    try:
        stamped = session_packets(data)
        held = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    assert len(stamped.packets) > 10_000
    assert held < 0.75 * len(data)  # the file's bytes are the caller's; 24 bytes a packet beside them
    assert [len(p) for _, p in stamped.packets][:3] == [len(stamped.packets[i][1]) for i in range(3)]
