"""The Sensors tab plots the magnetometer and the barometer once the session has them."""

import numpy as np

from groundstation.ui.plots import Plot

from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS


def test_magnetometer_and_barometer_appear_on_the_sensors_tab(window, qtbot, recording):
    window.start_demo()  # the demo craft carries a magnetometer and a barometer
    view = window.live_view
    view.tabs.setCurrentWidget(view.sensors)
    qtbot.waitUntil(lambda: len(view.sensors.items) == 4, timeout=LIMIT_MS)
    mag_x = next(c for s, c in view.sensors.curves if s.quantity == "mag_x_uT")
    pressure = next(c for s, c in view.sensors.curves if s.quantity == "baro_pressure_hPa")
    qtbot.waitUntil(lambda: mag_x.xData is not None and len(mag_x.xData) > 20 and pressure.xData is not None, timeout=LIMIT_MS)
    mag, baro = window.session.view.tables["mag_raw"], window.session.view.tables["baro"]
    row = np.flatnonzero(mag.column("time_s") == mag_x.xData[-1])[0]
    assert mag_x.yData[-1] == np.float32(mag.column("mag_x_uT")[row])
    row = np.flatnonzero(baro.column("time_s") == pressure.xData[-1])[0]
    assert pressure.yData[-1] == np.float32(baro.column("pressure_Pa")[row] / 100.0)
    assert [p.title for p in view.sensors._specs] == ["accelerometer", "gyroscope", "magnetometer", "pressure"]
    assert all(isinstance(p, Plot) for p in view.sensors._specs)
    open_file(window, qtbot, recording)  # an IMU-only flight: back to two plots
    assert len(view.sensors.items) == 2
