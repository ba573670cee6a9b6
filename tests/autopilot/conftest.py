"""The real window on a live MAVLink link: UDP on localhost from the simulated aircraft."""

import pytest
from mavlink_helpers import Flying, free_udp_port

from groundstation.sim.mavlink_aircraft import MavlinkAircraft
from groundstation.sim.udp_bridge import UdpBridge


@pytest.fixture
def window(qtbot, tmp_path):
    """A real main window, its settings and recordings in the test's folder."""
    from PySide6 import QtCore

    from groundstation.session_makers.factory import Sessions

    from groundstation.ui.main_window import MainWindow

    settings = QtCore.QSettings(str(tmp_path / "settings.ini"), QtCore.QSettings.Format.IniFormat)
    main = MainWindow(settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(main)
    main.show()
    return main


@pytest.fixture
def mavlink_window(window):
    port = free_udp_port()
    window.connect_serial(f"mavlink:udpin:127.0.0.1:{port}")
    assert not window.banner.isVisible(), window.banner.text()
    with Flying(UdpBridge(MavlinkAircraft(), ("127.0.0.1", port))):
        yield window
