"""Two app windows at once (issue 34, the teacher with two boards): each has settings of its own, so
neither overwrites the other's when it closes; a second window starts from the first one's settings."""

from PySide6 import QtCore

from groundstation.session_makers.factory import Sessions
from groundstation.ui.main_window import MainWindow
from groundstation.ui.window_settings import window_settings


def ini(folder):
    return lambda name: QtCore.QSettings(str(folder / f"{name}.ini"), QtCore.QSettings.Format.IniFormat)


def open_window(qtbot, folder, tmp_path):
    settings, claim = window_settings(ini(folder))
    window = MainWindow(settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(window)
    window.show()
    return window, claim


def test_two_windows_keep_their_own_settings(qtbot, tmp_path):
    folder = tmp_path / "config"  # not there yet, as on a first start
    first_settings = ini(folder)("groundstation")  # QSettings makes the folder as it writes
    first_settings.setValue("foxglove_port", 9100)  # what the user had before
    first_settings.sync()
    del first_settings
    first, first_claim = open_window(qtbot, folder, tmp_path)
    second, second_claim = open_window(qtbot, folder, tmp_path)
    assert first_claim.slot == 1 and second_claim.slot == 2
    assert first.settings.fileName() != second.settings.fileName()
    assert int(second.settings.value("foxglove_port")) == 9100  # started from the first window's
    assert first_claim.title("groundstation") == "groundstation"
    assert second_claim.title("groundstation") == "groundstation (window 2)"
    first.live_view.window_box.setCurrentText("10 s")
    second.live_view.window_box.setCurrentText("10 min")
    second.foxglove.set_port(9200)
    second.close()  # the second closes first, the first last: nothing of the second's is lost
    second_claim.release()
    first.close()
    first_claim.release()
    one, two = ini(folder)("groundstation"), ini(folder)("groundstation-2")
    assert one.value("time_window") == "10 s" and int(one.value("foxglove_port")) == 9100
    assert two.value("time_window") == "10 min" and int(two.value("foxglove_port")) == 9200
    again, claim = open_window(qtbot, folder, tmp_path)  # both closed: the next window is the first again
    assert claim.slot == 1 and again.live_view.window_box.currentText() == "10 s"
    claim.release()
