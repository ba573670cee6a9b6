"""Issue 24, defect 4 (persona 2: an ArduPilot user with SITL or a SiK radio): MAVLink arriving on a source
opened for the project's bridge (QGroundControl's habit, ``udp://…:14550``) is recognised and the window
opens the same port as ``mavlink:``, and says so; the project's own bridge on the same kind of source is not."""

import socket
import subprocess
import sys

import pytest
from PySide6 import QtCore

from groundstation.sources.sniff import as_mavlink, mavlink_packets
from tests.ui.test_first_session import type_in_source_box
from tests.waiting import LIMIT_MS


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.fixture
def sitl_on_udp():
    """``bridge-sim --mavlink --udp``: an ArduPilot-like copter sending MAVLink 2 datagrams, as SITL does."""
    port = free_udp_port()
    process = subprocess.Popen([sys.executable, "-m", "groundstation", "bridge-sim", "--mavlink", "--udp", f"127.0.0.1:{port}",
                                "--scenario", "hover", "--seed", "4"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    yield port
    process.terminate()
    process.wait(timeout=10)


def test_mavlink_on_a_udp_bridge_source_is_opened_as_mavlink(window, qtbot, sitl_on_udp):
    typed = f"udp://127.0.0.1:{sitl_on_udp}"
    type_in_source_box(qtbot, window, typed)
    qtbot.keyClick(window.bar.port_box.lineEdit(), QtCore.Qt.Key_Return)
    qtbot.waitUntil(lambda: window.session is not None and window.session.view.protocol == "mavlink", timeout=LIMIT_MS)
    assert window.bar.source == f"mavlink:udpin:127.0.0.1:{sitl_on_udp}"
    assert f"MAVLink heard on {typed}" in window.source_label.text()
    qtbot.waitUntil(lambda: len(window.session.view.onboard) > 2, timeout=LIMIT_MS)  # its attitude arrives
    assert not window.banner.isVisible()


def test_the_projects_own_bridge_is_never_taken_for_mavlink(window, qtbot):
    type_in_source_box(qtbot, window, "sim:?seed=6&ber=1e-3")  # bit errors: CRC failures, no frame of MAVLink
    qtbot.keyClick(window.bar.port_box.lineEdit(), QtCore.Qt.Key_Return)
    session = window.session
    qtbot.waitUntil(lambda: len(session.view.imu) > 100, timeout=LIMIT_MS)
    assert session.heard_protocol is None and window.session is session


def test_the_mavlink_spec_of_each_port_form():
    assert as_mavlink("udp://0.0.0.0:14550") == "mavlink:udpin:0.0.0.0:14550"
    assert as_mavlink("tcp://127.0.0.1:5760") == "mavlink:tcp:127.0.0.1:5760"
    assert as_mavlink("/dev/ttyUSB0", 57600) == "mavlink:/dev/ttyUSB0?baud=57600"
    assert as_mavlink("/dev/ttyUSB0?baud=921600", 115200) == "mavlink:/dev/ttyUSB0?baud=921600"
    assert as_mavlink("sim:") is None


def test_pymavlinks_own_packets_are_counted():
    """The oracle: packets pymavlink itself encodes, whole and then cut."""
    from pymavlink.dialects.v20 import ardupilotmega as mavlink

    sender = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    beat = sender.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, 0).pack(sender)
    attitude = sender.attitude_encode(1000, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0).pack(sender)
    assert mavlink_packets(beat + attitude) == 2
    assert mavlink_packets((beat + attitude)[:-3]) == 1
    assert mavlink_packets(bytes(range(256)) * 8) == 0
