"""A real ArduCopter log's vibration counters (VIBE per IMU, clips) and motor outputs (RCOU) through the
session, checked against pymavlink's DFReader read here on its own."""

from pathlib import Path

import numpy as np
import pytest
from pymavlink import DFReader

from groundstation.analysis.vibration import vibration_summary
from groundstation.session_makers.flight_log_session import load_log

LOG = Path("/work/shared/datasets/flightlogs/arducopter_cubeorange_2023-07-06_10-12-18.bin")
pytestmark = pytest.mark.skipif(not LOG.exists(), reason="the shared flight logs are not here")


@pytest.fixture(scope="module")
def logged():
    """DFReader's VIBE rows (TimeUS, IMU, VibeX, VibeY, VibeZ, Clip), RCOU rows and the first IMU[0] time."""
    reader = DFReader.DFReader_binary(str(LOG), zero_time_base=False)
    vibe, rcou, imu_t0 = [], [], None
    while (m := reader.recv_match(type=["VIBE", "RCOU", "IMU"])) is not None:
        if m.get_type() == "VIBE":
            vibe.append((m.TimeUS, m.IMU, m.VibeX, m.VibeY, m.VibeZ, m.Clip))
        elif m.get_type() == "RCOU":
            rcou.append((m.TimeUS, m.C1, m.C4))
        elif imu_t0 is None and m.I == 0:
            imu_t0 = m.TimeUS
    return np.array(vibe, dtype=float), np.array(rcou, dtype=float), imu_t0


@pytest.fixture(scope="module")
def session():
    return load_log(LOG, ["ahf"])


@pytest.mark.parametrize(("start_s", "end_s"), [(None, None), (20.0, 60.0)])
def test_vibe_levels_and_clips_per_imu_equal_dfreaders(logged, session, start_s, end_s):
    vibe, _, t0 = logged
    summary = vibration_summary(session, start_s, end_s)
    t_s = (vibe[:, 0] - t0) / 1e6
    inside = (t_s >= summary.start_s) & (t_s <= summary.end_s)
    assert summary.clipping["source"] == "VIBE"
    assert sorted(summary.clipping["imus"]) == ["0", "1", "2"]
    for imu, entry in summary.clipping["imus"].items():
        rows = vibe[inside & (vibe[:, 1] == int(imu))]
        for k, axis in enumerate("xyz"):
            assert entry[f"max_vibe_{axis}_m_s2"] == pytest.approx(rows[:, 2 + k].max(), rel=1e-6)
        assert entry["clips"] == rows[:, 5].max() - rows[:, 5].min()
        worst = rows[:, 2:5].max()
        assert entry["verdict"] == ("fine" if worst < 30 else "may cause problems" if worst < 60 else "too high")


def test_the_spectra_come_from_the_full_rate_imu_batches():
    reader = DFReader.DFReader_binary(str(LOG), zero_time_base=False)
    rates = {}
    while (m := reader.recv_match(type=["ISBH"])) is not None:
        rates.setdefault((m.type, m.instance), m.smp_rate)  # type 0 accel, 1 gyro
    summary = vibration_summary(load_log(LOG, ["ahf"]), 20.0, 60.0)
    assert summary.spectra["gyro"].table == "gyro_fast_0" and summary.spectra["accel"].table == "accel_fast_0"
    assert summary.spectra["gyro"].rate_hz == pytest.approx(rates[(1, 0)], rel=1e-3)
    assert summary.spectra["accel"].rate_hz == pytest.approx(rates[(0, 0)], rel=1e-3)
    assert summary.motor["throttle_source"] == "rcou" and summary.notch["ardupilot"]["INS_HNTCH_MODE"] == 1  # throttle-tracking


def test_the_motor_outputs_are_a_table_of_the_session(logged, session):
    _, rcou, t0 = logged
    table = session.tables["rcou"]
    np.testing.assert_allclose(table["time_s"], (rcou[:, 0] - t0) / 1e6)
    np.testing.assert_array_equal(table["C1_us"], rcou[:, 1])
    np.testing.assert_array_equal(table["C4_us"], rcou[:, 2])
    summary = vibration_summary(session)
    assert summary.motor["throttle_source"] == "rcou" and 0.0 < summary.motor["throttle"] < 1.0
