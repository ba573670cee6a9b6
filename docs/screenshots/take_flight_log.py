"""The README's picture of a flight log in the real window: the shared ArduCopter log played to its end,
its flight modes as bands under the plots, the mode and arming in the status bar, and the Parameters tab
filtered (flight-log.png).

    xvfb-run -s "-screen 0 1400x860x24" python docs/screenshots/take_flight_log.py docs/screenshots
"""

import os
import sys
import tempfile
from pathlib import Path

from PySide6 import QtCore, QtWidgets

from groundstation.session_makers.factory import Sessions
from groundstation.ui.main_window import MainWindow

LOG = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "flightlogs" / "arducopter_cubeorange_2023-07-06_10-12-18.bin"

out = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/screenshots")
app = QtWidgets.QApplication(sys.argv[:1])
settings = QtCore.QSettings(os.path.join(tempfile.mkdtemp(), "settings.ini"), QtCore.QSettings.Format.IniFormat)
window = MainWindow(settings, Sessions(), recordings_dir=Path(tempfile.mkdtemp()))
window.setGeometry(0, 0, 1400, 860)
window.show()


def wait_until(done, seconds: float) -> None:
    for _ in range(int(seconds * 10)):
        if done():
            return
        loop = QtCore.QEventLoop()
        QtCore.QTimer.singleShot(100, loop.quit)
        loop.exec()


window.open_recording(LOG)
wait_until(lambda: window.loading is None, 180)
window.live_view.window_box.setCurrentText("whole session")
window.replay_bar.speed_box.setCurrentIndex(window.replay_bar.speed_box.findData(64.0))
if window.session.source.paused:
    window.replay_bar.play_button.click()
wait_until(lambda: not window.session.running, 60)
window.controls.setCurrentWidget(window.parameters_view)
window.parameters_view.filter_box.setText("ATC_ANG")
wait_until(lambda: False, 1.5)
window.grab().save(str(out / "flight-log.png"))
print(f"wrote {out / 'flight-log.png'}")
