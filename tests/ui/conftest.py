"""A real main window per test, with its settings and recordings in the test's temporary folder; or one per
module (``module_window``) for tests that only read what it shows of the same opened file."""

import pytest
from PySide6 import QtCore
from pytestqt.qtbot import QtBot

from groundstation.session_makers.factory import Sessions

from groundstation.ui.main_window import MainWindow


def main_window(folder) -> MainWindow:
    settings = QtCore.QSettings(str(folder / "settings.ini"), QtCore.QSettings.Format.IniFormat)
    return MainWindow(settings, Sessions(), recordings_dir=folder / "recordings")


@pytest.fixture
def window(qtbot, tmp_path):
    main = main_window(tmp_path)
    qtbot.addWidget(main)  # closed (and its session stopped) after the test
    main.show()
    return main


@pytest.fixture(scope="module")
def module_qtbot(qapp, request):
    """A qtbot for module fixtures (pytest-qt's own is per test)."""
    return QtBot(request)


@pytest.fixture(scope="module")
def module_window(module_qtbot, tmp_path_factory):
    """One window for a module's tests that each look at a different part of what it shows of one file, which
    takes tens of seconds to open and play; closed (its session stopped) after the module, as qtbot closes a
    test's window."""
    main = main_window(tmp_path_factory.mktemp("window"))
    main.show()
    yield main
    main.close()
    main.deleteLater()


@pytest.fixture(scope="session")
def recording(tmp_path_factory):
    """30 s of simulated flight, as the app would have recorded it from the bridge."""
    from groundstation.cli import main

    path = tmp_path_factory.mktemp("recordings") / "flight.gsrec"
    assert main(["simulate", "--scenario", "flight", "--duration", "30", "--seed", "3", "--out", str(path)]) == 0
    return path
