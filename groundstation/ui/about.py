"""Help > About: the version, what it runs on, and links to the documentation (README, docs/)."""

from __future__ import annotations

import platform
from pathlib import Path

import PySide6
from PySide6 import QtCore, QtWidgets

from groundstation import __version__

CHECKOUT = Path(__file__).resolve().parents[2]  # README.md and docs/ sit here in a source checkout
DOCS = (("README.md", "Getting started, the window, the commands"), ("docs/sources.md", "Sources: ports, MAVLink, files"),
        ("docs/session.md", "What a session hands out"), ("docs/recording-format.md", "The recording format"),
        ("docs/conventions.md", "Axes, angles and quaternions"))  # fmt: skip


def about_text() -> str:
    """The About box's rich text: the version, Python and Qt, and a link to each document found."""
    links = "".join(f'<li><a href="{QtCore.QUrl.fromLocalFile(str(CHECKOUT / name)).toString()}">{name}</a>: {what}</li>'
                    for name, what in DOCS if (CHECKOUT / name).is_file())
    docs = f"<ul>{links}</ul>" if links else "<p>The documentation is the README and docs/ of the source distribution.</p>"
    return (f"<h3>groundstation {__version__}</h3>"
            "<p>Ground station for small quadrotors and MAVLink autopilots: live telemetry, attitude estimators, "
            "recording, replay and export.</p>"
            f"<p>Python {platform.python_version()}, Qt {QtCore.qVersion()} (PySide6 {PySide6.__version__})</p>{docs}"
            "<p>Commands: <code>groundstation --help</code>. Keys: Help &gt; Keyboard shortcuts (F1).</p>")


def show_about(parent) -> QtWidgets.QMessageBox:
    box = QtWidgets.QMessageBox(QtWidgets.QMessageBox.Information, "About groundstation", about_text(),
                                QtWidgets.QMessageBox.Close, parent)
    box.setTextFormat(QtCore.Qt.RichText)
    box.setTextInteractionFlags(QtCore.Qt.TextBrowserInteraction)  # the links open in the desktop's viewer
    box.setModal(False)
    box.show()
    return box
