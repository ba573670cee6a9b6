"""``groundstation app`` as the README's first command runs it: a real process on the simulated bridge."""

import os
import subprocess
import sys
import time

import pytest

from groundstation.recording import open_recording


def app_process(tmp_path, *args, **env):
    environment = {**os.environ, "GROUNDSTATION_RECORDINGS": str(tmp_path / "recordings"),
                   "XDG_CONFIG_HOME": str(tmp_path / "config"), **env}  # QSettings' folder on Linux
    environment = {k: v for k, v in environment.items() if v is not None}
    return subprocess.Popen([sys.executable, "-m", "groundstation", "app", *args], env=environment,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def recorded(tmp_path, size: int) -> bool:
    recordings = list((tmp_path / "recordings").glob("*.gsrec"))
    return len(recordings) == 1 and recordings[0].stat().st_size > size


def test_app_demo_streams_and_records(tmp_path):
    process = app_process(tmp_path, "--demo")
    try:
        deadline = time.monotonic() + 30  # starting Qt on a loaded machine takes seconds
        while time.monotonic() < deadline and not recorded(tmp_path, 20_000):  # some 4 s of the 100 Hz link
            assert process.poll() is None, process.communicate()
            time.sleep(0.2)
        assert recorded(tmp_path, 20_000) and process.poll() is None
    finally:
        process.terminate()  # as Ctrl-C: the window closes, the session stops
        _, stderr = process.communicate(timeout=30)  # closing waits for the reader thread; a loaded machine is slow
    assert process.returncode == 0 and "Traceback" not in stderr
    recording = open_recording(next((tmp_path / "recordings").glob("*.gsrec")))
    assert recording.closed_cleanly and sum(len(data) for _, data in recording.chunks()) > 10_000  # some 2 s of the link


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="only X11/Wayland need a display variable")
def test_without_a_display_it_says_so(tmp_path):
    process = app_process(tmp_path, DISPLAY=None, WAYLAND_DISPLAY=None, QT_QPA_PLATFORM=None)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 2 and "no display" in stderr and "Traceback" not in stderr


def test_demo_with_a_port_is_a_usage_error(tmp_path):
    process = app_process(tmp_path, "--demo", "--port", "COM3")
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 2 and "--demo" in stderr


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux sonames")
def test_a_missing_qt_library_is_named_by_its_packages():
    """Issue 34: on a bare desktop Linux Qt aborted with a list of plugins; the package to install is named."""
    from groundstation.errors import UserError
    from groundstation.ui.app import check_libraries

    check_libraries({"libc.so.6": ("libc6", "glibc")})  # present on every Linux: nothing said
    with pytest.raises(UserError) as said:
        check_libraries({"libc.so.6": ("libc6", "glibc"), "libgroundstation-absent.so.0": ("absent-deb", "absent-rpm")})
    assert "apt install absent-deb`" in str(said.value) and "dnf install absent-rpm`" in str(said.value)
    assert "libc6" not in str(said.value)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="X11")
def test_a_display_that_does_not_answer_is_one_line(tmp_path):
    """Qt aborted (status 134) with a list of plugins when DISPLAY named no X server (or, on a machine
    without Qt's system libraries, when one of them was missing)."""
    from groundstation.errors import UserError
    from groundstation.ui.app import QT_XCB_LIBRARIES, check_libraries

    try:
        check_libraries(QT_XCB_LIBRARIES)
        expected = "no X display answers at DISPLAY=':987'"
    except UserError as missing:
        expected = str(missing)
    process = app_process(tmp_path, "--demo", DISPLAY=":987", QT_QPA_PLATFORM=None, WAYLAND_DISPLAY=None)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 2 and expected in stderr and "Traceback" not in stderr


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="X11 and Wayland")
def test_a_wayland_session_is_not_asked_for_an_x_server(monkeypatch):
    """On Wayland without XWayland (no DISPLAY) Qt 6 takes its Wayland plugin: no X server is needed."""
    from groundstation.ui.app import check_display

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("QT_QPA_PLATFORM", raising=False)
    monkeypatch.setenv("WAYLAND_DISPLAY", "wayland-0")
    check_display()  # nothing said
