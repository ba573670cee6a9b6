"""The event console lists the session's events with their session times; a click shows that moment."""

import pytest

from groundstation.ui.event_console import event_time_s


def test_events_are_listed_with_their_times_and_a_click_moves_the_view(window, qtbot):
    window.start_demo()
    console, session = window.event_console, window.session
    qtbot.waitUntil(lambda: {"command", "ack", "config"} <= {console.table.item(r, 1).text()
                                                            for r in range(console.table.rowCount())}, timeout=8000)
    events = session.pipeline.events[: console.table.rowCount()]
    assert [console.table.item(r, 1).text() for r in range(len(events))] == [e["kind"] for e in events]
    # The ACK's time is the host time of the chunk that carried it, since the first chunk: the IMU
    # table's host_time_s column measures the same thing for the samples of that chunk.
    ack_row = next(r for r, e in enumerate(events) if e["kind"] == "ack")
    ack = events[ack_row]
    imu = session.pipeline.imu
    host_s = imu.column("host_time_s")
    assert host_s.min() - 0.05 <= event_time_s(session.pipeline, ack) <= host_s.max() + 0.05
    assert console.times() == sorted(console.times())
    qtbot.waitUntil(lambda: window.live_view.series["imu"].end_s > 8.0, timeout=15000)
    t_s = console.times()[ack_row]
    console.table.cellClicked.emit(ack_row, 0)
    low, high = window.live_view.attitude.items[0].getViewBox().viewRange()[0]
    assert window.live_view.paused and (low + high) / 2 == pytest.approx(t_s)
    assert "config" in console.table.item(next(r for r, e in enumerate(events) if e["kind"] == "config"), 1).text()
