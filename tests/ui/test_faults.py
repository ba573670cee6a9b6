"""Bad inputs show a message in the window, never an exception."""


def test_missing_or_damaged_recording_shows_a_message(window, tmp_path):
    window.open_recording(tmp_path / "missing.gsrec")
    assert window.banner.isVisible() and "no such file" in window.banner.text()
    damaged = tmp_path / "damaged.gsrec"
    damaged.write_bytes(b"this is not a recording at all" * 10)
    window.open_recording(damaged)
    assert window.banner.isVisible() and "damaged.gsrec" in window.banner.text()
    assert window.session is None


def test_a_port_that_cannot_be_opened_shows_why(window):
    window.connect_serial("/dev/no-such-serial-port", 115200)
    assert window.banner.isVisible() and "/dev/no-such-serial-port" in window.banner.text()
    assert window.session is None
