"""A re-plugged USB adapter that comes back under another name is found again by VID:PID and serial number.

The bytes go through a real pseudo-terminal (the simulated bridge in process, whose drop-outs give
each return a new /dev/pts/N, as Windows gives a new COMn). No USB device can exist here, so the one
fake is the port list (``serial.tools.list_ports.comports``'s answer): real ``ListPortInfo`` entries
naming the bridge's current pty with a USB identity, injected through ``SerialSource(list_ports=)``.
"""

import os
import threading

import pytest
from serial.tools.list_ports_common import ListPortInfo

from groundstation.session_makers.live import LiveSession
from groundstation.session_makers.pipeline import Pipeline
from groundstation.sim.link import LinkSettings
from groundstation.sim.stream import Scenario, SimStream
from groundstation.sources import SerialSource
from tests.waiting import wait_for

pytestmark = pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals are POSIX only")
FTDI = (0x0403, 0x6001)


def usb_port(device: str, serial_number: str | None = "A50285BI", vid_pid=FTDI) -> ListPortInfo:
    info = ListPortInfo(device, skip_link_detection=True)
    info.vid, info.pid = vid_pid
    info.serial_number = serial_number
    return info


def test_a_session_follows_its_adapter_to_a_new_name(tmp_path):
    from groundstation.sim.pty_bridge import PtyBridge

    link = LinkSettings(dropout_every_s=2.0, dropout_s=0.5)
    bridge = PtyBridge(SimStream(Scenario("hover", 60.0, seed=5, link=link)))
    first = bridge.slave_path
    held = os.open(first, os.O_RDWR | os.O_NOCTTY)  # the old name stays taken, so the new one differs
    other_adapter = usb_port("/dev/ttyS9", "OTHER")  # same VID:PID, another serial number: never chosen
    ports = lambda: [other_adapter, usb_port(bridge.slave_path)]  # noqa: E731 - what comports() would say now
    stop = threading.Event()
    thread = threading.Thread(target=bridge.run, args=(stop.is_set,), daemon=True)
    thread.start()
    try:
        source = SerialSource(first, list_ports=ports)
        assert source.usb_identity == (*FTDI, "A50285BI")
        with LiveSession(source, Pipeline(("ahf",)), recordings_dir=tmp_path) as session:
            wait_for(lambda: any(e["kind"] == "reconnected" for e in session.pipeline.events), what="reconnected")
            rows = len(session.pipeline.imu)
            wait_for(lambda: len(session.pipeline.imu) >= rows + 50, what="data after reconnecting")
    finally:
        stop.set()
        thread.join()
        bridge.close()
        os.close(held)
    reconnected = next(e for e in session.pipeline.events if e["kind"] == "reconnected")
    assert source.port_name != first and source.port_name.startswith("/dev/pts/")
    assert reconnected["source"] == f"{source.port_name} @ 115200 baud"  # the event says where it went


def test_the_name_is_kept_while_listed_and_never_guessed_between_two_adapters(tmp_path):
    master, slave = os.openpty()
    name = os.ttyname(slave)
    try:
        listed = [usb_port(name, None)]
        source = SerialSource(name, list_ports=lambda: listed)
        assert source.current_name() == name  # still there: reopen the same name (a busy port, not a new one)
        listed[:] = [usb_port("/dev/ttyUSB1", None)]
        assert source.current_name() == "/dev/ttyUSB1"  # gone; one adapter with that VID:PID and no serial number
        listed[:] = [usb_port("/dev/ttyUSB1", None), usb_port("/dev/ttyUSB2", None)]
        assert source.current_name() == name  # two candidates: keep waiting for our own name
        listed[:] = [usb_port("/dev/ttyUSB3", None, vid_pid=(0x1A86, 0x7523))]
        assert source.current_name() == name  # another kind of adapter is not ours
        source.close()
        not_usb = SerialSource(name, list_ports=lambda: [ListPortInfo(name, skip_link_detection=True)])
        assert not_usb.usb_identity is None and not_usb.current_name() == name
        not_usb.close()
    finally:
        os.close(master)
        os.close(slave)
