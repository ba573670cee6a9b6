"""Flight logs as a flyer reads them (issue 23): every tab a live session has, a table for every
message type or topic, the truth where the log has one, and the full-rate IMU.

The shared logs open through the loader the app and the commands use (``load_session``); pymavlink's
DFReader and pyulog read the same files as the oracles; logs written here (DataFlash records of ISBH/ISBD
bursts, ULog fifo topics) carry a known sine at a known rate."""

import math
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
from pymavlink import DFReader
from pyulog import ULog

from groundstation import quaternion
from groundstation.session_makers.flight_log_session import _Readings, read_log
from groundstation.estimation import aiding_estimator
from groundstation.estimation.evaluation import sample_periods_s
from groundstation.session_parts.catalogue import POSITION
from groundstation.errors import UserError
from groundstation.session_makers.load import load_session
from groundstation.units import STANDARD_GRAVITY_M_S2

from mavlink_helpers import BOOT_US, live_aiding_stage, px4_flight, write_dataflash, write_ulog

FLIGHTLOGS = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "flightlogs"
COPTER = "arducopter_cubeorange_2023-07-06_10-12-18.bin"  # GPS, baro, mag; ISBD at ~2 kHz
SITL_ULOG = "px4_sitl_quad_groundtruth.ulg"  # GPS, baro, mag in sensor_combined; vehicle_attitude_groundtruth
SITL_TLOG = "ardurover_boat_sitl_autotest.tlog"  # SIMSTATE


def shared(name: str) -> Path:
    path = FLIGHTLOGS / name
    if not path.exists():
        pytest.skip(f"{path} is absent (the shared flight logs)")
    return path


@pytest.fixture(scope="module")
def copter():
    return load_session(shared(COPTER), exact=True)  # its aiding estimator's attitudes as computed (the live stage's input)


@pytest.fixture(scope="module")
def sitl_ulog():
    return load_session(shared(SITL_ULOG))


def onboard_yaw_deg_at(data, time_s):
    board = data.tables["onboard"]
    ok = np.isfinite(board["qw"])
    yaw_deg = quaternion.euler_deg(np.column_stack([board[f"q{c}"][ok] for c in "wxyz"]))[0]
    return np.degrees(np.interp(time_s, board["time_s"][ok], np.unwrap(np.radians(yaw_deg))))


@pytest.mark.parametrize("name", [COPTER, SITL_ULOG, SITL_TLOG])
def test_a_log_with_gps_and_compass_fills_the_heading_and_position_tabs(name, request):
    data = load_session(shared(name))
    gps, mag, position = data.tables["gps"], data.tables["mag_raw"], data.tables["position"]
    assert len(gps["time_s"]) > 100 and np.isfinite(gps["lat_deg"]).mean() > 0.99  # a tlog's reboot: a gap row
    assert np.isfinite(mag["heading_deg"]).mean() > 0.99
    # the compass heading (the aiding stage, on the host estimator's tilt) against the autopilot's own yaw
    difference = (mag["heading_deg"] - onboard_yaw_deg_at(data, mag["time_s"]) + 180.0) % 360.0 - 180.0
    assert np.nanmedian(np.abs(difference)) < 10.0
    assert len(position["time_s"]) > 0.9 * len(data.tables["imu"]["time_s"])
    assert np.isfinite(position["pos_n_m"]).mean() > 0.99


def test_the_log_path_runs_the_live_aiding_stage(copter):
    """The heading and the position the live pipeline's ``Aiding`` computes, called once per reading and
    sample, on the aiding estimator's attitudes: the log path's, to the last bit (it runs the same
    rules on whole columns: the hand-over, ``reading_heading_rad``, the position filter's ``advance``)."""
    log = read_log(shared(COPTER))
    t_us = log.imu.time_us
    readings = _Readings(log, t_us)
    q = np.column_stack([copter.tables["imu"][f"{aiding_estimator(copter.filters)}_q{c}"] for c in "wxyz"])
    acc_g = log.imu.stack(["acc_x_g", "acc_y_g", "acc_z_g"])
    _, _, heading, at, rows = live_aiding_stage(readings.stream, readings, q, acc_g, sample_periods_s(t_us / 1e6), len(t_us))
    assert len(heading) > 100 and len(at) > 0.9 * len(t_us)
    np.testing.assert_array_equal(copter.tables["mag_raw"]["heading_deg"], heading)
    position = copter.tables["position"]
    np.testing.assert_array_equal(position["time_s"], copter.tables["imu"]["time_s"][at])
    np.testing.assert_array_equal(np.column_stack([position[c] for c in POSITION.column_names[1:]]), rows)


def test_a_log_has_no_host_arrival_column(copter, sitl_ulog):
    for data in (copter, sitl_ulog):
        assert "host_time_s" not in data.catalogue["imu"].column_names


def test_every_dataflash_message_type_is_a_table_as_pymavlink_reads_it(copter):
    reader = DFReader.DFReader_binary(str(shared(COPTER)), zero_time_base=False)
    rows = defaultdict(list)
    while (msg := reader.recv_msg()) is not None:
        if msg.get_type() in ("ATT", "VIBE", "BARO", "RCOU"):
            rows[(msg.get_type(), getattr(msg, msg.fmt.instance_field) if msg.fmt.instance_field else None)].append(msg)
    for (msg_type, instance), messages in rows.items():
        name = msg_type.lower() if instance is None else f"{msg_type.lower()}_{instance}"
        name = name + "_log" if name == "baro" else name
        table, info = copter.tables[name], copter.catalogue[name]
        assert len(table["time_s"]) == len(messages), name
        for field in ("Roll", "VibeX", "Press", "C1"):
            if field in messages[0].fmt.columns:
                column = next(c.name for c in info.columns if c.label == field)
                np.testing.assert_array_equal(table[column], [getattr(m, field) for m in messages])
    assert copter.catalogue["att"].column("Roll_deg").unit == "deg"  # FMTU's unit
    assert len([t for t in copter.catalogue if t.name not in ("imu", "onboard")]) > 60


def test_every_ulog_topic_is_a_table(sitl_ulog):
    topics = {(d.name, d.multi_id) for d in ULog(str(shared(SITL_ULOG))).data_list if len(d.data["timestamp"])}
    for topic, instance in topics:
        assert (topic if not instance else f"{topic}_{instance}") in sitl_ulog.catalogue.tables
    assert "gyro_rad_0" in sitl_ulog.catalogue["sensor_combined"].column_names


def test_the_sitl_truth_is_a_table_and_scores(sitl_ulog):
    truth = sitl_ulog.tables["truth"]
    assert len(truth["time_s"]) == 5421  # vehicle_attitude_groundtruth's messages (the README's 84 Hz over 58 s)
    assert sitl_ulog.evaluate()["onboard"]["incl_rmse_deg"] < 2.0


def test_a_sitl_tlog_takes_simstate_as_truth():
    data = load_session(shared(SITL_TLOG))
    sim = data.tables["simstate"]
    q = np.column_stack([data.tables["truth"][f"q{c}"] for c in "wxyz"])
    yaw, pitch, roll = quaternion.euler_deg(q)
    np.testing.assert_allclose(np.radians(roll), sim["roll_rad"][np.isfinite(sim["roll_rad"])], atol=1e-9)
    assert data.evaluate()["onboard"]["incl_rmse_deg"] < 1.0


# -- full rate: ArduPilot's batch sampler ---------------------------------------------------------

def pymavlink_isbd(path) -> dict[tuple[int, int], tuple[np.ndarray, np.ndarray]]:
    """(type, instance) -> (times µs, (n, 3) values): ISBD samples as DFReader reads them, one by one."""
    reader = DFReader.DFReader_binary(str(path), zero_time_base=False)
    headers, out = {}, defaultdict(lambda: ([], []))
    while (msg := reader.recv_match(type=["ISBH", "ISBD"])) is not None:
        if msg.get_type() == "ISBH":
            headers[msg.N] = msg
            continue
        h = headers[msg.N]
        times, values = out[(h.type, h.instance)]
        for j in range(32):
            k = msg.seqno * 32 + j
            if k < h.smp_cnt:
                times.append(h.SampleUS + k * 1e6 / h.smp_rate)
                values.append([msg.x[j] / h.mul, msg.y[j] / h.mul, msg.z[j] / h.mul])
    return {key: (np.array(t), np.array(v)) for key, (t, v) in out.items()}


def test_isbd_bursts_sample_for_sample_against_pymavlink(copter):
    expected = pymavlink_isbd(shared(COPTER))
    t0_us = copter.tables["imu"]["device_time_us"][0]
    for (kind, instance), (times, values) in expected.items():
        name = {0: "accel_fast", 1: "gyro_fast"}[kind] + f"_{instance}"
        table = copter.tables[name]
        columns = ("gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s") if kind == 1 else ("acc_x_m_s2", "acc_y_m_s2", "acc_z_m_s2")
        order = np.argsort(times, kind="stable")
        np.testing.assert_allclose(table["time_s"], (times[order] - t0_us) / 1e6, rtol=0, atol=1e-9)
        np.testing.assert_array_equal(np.column_stack([table[c] for c in columns]), values[order])
    assert len(copter.tables["gyro_fast_0"]["time_s"]) > 70_000  # ~2 kHz bursts
    assert 1900 < 1 / np.median(np.diff(copter.tables["gyro_fast_0"]["time_s"])) < 2050


SINE_HZ, RATE_HZ, MUL = 37.0, 2000.0, 938  # a gyro sine, the sampler's rate and ArduPilot's gyro multiplier


def sine_rad_s(t_s):
    return np.column_stack([0.5 * np.sin(2 * math.pi * SINE_HZ * t_s), 0.25 * np.cos(2 * math.pi * SINE_HZ * t_s),
                            np.full(len(t_s), 0.1)])  # fmt: skip


def isb_log(path, starts_s, seconds: float = 3.0):
    """A DataFlash log of a 100 Hz IMU, level and still, for ``seconds``, and 1024-sample gyro batches of a
    known sine starting at ``starts_s``."""
    t_imu_s = np.arange(round(100 * seconds)) / 100.0
    imu = [(int(10_000_000 + t * 1e6), 0, 0.0, 0.0, 0.0, 0.0, 0.0, -STANDARD_GRAVITY_M_S2) for t in t_imu_s]
    isbh, isbd = [], []
    for n, start_s in enumerate(starts_s):
        first_us = 10_000_000 + int(start_s * 1e6)
        isbh.append((first_us + 600_000, n, 1, 0, MUL, 1024, first_us, RATE_HZ))  # logged after its samples
        k = np.arange(1024)
        counts = np.rint(sine_rad_s((first_us + k * 1e6 / RATE_HZ) / 1e6) * MUL).astype(int)
        for seqno in range(32):
            block = counts[seqno * 32 : seqno * 32 + 32]
            isbd.append((first_us + 600_001 + seqno, n, seqno, *block[:, 0], *block[:, 1], *block[:, 2]))
    write_dataflash(path, {
        "IMU": ("QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ", imu),
        "ISBH": ("QHBBHHQf", "TimeUS,N,type,instance,mul,smp_cnt,SampleUS,smp_rate", isbh),
        "ISBD": ("QHHaaa", "TimeUS,N,seqno,x,y,z", isbd),
    })  # fmt: skip
    return path


@pytest.fixture(scope="module")
def sine_bin(tmp_path_factory):
    """Two 1024-sample gyro bursts of a known sine in three seconds of a 100 Hz IMU."""
    return isb_log(tmp_path_factory.mktemp("isb") / "sine.bin", (0.5, 1.7))


def test_isbd_written_here_gives_the_known_sine(sine_bin):
    log = read_log(sine_bin)
    fast = log.tables["gyro_fast_0"]
    assert len(fast) == 2048
    expected = sine_rad_s(fast.time_us / 1e6)
    np.testing.assert_allclose(fast.stack(("gyr_x", "gyr_y", "gyr_z")), expected, rtol=0, atol=0.5 / MUL + 1e-12)
    assert fast.rate_hz == pytest.approx(RATE_HZ, rel=1e-6)
    times, values = pymavlink_isbd(sine_bin)[(1, 0)]
    np.testing.assert_array_equal(fast.stack(("gyr_x", "gyr_y", "gyr_z")), values)


def test_bursts_do_not_feed_the_estimators_even_when_asked(sine_bin):
    regular, fast = load_session(sine_bin, ["ahf"]), load_session(sine_bin, ["ahf"], imu="fast")
    # two bursts in three seconds: the estimators stay on the logged IMU, and the session says why in one line
    np.testing.assert_array_equal(fast.tables["imu"]["time_s"], regular.tables["imu"]["time_s"])
    np.testing.assert_array_equal(fast.tables["imu"]["ahf_qw"], regular.tables["imu"]["ahf_qw"])
    said = [w for w in fast.warnings if "bursts" in w]
    assert len(said) == 1 and "2 bursts of 1024 samples at 2000 Hz" in said[0] and "the logged IMU (IMU[0], 100 Hz)" in said[0]
    assert "gyro_fast_0" in regular.tables and len(regular.tables["gyro_fast_0"]["time_s"]) == 2048
    np.testing.assert_array_equal(regular.tables["gyro_fast_0"]["batch"], np.repeat([0.0, 1.0], 1024))


def test_batches_back_to_back_are_a_continuous_stream_that_feeds_the_estimators(tmp_path):
    """The batch sampler set to sample without pause: one batch starts where the last ended, no bursts."""
    batch_s = 1024 / RATE_HZ
    path = isb_log(tmp_path / "continuous.bin", batch_s * np.arange(5), seconds=5 * batch_s)
    data = load_session(path, ["ahf"], imu="fast")
    assert not any("bursts" in w for w in data.warnings)
    rows = data.tables["imu"]
    assert 1 / np.median(np.diff(rows["time_s"])) == pytest.approx(RATE_HZ, rel=1e-6)
    assert len(rows["time_s"]) >= 5 * 1024
    np.testing.assert_allclose(rows["gyr_x_rad_s"][:5 * 1024], sine_rad_s(rows["device_time_us"][:5 * 1024] / 1e6)[:, 0],
                               atol=0.5 / MUL + 1e-12)


def test_fast_without_a_full_rate_imu_is_a_clear_error(tmp_path):
    topics, _ = px4_flight(duration_s=2.0)
    path = tmp_path / "plain.ulg"
    write_ulog(path, topics)
    with pytest.raises(UserError, match="no full-rate IMU"):
        load_session(path, imu="fast")
    with pytest.raises(UserError, match="has no full-rate IMU stream"):
        load_session(shared(SITL_TLOG), imu="fast")


def test_the_commands_take_imu_fast(sine_bin, tmp_path, capsys):
    from groundstation.cli import main

    assert main(["export", str(sine_bin), "--out", str(tmp_path / "fast.csv"), "--filters", "ahf", "--imu", "fast"]) == 0
    rows = np.genfromtxt(tmp_path / "fast.csv", delimiter=",", names=True)
    assert len(rows) == len(load_session(sine_bin, ["ahf"], imu="fast").tables["imu"]["time_s"])
    capsys.readouterr()
    assert main(["evaluate", str(shared(SITL_TLOG)), "--imu", "fast"]) == 2
    assert main(["export", str(shared(SITL_TLOG)), "--out", str(tmp_path / "refused.csv"), "--imu", "fast"]) == 2
    said = capsys.readouterr().err
    assert said.count("no full-rate IMU stream") == 2 and "Traceback" not in said
    assert not (tmp_path / "refused.csv").exists()


# -- full rate: PX4's fifo topics ---------------------------------------------------------------------

FIFO_FIELDS = [("uint64_t", "timestamp"), ("uint64_t", "timestamp_sample"), ("uint32_t", "device_id"), ("float", "dt"),
               ("float", "scale"), ("uint8_t", "samples"), ("int16_t[32]", "x"), ("int16_t[32]", "y"), ("int16_t[32]", "z")]  # fmt: skip
FIFO_HZ, FIFO_SCALE, PER_MESSAGE = 8000.0, 1.0 / 1000.0, 20  # 8 kHz, 1 mrad/s per count, 20 samples each


def fifo_topic(boot_us: int, duration_s: float, values_of):
    """Messages of ``PER_MESSAGE`` samples ``1/FIFO_HZ`` apart, the newest at ``timestamp_sample``."""
    dt_us = 1e6 / FIFO_HZ
    count = int(duration_s * FIFO_HZ) // PER_MESSAGE
    newest_us = boot_us + (np.arange(count) + 1) * PER_MESSAGE * dt_us - dt_us
    sample_us = newest_us[:, None] - (PER_MESSAGE - 1 - np.arange(PER_MESSAGE))[None, :] * dt_us
    counts = np.rint(values_of(sample_us / 1e6) / FIFO_SCALE).astype(int)  # (messages, samples, 3)
    pad = np.zeros((count, 32 - PER_MESSAGE), dtype=int)
    columns = {"timestamp": np.rint(newest_us + 300), "timestamp_sample": np.rint(newest_us), "device_id": np.full(count, 7),
               "dt": np.full(count, dt_us), "scale": np.full(count, FIFO_SCALE), "samples": np.full(count, PER_MESSAGE),
               **{a: np.hstack([counts[:, :, i], pad]) for i, a in enumerate("xyz")}}  # fmt: skip
    return FIFO_FIELDS, columns


@pytest.fixture(scope="module")
def fifo_ulog(tmp_path_factory):
    topics, _ = px4_flight(duration_s=2.0)
    topics["sensor_gyro_fifo"] = fifo_topic(BOOT_US, 2.0, lambda t: np.stack(
        [sine_rad_s(row) for row in np.atleast_2d(t)]))
    topics["sensor_accel_fifo"] = fifo_topic(BOOT_US, 2.0, lambda t: np.stack(
        [np.column_stack([np.zeros(len(row)), np.zeros(len(row)), np.full(len(row), -9.81)]) for row in np.atleast_2d(t)]))
    path = tmp_path_factory.mktemp("fifo") / "fifo.ulg"
    write_ulog(path, topics)
    return path


def test_fifo_topics_sample_for_sample_against_pyulog_and_the_known_sine(fifo_ulog):
    log = read_log(fifo_ulog)
    fast = log.tables["gyro_fast_0"]
    data = next(d for d in ULog(str(fifo_ulog)).data_list if d.name == "sensor_gyro_fifo").data
    times, values = [], []
    for m in range(len(data["timestamp"])):
        n = data["samples"][m]
        for i in range(n):
            times.append(data["timestamp_sample"][m] - (n - 1 - i) * float(data["dt"][m]))
            values.append([data[f"{a}[{i}]"][m] * float(data["scale"][m]) for a in "xyz"])
    np.testing.assert_allclose(fast.time_us, times, rtol=0, atol=1e-6)
    np.testing.assert_allclose(fast.stack(("gyr_x", "gyr_y", "gyr_z")), values, rtol=1e-6, atol=0)
    np.testing.assert_allclose(fast.stack(("gyr_x", "gyr_y", "gyr_z")), sine_rad_s(fast.time_us / 1e6),
                               rtol=0, atol=0.5 * FIFO_SCALE + 1e-6)
    assert fast.rate_hz == pytest.approx(FIFO_HZ, rel=1e-3)
    accel = log.tables["accel_fast_0"]
    np.testing.assert_allclose(accel.columns["acc_z"], -9.81, atol=FIFO_SCALE)


def test_the_fifo_stream_feeds_the_estimators_when_asked(fifo_ulog):
    data = load_session(fifo_ulog, ["ahf"], imu="fast")
    imu = data.tables["imu"]
    assert 1 / np.median(np.diff(imu["time_s"])) == pytest.approx(FIFO_HZ, rel=1e-3)
    np.testing.assert_allclose(imu["acc_z_g"][10:-10], -9.81 / STANDARD_GRAVITY_M_S2, atol=1e-3)
    assert data.catalogue["gyro_fast_0"].column_names == ("time_s", "gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s", "batch")
    assert data.catalogue["accel_fast_0"].column_names == ("time_s", "acc_x_m_s2", "acc_y_m_s2", "acc_z_m_s2", "batch")
    assert not any("bursts" in w for w in data.warnings)  # a fifo is a continuous stream: it feeds the estimators
    np.testing.assert_array_equal(data.tables["gyro_fast_0"]["batch"], np.repeat(np.arange(2.0 * FIFO_HZ / PER_MESSAGE), PER_MESSAGE))
