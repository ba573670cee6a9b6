"""A real main window per test, with its settings and recordings in the test's temporary folder."""

import pytest
from PySide6 import QtCore

from groundstation.session_makers.factory import Sessions

from groundstation.ui.main_window import MainWindow


@pytest.fixture
def window(qtbot, tmp_path):
    settings = QtCore.QSettings(str(tmp_path / "settings.ini"), QtCore.QSettings.Format.IniFormat)
    main = MainWindow(settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(main)  # closed (and its session stopped) after the test
    main.show()
    return main


@pytest.fixture(scope="session")
def recording(tmp_path_factory):
    """30 s of simulated flight, as the app would have recorded it from the bridge."""
    from groundstation.cli import main

    path = tmp_path_factory.mktemp("recordings") / "flight.gsrec"
    assert main(["simulate", "--scenario", "flight", "--duration", "30", "--seed", "3", "--out", str(path)]) == 0
    return path
