"""The replay transport: play/pause (Replay at the end), step, speed, a seek slider and the position.

It moves the playback clock of a ``RevealSession`` (``session.playback.Playback``) for pause, speed and
step; a seek is the window's (views that only add rows start over when it goes back), so the bar
only emits ``seekRequested``.
"""

from __future__ import annotations

import math

from PySide6 import QtCore, QtWidgets

from groundstation.session.playback import Playback
from groundstation.session.view import Session
from groundstation.sources.replay import MAX_SPEED, MIN_SPEED

SPEEDS = tuple(MIN_SPEED * 2.0**i for i in range(round(math.log2(MAX_SPEED / MIN_SPEED)) + 1))  # 0.25x, 0.5x ... 64x
SLIDER_STEPS_PER_S = 10


class JumpingStyle(QtWidgets.QProxyStyle):
    """A left click on a slider's track puts the handle there (not a page step towards it)."""

    def styleHint(self, hint, option=None, widget=None, data=None):
        if hint == QtWidgets.QStyle.SH_Slider_AbsoluteSetButtons:
            return QtCore.Qt.LeftButton.value
        return super().styleHint(hint, option, widget, data)


class ReplayBar(QtWidgets.QWidget):
    seekRequested = QtCore.Signal(float)  # seconds from the start of the recording

    def __init__(self, parent=None):
        super().__init__(parent)
        self.session: Session | None = None  # a seekable one: a file played back
        self.play_button = QtWidgets.QPushButton("Pause")
        self.play_button.clicked.connect(self.toggle)
        self.step_button = QtWidgets.QPushButton("Step")
        self.step_button.setToolTip("One more IMU sample (while paused)")
        self.step_button.clicked.connect(self.step)
        self.speed_box = QtWidgets.QComboBox()
        for speed in SPEEDS:
            self.speed_box.addItem(f"{speed:g}×", speed)
        self.speed_box.setCurrentIndex(SPEEDS.index(1.0))
        self.speed_box.currentIndexChanged.connect(self._speed_changed)
        self.slider = QtWidgets.QSlider(QtCore.Qt.Horizontal)
        self._style = JumpingStyle()  # on a style of its own (a proxy owns its base); kept: the slider does not own it
        self.slider.setStyle(self._style)
        self.slider.sliderReleased.connect(lambda: self.seekRequested.emit(self.slider.value() / SLIDER_STEPS_PER_S))
        self.slider.actionTriggered.connect(self._clicked_track)
        self.position = QtWidgets.QLabel("0.0 / 0.0 s")
        self.position.setMinimumWidth(140)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(4, 0, 4, 0)
        layout.addWidget(QtWidgets.QLabel("Replay"))
        for widget in (self.play_button, self.step_button, QtWidgets.QLabel("Speed"), self.speed_box):
            layout.addWidget(widget)
        layout.addWidget(self.slider, 1)
        layout.addWidget(self.position)

    @property
    def source(self) -> Playback:
        return self.session.source

    def set_session(self, session) -> None:
        """Show the bar for a replay (hidden otherwise); a recomputed replay keeps the pause and speed."""
        replay = session is not None and session.seekable
        self.session = session if replay else None
        self.setVisible(replay)
        if replay:
            self.slider.setRange(0, int(self.source.duration_s * SLIDER_STEPS_PER_S))
            self.source.speed = self.speed
            self._show_paused(self.source.paused)

    @property
    def speed(self) -> float:
        return self.speed_box.currentData()

    @property
    def ended(self) -> bool:
        return not self.session.running

    def toggle(self) -> None:
        """Pause or play; at the end, play again from the start."""
        if self.ended:
            self.source.pause(False)
            self.seekRequested.emit(0.0)
            self._show_paused(False)
            return
        self.source.pause(not self.source.paused)
        self._show_paused(self.source.paused)

    def _show_paused(self, paused: bool) -> None:
        self.play_button.setText("Replay" if self.ended else "Play" if paused else "Pause")
        self.step_button.setEnabled(paused and not self.ended)

    def _speed_changed(self) -> None:
        if self.session is not None:
            self.source.speed = self.speed

    def _clicked_track(self, action: int) -> None:
        """A key press on the slider seeks at once (a click or a drag seeks on release)."""
        if action != QtWidgets.QAbstractSlider.SliderMove:
            QtCore.QTimer.singleShot(0, lambda: self.seekRequested.emit(self.slider.value() / SLIDER_STEPS_PER_S))

    def step(self) -> None:
        """One more IMU sample (while paused)."""
        self.session.step()

    def refresh(self) -> None:
        if self.session is None:
            return
        position, duration = self.source.position_s, self.source.duration_s
        if not self.slider.isSliderDown():
            self.slider.setValue(int(position * SLIDER_STEPS_PER_S))
        self._show_paused(self.source.paused)
        self.position.setText(f"{position:.1f} / {duration:.1f} s{'  (end)' if self.ended else ''}")
