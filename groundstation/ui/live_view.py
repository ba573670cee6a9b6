"""The live view: attitude, raw sensors and AHF diagnostics over a chosen time window.

``refresh`` is called by the window's redraw timer: it pulls the rows the pipeline added since the
last call into the ``Series`` buffers and redraws the visible tab. "Pause view" freezes the plots
(acquisition and recording go on) and frees zoom and pan; panning or zooming pauses it too.
"""

from __future__ import annotations

from PySide6 import QtWidgets

from groundstation.session.live import LiveSession
from groundstation.ui.plots import Curve, Plot, StackedPlots
from groundstation.ui.series import Series, imu_quantities, onboard_quantities

WINDOWS_S = {"10 s": 10.0, "30 s": 30.0, "60 s": 60.0, "10 min": 600.0, "whole session": None}
DEFAULT_WINDOW = "30 s"
COLORS = {"ahf": "#1f5fbf", "onboard": "#e07000", "hf": "#2a9d3a", "ecf": "#8e44ad", "cf1": "#7f7f7f",
          "kf": "#c0392b", "ekf": "#16a085"}
LABELS = {"ahf": "AHF", "onboard": "onboard", "hf": "HF", "ecf": "ECF", "cf1": "CF1", "kf": "KF", "ekf": "EKF"}
AXIS_COLORS = ("#c0392b", "#2a9d3a", "#1f5fbf")


def attitude_plots(filters: tuple[str, ...]) -> tuple[Plot, ...]:
    def curves(angle: str) -> tuple[Curve, ...]:
        host = tuple(Curve("imu", f"{n}_{angle}_deg", LABELS.get(n, n), COLORS.get(n, "#444")) for n in filters)
        return host[:1] + (Curve("onboard", f"onboard_{angle}_deg", "onboard", COLORS["onboard"]),) + host[1:]

    return Plot("pitch", "°", curves("pitch")), Plot("roll", "°", curves("roll"))


def sensor_plots() -> tuple[Plot, ...]:
    def axes(prefix: str, unit: str) -> tuple[Curve, ...]:
        return tuple(Curve("imu", f"{prefix}_{a}_{unit}", a, c) for a, c in zip("xyz", AXIS_COLORS))

    return Plot("accelerometer", "g", axes("acc", "g")), Plot("gyroscope", "°/s", axes("gyr", "dps"))


def diagnostic_plots() -> tuple[Plot, ...]:
    return (
        Plot("λ", "rad/s", (Curve("imu", "ahf_lam", "AHF", COLORS["ahf"]),
                            Curve("onboard", "onboard_lam", "onboard", COLORS["onboard"]))),
        Plot("acceleration error e_a", "1", (Curve("imu", "ahf_e_a", "AHF", COLORS["ahf"]),)),
    )


class LiveView(QtWidgets.QWidget):
    """``hidden``: legend labels switched off at first (the comparison estimators, say)."""

    def __init__(self, hidden: frozenset[str] = frozenset(), parent=None):
        super().__init__(parent)
        self.session: LiveSession | None = None
        self.series: dict[str, Series] = {}
        self._pipeline = None
        self.frames_drawn = 0  # for the tests and the benchmark
        self.window_box = QtWidgets.QComboBox()
        self.window_box.addItems(list(WINDOWS_S))
        self.window_box.setCurrentText(DEFAULT_WINDOW)
        self.window_box.currentTextChanged.connect(lambda _: self.redraw())
        self.pause_button = QtWidgets.QPushButton("Pause view")
        self.pause_button.setCheckable(True)
        self.pause_button.setToolTip("Freeze the plots to zoom and pan; acquisition and recording go on")
        self.pause_button.toggled.connect(self._paused_changed)
        controls = QtWidgets.QHBoxLayout()
        controls.addWidget(QtWidgets.QLabel("Time window"))
        controls.addWidget(self.window_box)
        controls.addWidget(self.pause_button)
        controls.addStretch(1)
        self.tabs = QtWidgets.QTabWidget()
        self.tabs.currentChanged.connect(lambda _: self.redraw())
        self._hidden = hidden  # remembered also for labels the current session lacks
        self.attitude = self._add_tab(StackedPlots(attitude_plots(("ahf",)), hidden), "Attitude")
        self._filters = ("ahf",)
        self.sensors = self._add_tab(StackedPlots(sensor_plots()), "Sensors")
        self.diagnostics = self._add_tab(StackedPlots(diagnostic_plots()), "AHF diagnostics")
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addLayout(controls)
        layout.addWidget(self.tabs, 1)

    def _add_tab(self, plots: StackedPlots, title: str, index: int = -1) -> StackedPlots:
        plots.userInteracted.connect(lambda: self.pause_button.setChecked(True))
        self.tabs.insertTab(index, plots, title)
        return plots

    @property
    def window_s(self) -> float | None:
        return WINDOWS_S[self.window_box.currentText()]

    @property
    def paused(self) -> bool:
        return self.pause_button.isChecked()

    def set_session(self, session: LiveSession | None) -> None:
        """Show ``session``; its estimators decide the attitude curves."""
        self.session = session
        self._pipeline = None
        self.series = {}
        filters = session.pipeline.filters if session is not None else self._filters
        if filters != self._filters:
            self._hidden = self.hidden_labels()
            current = self.tabs.currentIndex()
            self.tabs.removeTab(0)
            self.attitude.deleteLater()
            self.attitude = self._add_tab(StackedPlots(attitude_plots(filters), self._hidden), "Attitude", 0)
            self.tabs.setCurrentIndex(current)
            self._filters = filters
        for plots in (self.attitude, self.sensors, self.diagnostics):
            plots.clear_data()

    def hidden_labels(self) -> frozenset[str]:
        """The attitude legend entries switched off, with those remembered from earlier sessions."""
        present = {spec.label for spec, _ in self.attitude.curves}
        return frozenset((self._hidden - present) | (present - self.attitude.visible_labels()))

    def _paused_changed(self, paused: bool) -> None:
        self.pause_button.setText("Resume view" if paused else "Pause view")
        if not paused:
            self.redraw()

    def refresh(self) -> bool:
        """Take the new rows; redraw the visible plots if anything grew. True when it drew."""
        if self.session is None:
            return False
        pipeline = self.session.pipeline
        if pipeline is not self._pipeline:  # a new session, or a replay restarted by a seek
            self._pipeline = pipeline
            self.series = {"imu": Series(pipeline.imu, imu_quantities(pipeline.filters)),
                           "onboard": Series(pipeline.onboard, onboard_quantities)}
        grew = {name for name, s in self.series.items() if s.take(self.session.lock)}
        if not grew or self.paused:
            return False
        self.current_plots().draw(self.series, self.window_s, grew)
        self.frames_drawn += 1
        return True

    def redraw(self) -> None:
        """Everything visible again (window, tab or visibility changed)."""
        if self.series and not self.paused:
            self.current_plots().draw(self.series, self.window_s, None)

    def current_plots(self) -> StackedPlots:
        return self.tabs.currentWidget()
