"""The live window's redraw does the work a person can see (issue 35): the tabs not in sight draw nothing;
a frame that reaches no new pixel column of the plots draws nothing (the rows wait in their tables)."""

import numpy as np

from tests.waiting import LIMIT_MS


def test_only_the_tab_in_sight_draws_and_only_when_the_data_reaches_a_new_pixel_column(window, qtbot):
    window.start_demo()
    view = window.live_view
    calls = {}
    for name in ("sensors", "heading", "diagnostics", "channels"):
        plots = getattr(view, name)
        draw = plots.draw
        plots.draw = lambda *args, name=name, draw=draw, **kw: (calls.__setitem__(name, calls.get(name, 0) + 1), draw(*args, **kw))
    frames = view.frames_drawn
    qtbot.waitUntil(lambda: view.frames_drawn - frames >= 20, timeout=LIMIT_MS)
    assert calls == {}  # the Attitude tab in sight
    view.window_box.setCurrentText("10 min")  # a pixel column is about 0.8 s of data: one every 24 ticks
    ticks, frames = window.ticks, view.frames_drawn
    qtbot.waitUntil(lambda: window.ticks - ticks >= 90, timeout=LIMIT_MS)
    assert 0 < view.frames_drawn - frames <= (window.ticks - ticks) // 3
    curve = next(c for s, c in view.attitude.curves if s.quantity == "ahf2_pitch_deg")
    box = view.attitude.items[0].getViewBox()
    pixel_s = (box.viewRange()[0][1] - box.viewRange()[0][0]) / box.width()
    with window.session.lock:
        newest_s = float(window.session.view.imu.tail(1)[0, 0])
    assert view.attitude.drawn(curve)[0][-1] >= newest_s - 2 * pixel_s - 0.1  # behind by a column (and a tick) at most
    every_t = view.series["imu"].data("ahf2_pitch_deg", 600.0)[0]
    assert len(curve.xData) < len(every_t) / 4  # the samples that draw each pixel column (tests/ui/test_series.py)
    view.pause_button.setChecked(True)  # to zoom in: every sample
    np.testing.assert_array_equal(curve.xData, view.series["imu"].data("ahf2_pitch_deg", 600.0)[0])
    view.pause_button.setChecked(False)
    view.tabs.setCurrentWidget(view.diagnostics)
    frames = view.frames_drawn
    qtbot.waitUntil(lambda: view.frames_drawn - frames >= 2, timeout=LIMIT_MS)
    assert set(calls) == {"diagnostics"}
