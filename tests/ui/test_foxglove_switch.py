"""File > Serve live session to Foxglove: a client receives the window's live session while it is on;
off, the server is gone; a port already taken is said in the banner and the switch goes back off."""

import socket

import pytest

from tests.foxglove_client import Client, decoded
from tests.waiting import LIMIT_MS


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_the_switch_serves_the_live_session(window, qtbot):
    port = free_port()
    window.settings.setValue("foxglove_port", port)
    window.start_demo()
    window.foxglove.action.trigger()
    assert window.foxglove.action.isChecked()
    assert window.foxglove_label.text().startswith(f"Foxglove: ws://127.0.0.1:{port}")
    client = Client(port)
    try:
        assert client.ready.wait(10)
        qtbot.waitUntil(lambda: len(client.messages.get("/imu", [])) > 100, timeout=LIMIT_MS)
        times = [row.time_s for row in decoded(client, "/imu")]
        assert times == sorted(times) and len(set(times)) == len(times)  # in order, none twice
    finally:
        window.foxglove.action.trigger()
        client.stop.set()
        client.thread.join(5)
    assert not window.foxglove.action.isChecked() and window.foxglove.bridge is None
    with pytest.raises(ConnectionRefusedError):  # nobody serves on the port any more
        socket.create_connection(("127.0.0.1", port), timeout=30).close()
    window.foxglove.action.trigger()  # and the switch serves on it again
    assert window.foxglove.action.isChecked() and not window.banner.isVisible()
    window.foxglove.action.trigger()


def test_a_taken_port_is_said_and_the_next_free_one_served(window, qtbot):
    """A second window (or session) asking for the port a first one serves on (issue 34): the next free
    port, said in the banner, instead of "Address already in use" and nothing served."""
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        busy = taken.getsockname()[1]
        window.settings.setValue("foxglove_port", busy)
        window.start_demo()
        window.foxglove.action.trigger()
        try:
            assert window.foxglove.action.isChecked()
            served = window.foxglove.bridge.port
            assert served > busy
            assert window.banner.isVisible() and f"port {busy} is taken" in window.banner.text()
            assert f"serving on {served}" in window.banner.text()
            assert window.foxglove_label.text().startswith(f"Foxglove: ws://127.0.0.1:{served}")
            client = Client(served)
            try:
                assert client.ready.wait(10)
            finally:
                client.stop.set()
                client.thread.join(5)
        finally:
            window.foxglove.action.trigger()
    assert window.foxglove.bridge is None


def test_the_port_is_chosen_in_a_dialog_and_remembered(window, qtbot):
    window.start_demo()
    window.foxglove.action.trigger()
    port = free_port()
    try:
        dialog = window.foxglove.choose_port()
        dialog.setIntValue(port)
        dialog.accept()
        assert window.foxglove.bridge.port == port  # served there at once
        assert int(window.settings.value("foxglove_port")) == port
    finally:
        window.foxglove.action.trigger()
