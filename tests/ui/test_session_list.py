"""Several sessions in one window (issue 34, the teacher): two simulated boards and yesterday's recording,
listed in the Sessions panel, their channels named by session and plotted on one time axis, each board
recorded completely and each recording and file exportable; the window's own session as before."""

import numpy as np

from firmware_protocol import StreamDecoder
from groundstation.recording import open_recording
from groundstation.ui.channels import PREFIX

from tests.ui.helpers import export_csv
from tests.waiting import LIMIT_MS


def decoded_frames(path) -> dict[str, int]:
    """Frames of each type in a recording, decoded afresh (the recording's own chunks, a new decoder)."""
    decoder = StreamDecoder()
    counts: dict[str, int] = {}
    for t_host_ns, data in open_recording(path).chunks():
        for frame in decoder.feed(data, t_host_ns):
            counts[frame.type.name] = counts.get(frame.type.name, 0) + 1
    return counts


def arrivals(session):
    """Session time and host arrival time (ns, monotonic) of each IMU sample of a live session."""
    with session.lock:
        imu = session.view.imu
        rows = imu.tail(len(imu))
    return rows[:, imu.columns.index("time_s")], session.view.t0_host_ns + rows[:, imu.columns.index("host_time_s")] * 1e9


def test_two_boards_and_a_recording_on_one_time_axis(window, qtbot, recording, tmp_path):
    panel = window.session_list
    window.start_demo()
    first = window.session
    qtbot.waitUntil(lambda: len(first.view.imu) > 200, timeout=LIMIT_MS)  # the window's board has flown a while
    board = panel.add_source("sim:?seed=7")
    assert board is not None and board.label == "S2"
    log = panel.add_file(recording)
    qtbot.waitUntil(lambda: log.session is not None and log.offset_s is not None, timeout=LIMIT_MS)
    assert log.label == "S3" and log.offset_s == 0.0  # a file from its start
    # Wall time: samples of the two boards that arrived together are at the same place on the axis.
    qtbot.waitUntil(lambda: board.offset_s is not None, timeout=LIMIT_MS)
    (t1, host1), (t2, host2) = (arrivals(s) for s in (first, board.session))
    nearest = np.clip(np.searchsorted(host1, host2[-200:]), 0, len(host1) - 1)
    assert np.median(np.abs(t2[-200:] + board.offset_s - t1[nearest])) < 0.05
    assert [panel.tree.topLevelItem(i).text(0) for i in range(3)] == ["main", "S2", "S3"]

    # Channels named by session, plotted in one pane on one axis.
    channels = window.live_view.channels
    window.live_view.tabs.setCurrentWidget(channels)
    listed = {channels.tree.topLevelItem(i).text(0) for i in range(channels.tree.topLevelItemCount())}
    assert {"imu", "S2:imu", "S3:imu"} <= listed
    for name in ("imu.acc_z_g", "S2:imu.acc_z_g", "S3:imu.acc_z_g"):
        channels.add(name)
    qtbot.waitUntil(lambda: all(len(channels.stacked.drawn(c)[0]) > 50 for _, c in channels.stacked.curves), timeout=LIMIT_MS)
    times = {spec.label: channels.stacked.drawn(curve)[0] for spec, curve in channels.stacked.curves}
    s2_table = board.session.view.imu
    with board.session.lock:
        s2_first_s = s2_table.tail(len(s2_table))[0, s2_table.columns.index("time_s")]
    assert channels.series[PREFIX + "S2:imu"].start_s == s2_first_s + board.offset_s
    # The file, revealed along the window's board: up to its present, from its own 0.
    s3 = channels.series[PREFIX + "S3:imu"]
    assert s3.start_s < 0.1 and s3.end_s <= times["imu.acc_z_g"][-1] + 0.1
    assert log.session.source.position_s > 0

    # The other sessions' attitude on the Attitude tab, each in its own pen style.
    window.live_view.tabs.setCurrentWidget(window.live_view.attitude)
    styles = {spec.label: curve.opts["pen"].style() for spec, curve in window.live_view.attitude.curves}
    assert {"S2 AHF2", "S2 onboard", "S3 onboard"} <= set(styles)
    assert len({styles["AHF2"], styles["S2 AHF2"], styles["S3 onboard"]}) == 3
    qtbot.waitUntil(lambda: any(len(window.live_view.attitude.drawn(c)[0]) for s, c in window.live_view.attitude.curves
                                if s.label == "S2 AHF2"), timeout=LIMIT_MS)

    # Stopped: each board's recording holds every frame its session decoded, and each exports whole.
    qtbot.waitUntil(lambda: len(board.session.view.imu) > 300, timeout=LIMIT_MS)
    frames = {"main": first.view.counters, "S2": board.session.view.counters}
    window.disconnect()
    panel.remove(board)
    assert [panel.tree.topLevelItem(i).text(0) for i in range(panel.tree.topLevelItemCount())] == ["main", "S3"]
    for name, session in (("main", first), ("S2", board.session)):
        counts = decoded_frames(session.recording_path)
        assert sum(counts.values()) == frames[name]()["frames"] > 500, name
    window.last_file = None
    assert panel.add_source(str(first.recording_path)) is not None  # a recording named: opened whole, as S4
    s2_again = panel.add_file(board.session.recording_path)
    qtbot.waitUntil(lambda: all(e.session is not None for e in panel.entries), timeout=LIMIT_MS)
    for row, path in ((2, first.recording_path), (3, board.session.recording_path), (1, recording)):
        table = export_csv(window, qtbot, panel, row, tmp_path / f"{row}.csv")
        assert len(table) == decoded_frames(path)["IMU_RAW"], path
        assert np.all(np.diff(table["time_s"]) > 0)
    assert s2_again.label == "S5"


def test_a_file_beside_a_file_plays_along_with_it(window, qtbot, recording):
    """Two recordings on one axis, both from their start: the added one follows the window's playback,
    its seeks back too (its curves start over, not left ahead of the clock)."""
    from tests.ui.helpers import open_file

    open_file(window, qtbot, recording)
    if not window.session.source.paused:
        window.replay_bar.play_button.click()  # paused: the clock stays where the seeks put it
    window.seek(20.0)
    other = window.session_list.add_file(recording)
    qtbot.waitUntil(lambda: other.session is not None and other.offset_s == 0.0, timeout=LIMIT_MS)
    window.tick()
    assert other.session.source.position_s == window.session.source.position_s == 20.0
    channels = window.live_view.channels
    window.live_view.tabs.setCurrentWidget(channels)
    channels.add("S2:imu.acc_z_g")
    window.tick()
    series = channels.series[PREFIX + "S2:imu"]
    assert 19.0 < series.end_s <= window.session.source.position_s + 0.1
    window.seek(5.0)
    window.tick()
    assert other.session.source.position_s == window.session.source.position_s
    window.tick()
    again = channels.series[PREFIX + "S2:imu"]
    assert again is not series and again.end_s <= 5.0 + 0.1  # started over at the new position


def test_a_bad_source_is_said_in_one_line_and_the_next_good_one_clears_it(window, qtbot):
    panel = window.session_list
    assert panel.add_source("sim:?seed=2/tmp/flight.gsrec") is None  # a path typed after the offered source
    assert window.banner.isVisible() and "option seed: not an integer" in window.banner.text()
    assert "\n" not in window.banner.text() and panel.entries == []
    board = panel.add_source("sim:?seed=2")
    assert board is not None and not window.banner.isVisible()
    panel.remove(board)
    assert not board.session.running and panel.entries == []
