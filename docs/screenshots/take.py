"""Screenshot of the real window on the simulated bridge, from the X server's framebuffer.

    xvfb-run -s "-screen 0 1400x860x24" python docs/screenshots/take.py docs/screenshot.png
"""

import os
import sys
import tempfile

from PySide6 import QtCore, QtWidgets

from groundstation.ui.main_window import MainWindow

SECONDS = 25  # of flight before the picture: the 30 s window nearly full

out = sys.argv[1]
os.environ.setdefault("GROUNDSTATION_RECORDINGS", tempfile.mkdtemp())
app = QtWidgets.QApplication(sys.argv[:1])
settings = QtCore.QSettings(os.path.join(tempfile.mkdtemp(), "settings.ini"), QtCore.QSettings.Format.IniFormat)
window = MainWindow(settings)
window.setGeometry(0, 0, 1400, 860)
window.show()
window.start_demo("no port given: streaming from the simulated bridge")
window.live_view.attitude.set_visible("ECF", True)  # one comparison estimator, as a user would add it


def shoot() -> None:
    app.primaryScreen().grabWindow(0).save(out)
    window.close()
    app.quit()


QtCore.QTimer.singleShot(SECONDS * 1000, shoot)
app.exec()
