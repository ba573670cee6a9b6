"""Every screenshot of the README, taken by scripted tours of the real window into a folder.

    xvfb-run -s "-screen 0 1400x860x24" python docs/screenshots/take.py docs/screenshots [SHOT ...]

(QT_QPA_PLATFORM=offscreen works too: every picture of the window is the widget's own rendering.) ``SHOTS`` lists
the tours, each on a new window with settings of its own; name some to take only theirs (default: all):

- ``live``: the simulated bridge typed into the Source box, live with one comparison estimator shown (live.png), the
  attitude panel with its horizon and 3D view (3d-view.png), the event console (events.png), the Channels tab with
  three panes, a custom series, an XY plot and a search (channels.png), the export dialog after an export
  (export-dialog.png), the flight just recorded replayed (replay.png), and a bridge on a pseudo-terminal unplugged
  (port-gone.png).
- ``flight-log``: the shared ArduCopter log opened whole, its flight modes as bands under the plots, the mode and
  arming in the status bar, the Parameters tab filtered (flight-log.png), its Heading and Position tabs
  (log-heading.png, log-position.png).
- ``vibration``: the Vibration tab on a simulated board at hover thrust with 30 Hz rotors (vibration.png).
- ``report``: File > Flight report of a simulated flight with 37 Hz rotors and a reboot at 15 s, the page as
  headless Chromium draws it (report.png; needs ``chromium``).
"""

import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from PySide6 import QtCore, QtGui, QtWidgets

from groundstation.cli import main as cli
from groundstation.session_makers.factory import Sessions
from groundstation.sim.stream import Scenario, SimStream
from groundstation.ui.main_window import MainWindow

SIZE = (1400, 860)  # the window's pictures
LIVE_S = 25  # of flight before the first picture: the 30 s window nearly full
FLIGHT_LOG = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "flightlogs" / "arducopter_cubeorange_2023-07-06_10-12-18.bin"
REPORT_PAGE_PX = (615, 1125)  # the top of the report page: its findings and first figures
REPORT_SCALE = 0.75  # of the page as a browser draws it at 100 %: a page 820 px wide in the picture's width
LIMIT_S = 600  # for a file to be computed or played: only a broken app takes this long

out = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/screenshots")
chosen = sys.argv[2:]
out.mkdir(parents=True, exist_ok=True)
scratch = Path(tempfile.mkdtemp())  # recordings, settings, simulated files: nothing of the user's
app = QtWidgets.QApplication(sys.argv[:1])


def new_window(name: str) -> MainWindow:
    settings = QtCore.QSettings(str(scratch / f"{name}.ini"), QtCore.QSettings.Format.IniFormat)
    window = MainWindow(settings, Sessions(), recordings_dir=scratch / "recordings")
    window.setGeometry(0, 0, *SIZE)
    window.show()
    return window


def wait(seconds: float) -> None:
    loop = QtCore.QEventLoop()
    QtCore.QTimer.singleShot(int(seconds * 1000), loop.quit)
    loop.exec()


def wait_until(done, what: str, seconds: float = LIMIT_S) -> None:
    deadline = time.monotonic() + seconds
    while not done():
        if time.monotonic() > deadline:
            raise SystemExit(f"take.py: {what} not within {seconds} s")
        wait(0.1)


def shoot(widget: QtWidgets.QWidget, name: str) -> None:
    widget.grab().save(str(out / name))
    print(f"wrote {out / name}")


def open_whole(window: MainWindow, path: Path) -> None:
    """``path`` opened as File > Open does, computed, and played to its end (a flight log opens there)."""
    window.open_recording(path)
    wait_until(lambda: window.loading is None, f"computing {path.name}")
    window.replay_bar.speed_box.setCurrentIndex(window.replay_bar.speed_box.findData(64.0))
    if window.session.source.paused:
        window.replay_bar.play_button.click()
    wait_until(lambda: not window.session.running, f"playing {path.name}")


def simulated(name: str, *options: str) -> Path:
    path = scratch / name
    if cli(["simulate", *options, "--out", str(path)]) != 0:
        raise SystemExit(f"take.py: simulate {' '.join(options)} failed")
    return path


def bridge_on_a_pty(stop: threading.Event) -> str:
    """A simulated bridge writing into a pseudo-terminal until ``stop``; its device name."""
    master, slave = os.openpty()

    def run():
        stream, start = SimStream(Scenario("hover", 120.0, seed=4)), time.monotonic()
        while not stop.is_set():
            for chunk in stream.advance(time.monotonic() - start):
                os.write(master, chunk.data)
            time.sleep(0.01)
        os.close(master)  # unplugged

    threading.Thread(target=run, daemon=True).start()
    return os.ttyname(slave)


def live(window: MainWindow) -> None:
    window.bar.port_box.setEditText("sim:?scenario=flight&seed=1")  # typed into the Source box, as a user would
    window.bar.connect_button.click()
    window.live_view.set_visible("ECF", True)  # one comparison estimator, as a user would add it
    window.estimator_panel.sync_shown(window.live_view.attitude.visible_labels())
    wait(LIVE_S)
    shoot(window, "live.png")
    shoot(window.attitude_panel, "3d-view.png")

    window.uplink_panel.config_button.click()  # a few events of a user's session: a command, a tuning
    window.estimator_panel.boxes["ecf", "kp"].setValue(1.5)
    window.estimator_panel.apply()
    wait(1.5)
    window.controls.setCurrentWidget(window.event_console)
    wait(0.5)
    shoot(window, "events.png")
    window.controls.setCurrentWidget(window.estimator_panel)

    view = window.live_view
    view.tabs.setCurrentWidget(view.channels)
    view.channels.restore_layout('{"panes": [["imu.gyr_x_rad_s", "imu.gyr_y_rad_s", "imu.gyr_z_rad_s"], '
                                 '["custom.roll_difference_deg"], ["baro.pressure_Pa"]], '
                                 '"xy": [["position.pos_e_m", "position.pos_n_m"]], '
                                 '"custom": {"roll_difference_deg": "ahf2_roll_deg - onboard_roll_deg"}}')
    view.channels.search.setText("pos")
    wait(3)
    shoot(window, "channels.png")
    view.tabs.setCurrentWidget(view.attitude)

    recording = window.session.recording_path
    window.disconnect()
    dialog = window.export()
    dialog.format_box.setCurrentIndex(dialog.format_box.findData(".csv"))
    dialog.path_edit.setText(str(scratch / "flight.csv"))
    dialog.export_button.click()
    wait_until(lambda: dialog.job is not None and dialog.job.done and not dialog.timer.isActive(), "the export")
    shoot(dialog, "export-dialog.png")
    dialog.close()

    window.open_recording(recording)  # computed in the background, then played back
    wait_until(lambda: window.loading is None, "computing the recording")
    window.seek(10.0)  # a seek only moves the playback clock
    window.replay_bar.speed_box.setCurrentIndex(window.replay_bar.speed_box.findData(4.0))
    wait(3)
    shoot(window, "replay.png")

    stop = threading.Event()
    window.bar.port_box.setEditText(bridge_on_a_pty(stop))  # typed into the Source box
    window.connect_serial(window.bar.source)
    wait(6)
    stop.set()
    wait(3)
    shoot(window, "port-gone.png")


def flight_log(window: MainWindow) -> None:
    open_whole(window, FLIGHT_LOG)
    window.controls.setCurrentWidget(window.parameters_view)
    window.parameters_view.filter_box.setText("ATC_ANG")
    wait(1.5)
    shoot(window, "flight-log.png")
    window.controls.setCurrentWidget(window.estimator_panel)
    view = window.live_view
    for tab, name in ((view.heading, "log-heading.png"), (view.position, "log-position.png")):
        view.tabs.setCurrentWidget(tab)
        wait(1.5)
        shoot(window, name)


def vibration(window: MainWindow) -> None:
    open_whole(window, simulated("rotors.gsrec", "--scenario", "static", "--vibration", "30", "--duration", "40"))
    view = window.live_view
    view.tabs.setCurrentWidget(view.vibration)
    wait_until(lambda: view.vibration.summary is not None, "the vibration view")
    wait(1.5)
    shoot(window, "vibration.png")


def report(window: MainWindow) -> None:
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        raise SystemExit("take.py: the report's picture needs chromium (apt install chromium)")
    window.open_recording(simulated("shaky.gsrec", "--duration", "30", "--vibration", "37", "--reboot-after", "15"))
    wait_until(lambda: window.loading is None, "computing the recording")
    page = scratch / "shaky.html"
    job = window.flight_report(page)  # File > Flight report…
    wait_until(lambda: job.done, "the flight report")
    if job.error:
        raise SystemExit(f"take.py: {job.error}")
    width, height = REPORT_PAGE_PX
    shot = scratch / "report.png"
    subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                    "--hide-scrollbars", f"--force-device-scale-factor={REPORT_SCALE}",
                    f"--window-size={round(width / REPORT_SCALE)},{round(height / REPORT_SCALE)}",
                    f"--screenshot={shot}", page.as_uri()], capture_output=True, timeout=120, check=True)
    # a page of text and lines in 256 colours, undithered (dithering speckles the white): a third of the bytes
    colours = QtCore.Qt.ImageConversionFlag.ThresholdDither | QtCore.Qt.ImageConversionFlag.AvoidDither
    QtGui.QImage(str(shot)).convertToFormat(QtGui.QImage.Format.Format_Indexed8, colours).save(str(out / "report.png"))
    print(f"wrote {out / 'report.png'}")


SHOTS = {"live": live, "flight-log": flight_log, "vibration": vibration, "report": report}


def tour() -> None:
    unknown = set(chosen) - set(SHOTS)
    if unknown:
        print(f"take.py: no shot {', '.join(sorted(unknown))}; the shots: {', '.join(SHOTS)}", file=sys.stderr)
        app.exit(2)
        return
    try:
        for name, take in SHOTS.items():
            if not chosen or name in chosen:
                window = new_window(name)
                take(window)
                window.close()
    except SystemExit as stop:  # raised in a Qt slot it would only be printed
        print(stop, file=sys.stderr)
        app.exit(1)
        return
    app.quit()


QtCore.QTimer.singleShot(0, tour)
sys.exit(app.exec())
