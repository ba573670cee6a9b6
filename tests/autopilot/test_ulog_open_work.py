"""What opening a PX4 ``.ulg`` costs in work, not time (issue 25; the times are in bench/bench_ulog.py):
pyulog parses the file once, through its own file with no Python call of ours per message; the aiding
stage's arrays (heading, hand-over, position) are exactly what the live stage's ``Aiding`` computes
reading by reading and sample by sample."""

import struct
import sys
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from groundstation.autopilot.flightlog import GPS_COLUMNS
from groundstation.session_makers.flight_log_session import _Readings, read_log
from groundstation.estimation import create
from groundstation.estimation.evaluation import sample_periods_s
from groundstation.session_parts import aiding
from groundstation.session_makers.load import load_session

from mavlink_helpers import flightlog, live_aiding_stage

ULOGS = ("px4_auavx21_bench_sample.ulg", "px4_fmuv5_quad_hop.ulg", "px4_sitl_quad_groundtruth.ulg")
SITL = "px4_sitl_quad_groundtruth.ulg"  # magnetometer, barometer and GPS
PACKAGE = str(Path(__file__).resolve().parents[2] / "groundstation")


@pytest.mark.parametrize("name", ULOGS)
def test_opening_a_log_parses_it_once(name, monkeypatch):
    constructed = []
    parse = ULog.__init__

    def counted(self, *args, **kwargs):
        constructed.append(args[0])
        parse(self, *args, **kwargs)

    monkeypatch.setattr(ULog, "__init__", counted)
    load_session(flightlog(name))
    assert len(constructed) == 1


def test_a_plain_log_is_read_with_no_python_call_of_ours_per_message():
    """The reader's own Python calls while it reads the log: far fewer than the log's messages (it once
    watched each of pyulog's reads, two calls a message)."""
    path = flightlog(SITL)
    rows = sum(len(d.data["timestamp"]) for d in ULog(str(path)).data_list)
    ours = []

    def count(frame, event, _):
        if event == "call" and frame.f_code.co_filename.startswith(PACKAGE):
            ours.append(frame.f_code.co_name)

    sys.setprofile(count)
    try:
        log = read_log(path)
    finally:
        sys.setprofile(None)
    assert len(log.imu) > 10_000 and rows > 40_000
    assert len(ours) < rows / 20, sorted(set(ours))


def last_message_start(data: bytes) -> int:
    """Where the last message of a ULog file begins (the specification's 3-byte headers: size, type)."""
    at = 16
    while at + 3 <= len(data):
        size, _ = struct.unpack_from("<HB", data, at)
        if at + 3 + size > len(data):
            return at
        at += 3 + size
    return at


def test_a_cut_log_still_says_exactly_how_much_of_its_last_message_there_is(tmp_path):
    whole = flightlog(SITL).read_bytes()
    for fraction in (0.37, 0.61):
        cut = whole[: int(len(whole) * fraction)]
        path = tmp_path / f"cut_{fraction}.ulg"
        path.write_bytes(cut)
        unfinished = len(cut) - last_message_start(cut)
        assert unfinished > 0
        assert any(f"({unfinished} bytes of an unfinished one)" in d for d in read_log(path).damage), read_log(path).damage


@pytest.mark.parametrize("restarts", [0, 3])
def test_the_aiding_arrays_are_the_live_stage_exactly(restarts):
    log = read_log(flightlog(SITL))
    t_us = log.imu.time_us
    readings = _Readings(log, t_us)
    kinds, index = readings.stream
    if restarts:  # device restarts (a recording's) among the events: each drops what waits and resets the position
        gps_us = log.gps.time_us[np.isfinite(log.gps.stack(GPS_COLUMNS[3:6])).all(axis=1)]  # those _Readings keeps
        at_us = np.linspace(t_us[0], t_us[-1], restarts + 2)[1:-1]
        kinds, index = aiding.merged([(log.mag.time_us, aiding.MAG), (log.baro.time_us, aiding.BARO), (gps_us, aiding.GPS),
                                      (t_us, aiding.SAMPLE), (at_us, aiding.RESTART)])
    acc_g = log.imu.stack(["acc_x_g", "acc_y_g", "acc_z_g"])
    dt_s = sample_periods_s(t_us / 1e6)
    q, _ = create("ahf").run(log.imu.stack(["gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s"]), acc_g, dt_s)
    mag, fix, heading, at, rows = live_aiding_stage((kinds, index), readings, q, acc_g, dt_s, len(t_us))
    got_mag, got_fix = aiding.handed_to_samples((kinds, index), len(t_us), readings.mag_body, readings.gps_values)
    got_heading, got_at, got_rows = aiding.heading_and_position((kinds, index), readings.mag_body, readings.pressure_pa,
                                                                readings.gps_values, q, acc_g, dt_s)
    assert np.isfinite(heading).sum() > 10_000 and len(at) > 10_000  # the log aids: every path is taken
    np.testing.assert_array_equal(got_mag, mag)
    np.testing.assert_array_equal(got_fix, fix)
    np.testing.assert_array_equal(got_heading, heading)
    np.testing.assert_array_equal(got_at, at)
    np.testing.assert_array_equal(got_rows, rows)
