"""The workbook read back with openpyxl: sheets, headers, row counts and the session's own numbers."""

from datetime import datetime, timedelta

import numpy as np
import pytest
from openpyxl import load_workbook

from groundstation.estimation import create
from groundstation.export import excel_columns
from groundstation.export.columns import select_rows, sensor_columns
from groundstation.export.excel import write_workbook
from groundstation.recording import open_recording
from groundstation.session_makers.load import load_session

from .conftest import CHANGE_AT_S, simulated_recording

ATTITUDE_HEADERS = [
    "time (s)", "time (UTC)",
    "ahf pitch (°)", "ahf roll (°)", "ahf yaw (°)", "hf pitch (°)", "hf roll (°)", "hf yaw (°)",
    "onboard pitch (°)", "onboard roll (°)", "onboard yaw (°)", "ahf λ (rad/s)",
]  # fmt: skip


def columns(sheet) -> dict[str, list]:
    """Header -> the values below it; blocks side by side repeat no header, so this is unambiguous."""
    rows = list(sheet.iter_rows(values_only=True))
    return {h: [r[i] for r in rows[1:]] for i, h in enumerate(rows[0]) if h is not None}


def floats(values) -> np.ndarray:
    return np.array([np.nan if v is None else v for v in values], dtype=float)


def euler_deg(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ZYX pitch, roll, yaw of body->NED quaternions, written out here, not taken from the code."""
    w, x, y, z = q.T
    pitch = np.degrees(np.arcsin(np.clip(2 * (w * y - x * z), -1, 1)))
    roll = np.degrees(np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)))
    yaw = np.degrees(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
    return pitch, roll, yaw


@pytest.fixture(scope="module")
def sim_book(sim_session, tmp_path_factory):
    path = tmp_path_factory.mktemp("book") / "hover.xlsx"
    sheets = write_workbook(sim_session, path)
    return sheets, load_workbook(path)


def test_sheets_headers_row_counts_and_layout(sim_session, sim_book):
    sheets, book = sim_book
    assert sheets == ["Session", "Attitude", "Sensors", "Link", "Chart", "Vibration"]
    assert book.sheetnames == ["Session", "Attitude", "Sensors", "Link", "Chart", "Chart data", "Vibration"]
    assert book["Chart data"].sheet_state == "hidden"
    attitude = book["Attitude"]
    assert [c.value for c in attitude[1]] == ATTITUDE_HEADERS
    assert attitude.max_row == len(sim_session) + 1
    for title in ("Attitude", "Sensors", "Link"):
        sheet = book[title]
        assert sheet.freeze_panes == "B2"
        assert all(c.font.b for c in sheet[1] if c.value is not None)
        assert all("(" in c.value for c in sheet[1] if c.value is not None)  # a unit in every header
    assert attitude["A2"].number_format == "0.000" and attitude["C2"].number_format == "0.00"
    assert attitude["B2"].number_format == "yyyy-mm-dd hh:mm:ss.000"
    assert attitude.column_dimensions["B"].width >= 23  # the date-time is not shown as ####
    sensors = columns(book["Sensors"])
    rows = {name: len(table["time_s"]) for name, table in sim_session.tables.items()}
    assert len([v for v in sensors["mag x (µT)"] if v is not None]) == rows["mag_raw"]
    assert len([v for v in sensors["baro pressure (Pa)"] if v is not None]) == rows["baro"]
    assert len([v for v in sensors["gps lat (°)"] if v is not None]) == rows["gps"]
    link = columns(book["Link"])
    assert len([v for v in link["frames (1/s)"] if v is not None]) == len(sim_session.link.per_second["t_s"])


def test_attitude_values_are_the_sessions(sim_session, sim_book):
    got = columns(sim_book[1]["Attitude"])
    np.testing.assert_allclose(floats(got["time (s)"]), sim_session.time_s, rtol=1e-15)
    for name, q in sim_session.attitudes().items():
        for angle, expected in zip(("pitch", "roll", "yaw"), euler_deg(q)):
            np.testing.assert_allclose(floats(got[f"{name} {angle} (°)"]), expected, rtol=1e-12, atol=1e-12)
    missing = np.isnan(sim_session.quaternion("onboard")[:, 0])
    assert missing.any()  # the lossy link lost ATTITUDE frames: those cells are empty, not NaN text
    assert all(v is None for v, m in zip(got["onboard pitch (°)"], missing) if m)
    np.testing.assert_allclose(floats(got["ahf λ (rad/s)"]), sim_session.tables["imu"]["ahf_lam"], rtol=1e-15)
    start = datetime(2024, 5, 1, 12, 0, 0)
    for i in (0, 777, len(sim_session) - 1):
        expected = start + timedelta(seconds=float(sim_session.time_s[i]))
        assert abs((got["time (UTC)"][i] - expected).total_seconds()) < 1e-3


def test_sensor_and_link_values_are_the_sessions(sim_session, sim_book):
    book = sim_book[1]
    got = columns(book["Sensors"])
    for name, header in (("acc_y_g", "acc y (g)"), ("gyr_z_dps", "gyro z (°/s)"), ("temperature_c", "temperature (°C)")):
        np.testing.assert_allclose(floats(got[header]), sensor_columns(sim_session)[name], rtol=1e-15)
    baro = sim_session.tables["baro"]
    n = len(baro["time_s"])
    np.testing.assert_allclose(floats(got["baro time (s)"][:n]), baro["time_s"], rtol=1e-15)
    np.testing.assert_allclose(floats(got["baro pressure (Pa)"][:n]), baro["pressure_Pa"], rtol=1e-15)
    link = columns(book["Link"])
    per_second = sim_session.link.per_second
    for name, header in (("frames", "frames (1/s)"), ("crc_errors", "CRC failures (1/s)"), ("bytes", "bytes (B/s)")):
        assert link[header][: len(per_second[name])] == per_second[name].astype(int).tolist()


def session_values(sheet) -> dict:
    return {row[0]: row[1:] for row in sheet.iter_rows(values_only=True) if row[0]}


def test_session_sheet_explains_the_session(sim_session, sim_book, sim_recording):
    rows = session_values(sim_book[1]["Session"])
    counters = sim_session.link.counters
    assert counters["crc_errors"] > 0 and counters["frames_lost"] > 0  # the numbers below are not trivially 0
    assert rows["CRC failures (count)"][0] == counters["crc_errors"]
    assert rows["frames lost (count)"][0] == counters["frames_lost"]
    assert rows["frames received (count)"][0] == counters["frames"]
    assert rows["port"][0] == "/dev/ttySIM"
    assert rows["recording started (UTC)"][0] == datetime(2024, 5, 1, 12, 0, 0)
    assert rows["duration (s)"][0] == pytest.approx(sim_session.time_s[-1])
    assert rows["firmware version"][0] == "0.1.0"
    assert rows["mounting"][0] == "sensor +x forward, -y right"
    assert rows["hf.beta"][:2] == (0.1, 0.3)  # at start, at end
    changes = [r for r in sim_book[1]["Session"].iter_rows(values_only=True) if r[2] == "settings"]
    assert len(changes) == 1 and changes[0][3] == "hf.beta = 0.3"
    first_byte_s = next(open_recording(sim_recording).chunks())[0] / 1e9
    assert changes[0][1] == pytest.approx(CHANGE_AT_S - first_byte_s, abs=1e-6)  # host seconds from the first byte


def test_error_table_and_rows_of_a_session_with_truth(trial_session, tmp_path):
    path = tmp_path / "trial.xlsx"
    write_workbook(trial_session, path, t_from=5, t_to=10, rate_hz=50, forced={"hf": {"beta": 0.05}})
    book = load_workbook(path)
    rows = session_values(book["Session"])
    for name, scores in trial_session.evaluate().items():
        assert rows[name][:2] == pytest.approx((scores["incl_rmse_deg"], scores["incl_max_deg"]), rel=1e-15)
    # What the session ran with (the forced settings reach it through load_session, as in the export command).
    assert rows["hf.beta"][0] == trial_session.settings_at_start["hf"]["beta"] == create("hf", {}).settings.beta
    expected = select_rows(trial_session.time_s, 5, 10, 50)
    got = columns(book["Attitude"])
    assert "time (UTC)" not in got  # a dataset has no wall clock
    np.testing.assert_allclose(floats(got["time (s)"]), trial_session.time_s[expected], rtol=1e-15)
    pitch, _, _ = euler_deg(trial_session.quaternion("hf")[expected])
    np.testing.assert_allclose(floats(got["hf pitch (°)"]), pitch, rtol=1e-12, atol=1e-12)
    assert book["Link"].max_row == 1  # no link: the header only
    assert rows["exported rows (count)"][0] == len(expected)


def test_continuation_sheets_hold_every_row_in_order(sim_session, tmp_path):
    path = tmp_path / "split.xlsx"
    sheets = write_workbook(sim_session, path, max_rows=500)
    n = len(sim_session)
    pages = -(-n // 499)
    assert pages == 4  # 1,884 rows: 499 + 499 + 499 + 387
    expected = ["Attitude"] + [f"Attitude ({k})" for k in range(2, pages + 1)]
    assert [s for s in sheets if s.startswith("Attitude")] == expected
    assert [s for s in sheets if s.startswith("Link")] == ["Link"]  # 20 rows fit
    book = load_workbook(path)
    times = []
    for title in expected:
        sheet = book[title]
        assert sheet.max_row <= 500 and [c.value for c in sheet[1]] == ATTITUDE_HEADERS
        times += columns(sheet)["time (s)"]
    np.testing.assert_allclose(floats(times), sim_session.time_s, rtol=1e-15)
    assert [s for s in sheets if s.startswith("Sensors")] == ["Sensors"] + [f"Sensors ({k})" for k in range(2, pages + 1)]


def test_charts_of_pitch_and_roll_read_a_decimated_range(sim_session, tmp_path, monkeypatch):
    monkeypatch.setattr(excel_columns, "CHART_POINTS", 100)
    path = tmp_path / "chart.xlsx"
    write_workbook(sim_session, path)
    book = load_workbook(path)
    charts = book["Chart"]._charts
    assert [c.title.tx.rich.p[0].r[0].t for c in charts] == ["pitch (°)", "roll (°)"]
    assert all(len(c.series) == 3 for c in charts)  # ahf, hf, onboard
    assert "'Chart data'!$B$2:$B$" in charts[0].series[0].yVal.numRef.f  # against time: xVal
    data = columns(book["Chart data"])
    step = -(-len(sim_session) // 100)
    assert len(data["time (s)"]) <= 100
    np.testing.assert_allclose(floats(data["time (s)"]), sim_session.time_s[::step], rtol=1e-15)
    pitch, _, _ = euler_deg(sim_session.quaternion("ahf")[::step])
    np.testing.assert_allclose(floats(data["ahf pitch (°)"]), pitch, rtol=1e-12, atol=1e-12)


def test_a_session_without_raw_imu_samples(tmp_path):
    """"estimated" mode: the aircraft sends its attitude only; no estimator runs on the host."""
    data = load_session(simulated_recording(tmp_path / "estimated.gsrec", duration_s=5, mode="estimated"), exact=True)
    assert data.sample_table == "onboard" and sensor_columns(data) == {}
    path = tmp_path / "estimated.xlsx"
    write_workbook(data, path)
    book = load_workbook(path)
    got = columns(book["Attitude"])
    assert list(got) == ["time (s)", "time (UTC)", "onboard pitch (°)", "onboard roll (°)", "onboard yaw (°)"]
    pitch, _, _ = euler_deg(data.quaternion("onboard"))
    np.testing.assert_allclose(floats(got["onboard pitch (°)"]), pitch, rtol=1e-12, atol=1e-12)
    assert book["Sensors"]["A1"].value == "mag time (s)"  # no IMU block; the other sensors still
    assert all(len(chart.series) == 1 for chart in book["Chart"]._charts)
    assert "Estimator settings" not in session_values(book["Session"])
