"""A scripted tour of the real window that takes the README's screenshots into a folder.

    xvfb-run -s "-screen 0 1400x860x24" python docs/screenshots/take.py docs/screenshots

(QT_QPA_PLATFORM=offscreen works too: every picture is the widget's own rendering.) The tour: the
simulated bridge typed into the Source box, live with one comparison estimator shown (live.png), the attitude panel with its
horizon and 3D view (3d-view.png), the event console (events.png), the Channels tab with three panes, a custom series, an XY
plot and a search (channels.png), the export dialog after an export (export-dialog.png), the flight just recorded
replayed (replay.png), and a bridge on a pseudo-terminal unplugged (port-gone.png).
"""

import os
import sys
import tempfile
import threading
import time
from pathlib import Path

from PySide6 import QtCore, QtWidgets

from groundstation.session_makers.factory import Sessions
from groundstation.sim.stream import Scenario, SimStream
from groundstation.ui.main_window import MainWindow

LIVE_S = 25  # of flight before the first picture: the 30 s window nearly full

out = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/screenshots")
out.mkdir(parents=True, exist_ok=True)
os.environ.setdefault("GROUNDSTATION_RECORDINGS", tempfile.mkdtemp())
app = QtWidgets.QApplication(sys.argv[:1])
settings = QtCore.QSettings(os.path.join(tempfile.mkdtemp(), "settings.ini"), QtCore.QSettings.Format.IniFormat)
window = MainWindow(settings, Sessions())
window.setGeometry(0, 0, 1400, 860)
window.show()


def wait(seconds: float) -> None:
    loop = QtCore.QEventLoop()
    QtCore.QTimer.singleShot(int(seconds * 1000), loop.quit)
    loop.exec()


def shoot(widget: QtWidgets.QWidget, name: str) -> None:
    widget.grab().save(str(out / name))
    print(f"wrote {out / name}")


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


def tour() -> None:
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
    dialog.path_edit.setText(str(Path(tempfile.mkdtemp()) / "flight.csv"))
    dialog.export_button.click()
    while dialog.job is None or not dialog.job.done or dialog.timer.isActive():
        wait(0.2)
    shoot(dialog, "export-dialog.png")
    dialog.close()

    window.open_recording(recording)  # computed in the background, then played back
    while window.loading is not None:
        wait(0.2)
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
    window.close()
    app.quit()


QtCore.QTimer.singleShot(0, tour)
app.exec()
