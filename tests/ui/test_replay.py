"""Any file in the window, one way: computed whole by ``load_session`` in a worker (a progress bar
meanwhile), then played back by revealing the computed rows up to a clock. The plots show exactly
the computed session's rows up to the clock; pause, step and seek move the clock and never compute
again; a what-if (an estimator added, a setting changed) computes again and keeps the position;
a bad file is a message in the banner."""

import os
from pathlib import Path

import numpy as np
import pytest

from groundstation import quaternion
from groundstation.session_makers import load as opening
from groundstation.session_makers.load import load_session
from groundstation.estimation import AIDING_ESTIMATOR, live_estimators, runnable
from groundstation.formats import FILE_AIDING
from groundstation.ui.sample_streams import headline

from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS

FLIGHTLOGS = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "flightlogs"
# Small ones, one per format: a 208 s ArduPlane SITL tlog (4 Hz IMU), a 98 s ArduCopter DataFlash log
# (25 Hz IMU), a 9 s PX4 hop (200 Hz IMU).
LOGS = ("arduplane_quadplane_sitl.tlog", "arducopter_cubeorange_2023-07-06_10-12-18.bin", "px4_fmuv5_quad_hop.ulg")


def flightlog(name: str) -> Path:
    path = FLIGHTLOGS / name
    if not path.exists():
        pytest.skip(f"{path} is absent (the shared flight logs, ../shared/datasets/flightlogs)")
    return path


@pytest.fixture
def loads(monkeypatch):
    """Every ``load_session`` the window runs, counted."""
    calls = []

    def counted(*args, **kwargs):
        calls.append(args[1:3])
        return load_session(*args, **kwargs)

    monkeypatch.setattr(opening, "load_session", counted)
    return calls


def pitch_curve(window, name: str):
    return next(c for s, c in window.live_view.attitude.curves if s.quantity == f"{name}_pitch_deg")


def points(curve) -> int:
    return 0 if curve.xData is None else len(curve.xData)  # pyqtgraph keeps None for no data


def pitch_deg(q: np.ndarray) -> np.ndarray:
    return np.degrees(quaternion.to_euler_zyx(q))[:, 1]


def check_plotted_up_to(window, qtbot, data, name: str, t_s: float) -> None:
    """The plotted pitch of ``name`` is the computed session's, from its first row to its last up to ``t_s``
    and none after. A view that is not paused draws the rows that draw each pixel column (``series.per_pixel``,
    tested against every sample in tests/ui/test_series.py), so the rows drawn are some of those, each at its
    own value."""
    rows = data.time_s <= t_s
    curve = pitch_curve(window, name)

    def sampled():  # the curve's points at the session's rows; the others break the line in a gap (NaN)
        return np.isin(curve.xData, data.time_s) if curve.xData is not None else np.zeros(0, dtype=bool)

    def drawn_s():
        return curve.xData[sampled()] if curve.xData is not None else np.empty(0)

    first_s, last_s = data.time_s[rows][[0, -1]]
    qtbot.waitUntil(lambda: len(drawn_s()) and (drawn_s()[0], drawn_s()[-1]) == (first_s, last_s), timeout=LIMIT_MS)
    assert np.isnan(curve.yData[~sampled()]).all()
    drawn = np.searchsorted(data.time_s, drawn_s())  # each drawn point's row
    assert np.all(np.diff(drawn) > 0) and drawn[-1] == np.flatnonzero(rows)[-1]
    expected = pitch_deg(data.quaternion(name)[drawn])
    np.testing.assert_allclose(curve.yData[sampled()], expected, atol=1e-4)  # the plot keeps float32


def test_a_recording_shows_the_rows_load_session_computes(window, qtbot, recording, loads):
    open_file(window, qtbot, recording)
    assert len(loads) == 1 and window.banner.isHidden()
    session, bar = window.session, window.replay_bar
    data = load_session(recording)  # the export's and evaluate's session, computed apart
    assert session.view.filters == data.filters == ("ahf",)
    window.live_view.set_visible("AHF", True)  # one click away (issue 34: not shown at first)
    window.live_view.window_box.setCurrentText("whole session")
    qtbot.waitUntil(lambda: session.source.position_s > 0.5, timeout=LIMIT_MS)

    bar.play_button.click()  # pause: the clock stops
    assert session.source.paused and bar.play_button.text() == "Play"
    paused_at = session.source.position_s
    qtbot.wait(200)
    assert session.source.position_s == paused_at
    shown = len(session.view.imu)
    bar.step_button.click()  # one more sample
    assert len(session.view.imu) == shown + 1 and session.source.position_s == data.time_s[shown]

    bar.speed_box.setCurrentIndex(bar.speed_box.findData(4.0))
    assert session.source.speed == 4.0
    window.seek(20.0)  # forward, then back: the clock moves, nothing is computed again
    check_plotted_up_to(window, qtbot, data, "ahf", 20.0)
    window.seek(7.5)
    check_plotted_up_to(window, qtbot, data, "ahf", 7.5)
    assert window.session is session and window.loading is None and len(loads) == 1
    assert session.source.paused and session.source.speed == 4.0  # kept across the seeks
    shown = session.view.imu.to_dict()
    for column, values in data.tables["imu"].items():  # every column, bit for bit, up to the clock
        np.testing.assert_array_equal(shown[column], values[data.time_s <= 7.5], err_msg=column)
    times = [e.get("session_time_s", e["t_s"]) for e in data.events]
    assert [e["session_time_s"] for e in session.view.events] == sorted(t for t in times if t <= 7.5)

    bar.play_button.click()
    qtbot.waitUntil(lambda: session.source.position_s > 8.5, timeout=LIMIT_MS)  # 4x from 7.5 s
    assert session.view.counters()["frames"] > 0 and window.link_panel.values["frames/s"].text() not in ("—", "")


@pytest.mark.parametrize("name", LOGS)
def test_a_flight_log_opens_plays_seeks_pauses_and_takes_a_what_if(window, qtbot, loads, name):
    path = flightlog(name)
    window.open_recording(path)
    assert window.loading_row.isVisible() and "computing" in window.loading_bar.format()  # progress while computing
    qtbot.waitUntil(lambda: window.loading is None, timeout=LIMIT_MS)
    assert window.banner.isHidden() and not window.loading_row.isVisible()
    session, bar = window.session, window.replay_bar
    filters = runnable(FILE_AIDING, live_estimators())
    assert "ukf" not in filters and "hfm" in filters  # a log is not counted on for GPS aiding
    assert loads == [(None, None)] and session.view.filters == filters  # None: the file's default set (load.estimators_for)
    data = session.data
    assert len(data) > 100 and (data.link is not None) == name.endswith(".tlog")  # a tlog is a link's packets, as recorded
    assert not window.uplink_panel.isEnabled() and not window.estimator_panel.send_button.isEnabled()  # no uplink
    # a tlog's as its recording's: opened whole, at its end, its link has stopped
    assert window.link_panel.headline.text().startswith("STOPPED" if data.link else "NO LINK")
    # the whole flight at once (issue 34): paused at its end, in the whole-session window
    assert session.source.paused and not session.running and window.live_view.window_box.currentText() == "whole session"
    # where the IMU is too slow for host filtering (the quadplane tlog's 4.2 Hz) the host estimators start switched off
    assert (pitch_curve(window, AIDING_ESTIMATOR).isVisible()) != (headline(session.view)[1].startswith("IMU at"))
    window.live_view.set_visible("AHF2", True)
    check_plotted_up_to(window, qtbot, data, AIDING_ESTIMATOR, float(data.time_s[-1]))

    # the slowest speed: at 8x the 8.9 s ULog played to its end (and Pause started it again) within one event-loop pass
    # of a machine at load 20
    bar.speed_box.setCurrentIndex(0)
    bar.play_button.click()  # "Replay": from the start
    qtbot.waitUntil(lambda: not session.source.paused and 0.0 < session.source.position_s, timeout=LIMIT_MS)  # playing
    bar.play_button.click()
    assert session.source.paused
    middle = float(data.time_s[len(data) // 2])
    window.seek(middle)
    check_plotted_up_to(window, qtbot, data, AIDING_ESTIMATOR, middle)
    window.seek(middle / 3)  # back
    check_plotted_up_to(window, qtbot, data, AIDING_ESTIMATOR, middle / 3)
    last = np.flatnonzero(data.time_s <= middle / 3)[-1]  # the horizon shows the newest estimate shown
    shown, _ = headline(session.view)  # AHF2, or the onboard estimate where the IMU is too slow (a 4 Hz tlog)
    assert shown == ("onboard" if name.endswith(".tlog") else AIDING_ESTIMATOR)
    if shown == "onboard":  # its own rows: the newest at or before the clock
        board = data.tables["onboard"]
        at = np.flatnonzero(board["time_s"] <= middle / 3)[-1]
        q = np.array([[board[f"q{c}"][at] for c in "wxyz"]])
    else:
        q = data.quaternion(shown)[last:last + 1]
    newest = f"{pitch_deg(q)[0]:+7.1f}°"
    qtbot.waitUntil(lambda: window.attitude_panel.readouts["pitch"].text() == newest, timeout=LIMIT_MS)
    assert len(loads) == 1  # seeking computed nothing

    window.estimator_panel.shown["cf1"].setChecked(True)  # a what-if: one more estimator
    qtbot.waitUntil(lambda: window.loading is None and "cf1" in window.session.view.filters, timeout=LIMIT_MS)
    assert loads[-1][0] == (*filters, "cf1")
    session = window.session
    assert session.source.position_s == middle / 3 and session.source.paused  # the position kept
    window.live_view.set_visible("CF1", True)
    check_plotted_up_to(window, qtbot, session.data, "cf1", middle / 3)
    alone = load_session(path, ("cf1",))  # the same estimator computed by itself
    np.testing.assert_array_equal(session.data.quaternion("cf1"), alone.quaternion("cf1"))


def test_replay_from_the_end_starts_at_the_start_however_long_the_views_take_to_restart(window, qtbot, recording, monkeypatch):
    """The views start over when the clock goes back (a second for a whole flight on a busy machine): that time was
    counted as playback, so "Replay" at 8x began 8 s in (a 9 s log: at its end again before "Pause" could be clicked)."""
    open_file(window, qtbot, recording)
    session = window.session
    window.seek(session.source.duration_s)
    wall = [1000.0]
    session.source._clock = lambda: wall[0]  # the clock the playback is given (``Playback(clock=...)``)
    restart = window.live_view.set_session

    def slow_restart(s):
        restart(s)
        wall[0] += 5.0  # the views' restart, seen by the playback's clock

    monkeypatch.setattr(window.live_view, "set_session", slow_restart)
    qtbot.waitUntil(lambda: window.replay_bar.play_button.text() == "Replay", timeout=LIMIT_MS)
    window.replay_bar.play_button.click()
    assert session.source.advance() == 0.0 and not session.source.paused


def test_a_log_without_imu_plays_its_onboard_estimate(window, qtbot):
    path = flightlog("arduplane_omnibusf4_ground_pilot_0004.bin")
    open_file(window, qtbot, path)
    session = window.session
    assert session.view.filters == () and session.data.has_onboard()
    assert any("IMU" in e["message"] for e in session.view.events if e["kind"] == "warning")  # said, at 0 s
    assert window.session.source.paused  # opened whole (issue 34)
    window.seek(30.0)
    check_plotted_up_to(window, qtbot, session.data, "onboard", 30.0)
    qtbot.waitUntil(lambda: window.attitude_panel.readouts["pitch"].text() != "—", timeout=LIMIT_MS)


def bad_files(tmp_path: Path) -> list[tuple[Path, str]]:
    """(file, what the banner must say) for a truncated file of each kind, non-logs and unreadable paths."""
    samples = Path(__file__).resolve().parents[2] / "recordings" / "samples"
    cut_gsrec = tmp_path / "cut.gsrec"
    cut_gsrec.write_bytes((samples / "hover-raw.gsrec").read_bytes()[:40])
    text = b"these are not the bytes of a flight log\n" * 20
    cases = [(cut_gsrec, "cut.gsrec"), (tmp_path / "folder.ulg", "folder.ulg"), (tmp_path / "no" / "such.tlog", "such.tlog")]
    (tmp_path / "folder.ulg").mkdir()
    for suffix in (".ulg", ".bin", ".tlog", ".gsrec"):
        (tmp_path / f"text{suffix}").write_bytes(text)
        cases.append((tmp_path / f"text{suffix}", f"text{suffix}"))
    ulg = FLIGHTLOGS / "px4_fmuv5_quad_hop.ulg"
    if ulg.exists():
        (tmp_path / "cut.ulg").write_bytes(ulg.read_bytes()[:3000])
        cases.append((tmp_path / "cut.ulg", "cut.ulg"))
    return cases


def test_bad_files_say_why_in_the_banner(window, qtbot, tmp_path, recording):
    for path, named in bad_files(tmp_path):
        open_file(window, qtbot, recording)
        assert window.session is not None
        open_file(window, qtbot, path)
        text = window.banner.text()
        assert window.banner.isVisible() and named in text and "Traceback" not in text, (path, text)
        assert window.session is None and window.replay_bar.isHidden() and not window.loading_row.isVisible()
    if os.geteuid() != 0:  # root reads any file
        locked = tmp_path / "locked.gsrec"
        locked.write_bytes(recording.read_bytes())
        locked.chmod(0)
        open_file(window, qtbot, locked)
        assert window.banner.isVisible() and "locked.gsrec" in window.banner.text()


def test_a_file_typed_as_the_source_opens_whole(window, qtbot, recording):
    window.connect_serial(str(recording), 115200)
    qtbot.waitUntil(lambda: window.loading is None, timeout=LIMIT_MS)
    assert window.session.source.path == recording and window.replay_bar.isVisible()


def test_the_export_dialog_writes_the_estimators_a_flight_log_is_shown_with(window, qtbot, tmp_path):
    path = flightlog("px4_fmuv5_quad_hop.ulg")
    open_file(window, qtbot, path)
    dialog = window.export()
    qtbot.addWidget(dialog)
    out = tmp_path / "hop.csv"
    dialog.path_edit.setText(str(out))
    dialog.format_box.setCurrentIndex(dialog.format_box.findData(".csv"))
    dialog.path_edit.setText(str(out))
    dialog.export_button.click()
    qtbot.waitUntil(lambda: dialog.job.done, timeout=LIMIT_MS)
    assert dialog.job.error is None, dialog.job.error
    header = out.read_text().splitlines()[0].split(",")
    for name in window.session.view.filters:  # the window's estimators, not the CLI's default
        assert f"{name}_pitch_deg" in header, name


def test_a_tlogs_messages_are_channels_revealed_with_the_clock(window, qtbot):
    path = flightlog("arduplane_quadplane_sitl.tlog")
    open_file(window, qtbot, path)
    view, data = window.live_view, window.session.data
    channel = "vfr_hud.airspeed_m_s"  # a message type of its own: "plot any channel"
    assert channel in {f"{t.name}.{c.name}" for t, c in data.catalogue.channels()}
    view.tabs.setCurrentWidget(view.channels)
    view.channels.add(channel)
    assert window.session.source.paused  # opened whole (issue 34)
    window.seek(120.0)
    curve = next(c for s, c in view.channels.stacked.curves if s.label == channel)
    table = data.tables["vfr_hud"]
    rows = table["time_s"] <= 120.0
    sampled = lambda: np.isin(curve.xData, table["time_s"]) if curve.xData is not None else np.zeros(0, dtype=bool)  # noqa: E731
    qtbot.waitUntil(lambda: sampled().sum() == rows.sum(), timeout=LIMIT_MS)
    assert np.isnan(curve.yData[~sampled()]).all()  # the points that break the line across a gap
    np.testing.assert_array_equal(curve.xData[sampled()], table["time_s"][rows])
    np.testing.assert_array_equal(curve.yData[sampled()], table["airspeed_m_s"][rows].astype(np.float32))


def test_a_dataset_csv_plays_as_a_recording_does(window, qtbot, tmp_path):
    from groundstation.cli import main

    assert main(["simulate", "--scenario", "flight", "--duration", "12", "--seed", "5", "--out", str(tmp_path / "f.bin")]) == 0
    csv = tmp_path / "f.truth.csv.gz"  # the truth and sensor values in the dataset CSV layout
    open_file(window, qtbot, csv)
    data = window.session.data
    assert window.banner.isHidden() and window.session.view.filters[0] == AIDING_ESTIMATOR and data.true_q is not None
    window.live_view.window_box.setCurrentText("whole session")
    window.replay_bar.play_button.click()
    window.seek(6.0)
    check_plotted_up_to(window, qtbot, data, AIDING_ESTIMATOR, 6.0)
    assert window.link_panel.headline.text().startswith("NO LINK")


def test_cancel_while_computing_leaves_no_session(window, qtbot):
    window.open_recording(flightlog("px4_fmuv5_quad_hop.ulg"))
    assert window.loading_row.isVisible()
    loading = window.loading
    window.loading_cancel.click()
    assert window.loading is None and not window.loading_row.isVisible()
    loading.wait(30)  # the worker ends (or is dropped); nothing is adopted
    qtbot.wait(200)
    assert window.session is None and window.banner.isHidden()


def test_a_file_opened_after_the_live_view_was_paused_draws(window, qtbot, recording):
    """Issue 34: after "Pause view" in a live session, a replay showed blank plots until "Resume view"."""
    window.start_demo()
    window.live_view.pause_button.click()
    assert window.live_view.paused
    open_file(window, qtbot, recording)
    assert not window.live_view.paused and window.live_view.pause_button.text() == "Pause view"
    qtbot.waitUntil(lambda: any(points(curve) for _, curve in window.live_view.attitude.curves), timeout=10000)
