"""The warning banner of a held CONFIG: the aircraft (or something posing as it) said other full scales
or another mounting without a device restart, so the data keeps the ones in use until the user
decides: "Accept new scales" applies them from now on, "Keep current" keeps the ones in use
(``Session.held_config`` and ``resolve_config``; ``pipeline.ConfigGuard`` holds it)."""

from __future__ import annotations

import html

from PySide6 import QtWidgets

from groundstation.session.view import Session


class ConfigBanner(QtWidgets.QFrame):
    def __init__(self, parent=None):
        super().__init__(parent)
        self.session: Session | None = None
        self.setObjectName("configBanner")
        self.setStyleSheet("#configBanner { background:#fff3cd; border:1px solid #e0b000; border-radius:4px; }"
                           "#configBanner QLabel { color:#5c4400; }")
        self.label = QtWidgets.QLabel()
        self.label.setWordWrap(True)
        self.accept_button = QtWidgets.QPushButton("Accept new scales")
        self.accept_button.setToolTip("Convert the data with the scales of the new CONFIG from now on")
        self.accept_button.clicked.connect(lambda: self.answer(True))
        self.keep_button = QtWidgets.QPushButton("Keep current")
        self.keep_button.setToolTip("Ignore the new CONFIG: keep converting with the scales in use")
        self.keep_button.clicked.connect(lambda: self.answer(False))
        layout = QtWidgets.QHBoxLayout(self)
        layout.addWidget(self.label, 1)
        layout.addWidget(self.accept_button)
        layout.addWidget(self.keep_button)
        self.hide()

    def refresh(self, session: Session | None) -> None:
        """Shown while ``session`` holds a CONFIG for the user's answer; hidden otherwise."""
        self.session = session
        held = session.held_config() if session is not None else None
        if held is None:
            self.hide()
            return
        self.label.setText(f"<b>⚠ THE SENSOR'S SCALES CHANGED WITHOUT A RESTART</b> — {html.escape(held)}<br>"
                           "The data keeps the scales in use until you decide.")
        self.show()

    def answer(self, accept: bool) -> None:
        if self.session is not None:
            self.session.resolve_config(accept)
        self.refresh(self.session)
