"""The banner that says, loudly, that a live session's recording stopped: why, that decoding and the
display go on, where the flight so far is, and a "Resume recording" button (a new file)."""

from __future__ import annotations

import html

from PySide6 import QtWidgets

from groundstation.recording.recorder import RESUME_MIN_FREE_BYTES
from groundstation.session.view import Session


class RecordingBanner(QtWidgets.QFrame):
    def __init__(self, parent=None):
        super().__init__(parent)
        self.session: Session | None = None
        self.setObjectName("recordingBanner")
        self.setStyleSheet("#recordingBanner { background:#b00020; border-radius:4px; }"
                           "#recordingBanner QLabel { color:white; font-size:11pt; }")
        self.label = QtWidgets.QLabel()
        self.label.setWordWrap(True)
        self.resume_button = QtWidgets.QPushButton("Resume recording")
        self.resume_button.setToolTip("Start a new recording file now (after making room on the disk)")
        self.resume_button.clicked.connect(self.resume)
        layout = QtWidgets.QHBoxLayout(self)
        layout.addWidget(self.label, 1)
        layout.addWidget(self.resume_button)
        self.hide()

    def refresh(self, session: Session | None) -> None:
        """Shown while ``session``'s recorder has failed; hidden otherwise."""
        self.session = session
        recorder = session.recorder if session is not None else None
        if recorder is None or recorder.state != "failed":
            self.hide()
            return
        kept = f"{recorder.path} keeps the {recorder.bytes_written / 1e6:.2f} MB written before. " if recorder.path else ""
        retry = (f"It resumes into a new file by itself once the disk has {RESUME_MIN_FREE_BYTES // 2**20} MB free, "
                 if recorder.retry_interval_s is not None else "")
        self.label.setText(
            f"<b>⚠ RECORDING STOPPED</b> — {html.escape(recorder.error or 'unknown error')}<br>"
            f"Decoding and the display go on, but this part of the flight is not being saved. {html.escape(kept)}"
            f"{retry}or press Resume recording."
        )
        self.show()

    def resume(self) -> None:
        if self.session is not None:
            self.session.resume_recording()  # on failure the recorder's error (shown here) says why
        self.refresh(self.session)
