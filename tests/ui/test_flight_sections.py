"""The Flight tab (issue 34): a flight log's sections as a flyer reads them in Mission Planner or Flight Review,
desired against actual attitude and rates, battery, GPS and outputs, each plotting every row of its table
(``autopilot.sections``); only the sections the log has; none for the project's own aircraft."""

import numpy as np

from tests.ui.helpers import open_file
from tests.ui.test_replay import flightlog, points
from tests.waiting import LIMIT_MS

COPTER = "arducopter_cubeorange_2023-07-06_10-12-18.bin"
SUB = "ardusub_rov_surface.tlog"


def shown_page(window, qtbot, title):
    live = window.live_view
    tabs = live.tabs
    qtbot.waitUntil(lambda: tabs.isTabVisible(tabs.indexOf(live.flight)), timeout=LIMIT_MS)
    tabs.setCurrentWidget(live.flight)
    button = next(b for b in live.flight.buttons.buttons() if b.text() == title)
    button.click()
    return live.flight


def test_a_dataflash_log_shows_desired_against_actual_and_its_battery_gps_and_outputs(window, qtbot):
    open_file(window, qtbot, flightlog(COPTER), timeout_ms=180000)
    data = window.session.data
    flight = shown_page(window, qtbot, "Attitude")
    assert [b.text() for b in flight.buttons.buttons()] == ["Attitude", "Rates", "Battery", "GPS", "Outputs"]
    desired = next(c for s, c in flight.plots.curves if s.label == "desired" and s.quantity == "roll_deg")
    actual = next(c for s, c in flight.plots.curves if s.label == "actual" and s.quantity == "roll_deg")
    qtbot.waitUntil(lambda: points(desired) >= len(data.tables["attitude_setpoint"]["time_s"]), timeout=LIMIT_MS)
    finite = np.isfinite(desired.yData)
    np.testing.assert_allclose(desired.yData[finite], data.tables["attitude_setpoint"]["roll_deg"], atol=1e-4)
    qtbot.waitUntil(lambda: points(actual) >= len(data.tables["attitude"]["time_s"]), timeout=LIMIT_MS)
    assert next(s for s, _ in flight.plots.curves if s.quantity == "yaw_deg").wraps_at == 360.0  # no line across 0/360
    for title, table, quantity in (("Rates", "rates_setpoint", "pitch_deg_s"), ("Battery", "battery", "voltage_V"),
                                   ("GPS", "gps_quality", "hdop"), ("Outputs", "outputs", "out_1_us")):
        flight = shown_page(window, qtbot, title)
        curve = next(c for s, c in flight.plots.curves if s.quantity == quantity)
        qtbot.waitUntil(lambda: points(curve) >= len(data.tables[table]["time_s"]), timeout=LIMIT_MS)
    assert len(flight.plots.curves) == 14  # RCOU: C1..C14


def test_a_tlog_offers_only_what_it_has_and_a_recording_of_our_aircraft_no_flight_tab(window, qtbot, recording):
    open_file(window, qtbot, flightlog(SUB))
    flight = shown_page(window, qtbot, "Attitude")
    assert "Rates" in [b.text() for b in flight.buttons.buttons()]  # the IMU's gyro: the rates it had
    assert {s.quantity for s, _ in flight.plots.curves if s.label == "desired"} == {"roll_deg", "pitch_deg"}  # no yaw asked
    open_file(window, qtbot, recording)
    tabs = window.live_view.tabs
    qtbot.wait(200)
    assert not tabs.isTabVisible(tabs.indexOf(window.live_view.flight))
