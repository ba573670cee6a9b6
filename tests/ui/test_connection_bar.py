"""Defect 4 of issue 12: the source box takes every string ``open_source`` accepts, lists the ports found
(description, VID:PID) and the recent sources, and a refresh never changes what the user typed or picked."""

import pytest
from PySide6 import QtCore, QtWidgets

from groundstation.sources import SourceError, open_source
from groundstation.ui import connection_bar
from groundstation.session_makers.factory import Sessions
from groundstation.ui.main_window import MainWindow

FTDI = {"device": "/dev/ttyUSB7", "description": "FT232R USB UART", "vid_pid": "0403:6001"}
CP210X = {"device": "/dev/ttyUSB8", "description": "CP2102 USB to UART", "vid_pid": "10C4:EA60"}


@pytest.fixture
def ports(monkeypatch):
    """The ports pyserial finds: a list the test changes, as devices are plugged in and out (no USB here)."""
    found = []
    monkeypatch.setattr(connection_bar, "list_ports", lambda: [dict(p) for p in found])
    return found


def type_source(qtbot, window, text):
    box = window.bar.port_box
    box.lineEdit().clear()
    qtbot.keyClicks(box.lineEdit(), text)
    return box


def test_a_typed_sim_source_connects_and_is_remembered_as_recent(qtbot, ports, window, tmp_path):
    type_source(qtbot, window, "sim:?seed=4")
    qtbot.mouseClick(window.bar.connect_button, QtCore.Qt.LeftButton)
    assert window.session is not None and not window.banner.isVisible()
    assert "sim" in window.source_label.text().lower()
    assert window.bar.listed() == ["sim:?seed=4"]
    window.disconnect()
    again = MainWindow(window.settings, Sessions(), recordings_dir=tmp_path / "recordings")  # the next start of the app
    qtbot.addWidget(again)
    assert again.bar.listed() == ["sim:?seed=4"] and again.bar.source == "sim:?seed=4"


def test_return_in_the_box_connects(qtbot, window):
    box = type_source(qtbot, window, "sim:")
    qtbot.keyClick(box.lineEdit(), QtCore.Qt.Key_Return)
    assert window.session is not None


@pytest.mark.parametrize("garbled", ["udp://nohost", "sim:?seed=x&seed=y", "bogus://x", "no/such/file.gsrec"])
def test_a_garbled_source_shows_open_sources_message_in_the_banner(qtbot, ports, window, garbled):
    with pytest.raises(SourceError) as expected:
        open_source(garbled)
    type_source(qtbot, window, garbled)
    qtbot.mouseClick(window.bar.connect_button, QtCore.Qt.LeftButton)
    assert window.session is None
    assert window.banner.isVisible() and str(expected.value) in window.banner.text()
    assert window.bar.listed() == []  # a source that did not open is not offered again


def test_ports_are_listed_with_description_and_vid_pid_and_picking_one_gives_its_device(qtbot, ports):
    ports.append(FTDI)
    bar = connection_bar.ConnectionBar()
    qtbot.addWidget(bar)
    assert bar.port_box.itemText(0) == "/dev/ttyUSB7 — FT232R USB UART, 0403:6001"
    bar.port_box.activated.emit(0)  # what a click on the line in the open list sends
    assert bar.source == "/dev/ttyUSB7"
    with qtbot.waitSignal(bar.connectRequested) as asked:
        qtbot.mouseClick(bar.connect_button, QtCore.Qt.LeftButton)
    assert asked.args == ["/dev/ttyUSB7", 0]  # baud "auto": the source's own default


def test_devices_coming_and_going_never_change_what_the_user_typed_or_picked(qtbot, ports):
    bar = connection_bar.ConnectionBar()
    qtbot.addWidget(bar)
    bar.set_recent(["udp://0.0.0.0:9000"])
    qtbot.keyClicks(bar.port_box.lineEdit(), "socket://192.168.4.1:88")
    ports.append(FTDI)  # plugged in while the user types
    bar.refresh_ports()
    assert bar.source == "socket://192.168.4.1:88"
    assert bar.port_box.lineEdit().cursorPosition() == len("socket://192.168.4.1:88")
    assert bar.listed() == ["/dev/ttyUSB7", "udp://0.0.0.0:9000"]
    bar.port_box.activated.emit(0)
    ports.append(CP210X)  # another device
    bar.refresh_ports()
    assert bar.source == "/dev/ttyUSB7" and bar.listed() == ["/dev/ttyUSB7", "/dev/ttyUSB8", "udp://0.0.0.0:9000"]
    ports.clear()  # the chosen one unplugged: still what the user asked for
    bar.refresh_ports()
    assert bar.source == "/dev/ttyUSB7" and bar.listed() == ["udp://0.0.0.0:9000"]
    assert bar.connect_button.isEnabled()


def test_the_source_box_says_every_registered_source_form(qtbot, ports):
    """Its tooltip lists each scheme of ``sources.spec.SCHEMES`` with its forms and what it is; its placeholder
    each scheme's commonest forms: from the registry, not a copy."""
    from groundstation.sources import SCHEMES

    bar = connection_bar.ConnectionBar()
    qtbot.addWidget(bar)
    for scheme in SCHEMES.values():
        assert f"{', '.join(scheme.forms)}  —  {scheme.what}" in bar.port_box.toolTip()
        assert scheme.forms[0] in bar.port_box.lineEdit().placeholderText()
