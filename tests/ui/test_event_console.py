"""The event console lists the session's events with their session times; a click shows that moment."""

import pytest

from groundstation.session.view import event_session_time_s
from tests.waiting import LIMIT_MS


def test_events_are_listed_with_their_times_and_a_click_moves_the_view(window, qtbot):
    window.start_demo()
    console, session = window.event_console, window.session
    qtbot.waitUntil(lambda: {"command", "ack", "config"} <= {console.table.item(r, 1).text()
                                                            for r in range(console.table.rowCount())}, timeout=LIMIT_MS)
    events = session.view.events[: console.table.rowCount()]
    assert [console.table.item(r, 1).text() for r in range(len(events))] == [e["kind"] for e in events]
    # The ACK's time is the host time of the chunk that carried it, since the first chunk: the IMU
    # table's host_time_s column measures the same thing for the samples of that chunk.
    ack_row = next(r for r, e in enumerate(events) if e["kind"] == "ack")
    ack = events[ack_row]
    imu = session.view.imu
    host_s = imu.column("host_time_s")
    assert host_s.min() - 0.05 <= event_session_time_s(session.view, ack) <= host_s.max() + 0.05
    assert console.times() == sorted(console.times())
    qtbot.waitUntil(lambda: window.live_view.series["imu"].end_s > 8.0, timeout=LIMIT_MS)
    t_s = console.times()[ack_row]
    console.table.cellClicked.emit(ack_row, 0)
    low, high = window.live_view.attitude.items[0].getViewBox().viewRange()[0]
    assert window.live_view.paused and (low + high) / 2 == pytest.approx(t_s)
    assert "config" in console.table.item(next(r for r, e in enumerate(events) if e["kind"] == "config"), 1).text()


def test_an_event_late_in_the_session_is_placed_at_its_time_not_at_the_start(window, qtbot):
    """Events without a clock time are placed by host time since the session's first chunk (the
    pipeline's public ``t0_host_ns``); the IMU table's host_time_s column is the independent measure."""
    window.start_demo()
    session = window.session
    qtbot.waitUntil(lambda: len(session.view.imu) > 250, timeout=LIMIT_MS)
    session.send_command("request_config")
    command = next(e for e in reversed(session.view.events) if e["kind"] == "command")
    host_s = session.view.imu.column("host_time_s")[-1]
    assert event_session_time_s(session.view, command) == pytest.approx(host_s, abs=0.3)


def test_an_events_flags_read_as_words_and_missing_values_are_left_out():
    """Issue 34: the console showed "severity None" and "armed True"."""
    from groundstation.ui.event_console import describe

    assert describe({"kind": "mode", "t_host_ns": 5, "mode": "RTL", "armed": True, "severity": None}) == "mode RTL, armed"
    assert describe({"kind": "mode", "mode": "LOITER", "armed": False}) == "mode LOITER, not armed"
