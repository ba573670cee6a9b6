"""The live view: attitude, raw sensors, AHF diagnostics, heading, position and any channel over a
chosen time window.

``refresh`` is called by the window's redraw timer: once the newest sample reaches a pixel column the
plots have not drawn, it pulls the rows the session added since the last draw into the ``Series``
buffers and redraws the visible tab (the others draw nothing until they are shown). The heading and position tabs
appear, and the Sensors tab gains the magnetometer and barometer, once the session has delivered
their frames. "Pause view" freezes the plots (acquisition and recording go on) and frees zoom and
pan; panning or zooming pauses it too. ``show_time`` and ``pan`` pause it and move it (the event
console, the arrow keys), drawing every sample once so that the past beyond the window shows.
"""

from __future__ import annotations

from PySide6 import QtWidgets

from groundstation import estimation
from groundstation.session.view import Session
from groundstation.ui.navigation import aiding_series
from groundstation.ui.channels import ChannelsView
from groundstation.ui.flight_sections_view import SERIES as SECTION_SERIES, FlightSectionsView, section_series
from groundstation.ui.mode_bands import ModeBands
from groundstation.estimation import colour_of as colour
from groundstation.estimation.evaluation import gives_heading
from groundstation.palette import ONBOARD_COLOUR, TRUTH_COLOUR
from groundstation.ui.plots import Curve, Plot, StackedPlots
from groundstation.ui.position_view import PositionView
from groundstation.ui.sample_streams import newest_time_s, slow_imu_hz
from groundstation.ui.series import Series, clock_series, imu_quantities, onboard_quantities, truth_quantities
from groundstation.ui.session_series import Other, other_series
from groundstation.ui.vibration_view import VibrationView
from groundstation.ui.whole_flight import WHOLE_WINDOW, is_flight_log, replayed_path

WINDOWS_S = {"10 s": 10.0, "30 s": 30.0, "60 s": 60.0, "10 min": 600.0, "whole session": None}
DEFAULT_WINDOW = "30 s"
# The eleven curves the app shows together (the live estimators and the onboard one) each get their own
# colour of the palette, the one the estimator names (``Estimator.colour``); the estimators only a replay
# of an older recording has (CF1, KF, EKF) share one. The aircraft's own estimate is wine.
AXIS_COLORS = ("#c0392b", "#2a9d3a", "#1f5fbf")
# The sensors' headings in colours no estimator takes (the palette's are theirs; black is AHF2's).
HEADING_COLORS = {"compass": "#8c8c8c", "GPS": "#b8860b"}
SENSOR_AIDING = frozenset({"mag", "baro"})  # aiding sensors plotted on the Sensors tab once they have rows
# The tabs that appear once a series of theirs has rows.
AIDING_TABS = {"heading": ("mag", "gps"), "position": ("gps", "baro", "position"), "flight": SECTION_SERIES}
# The tabs after Attitude, in order. Those not in sight at the start are built when first asked for (a
# session, a click on their title): their plots are two thirds of building the window, which its first
# paint need not wait for (bench/bench_first_frame.py).
LATER_TABS = {"sensors": "Sensors", "diagnostics": "AHF diagnostics", "heading": "Heading", "position": "Position",
              "flight": "Flight", "channels": "Channels", "vibration": "Vibration"}


def estimator_curves(filters: tuple[str, ...], angle: str, wraps_at: float | None = None, truth: bool = False,
                     onboard_main: bool = False) -> tuple[Curve, ...]:
    """``angle`` (pitch, roll, heading) of the first host estimator, the onboard one (dashed, beneath), the
    others, then the truth when the session has one (a SITL log's); ``onboard_main`` (the IMU too slow for
    the host estimators: ``sample_streams.slow_imu_hz``): the onboard one first and solid."""
    host = tuple(Curve("imu", f"{n}_{angle}_deg", estimation.label(n), colour(n), wraps_at) for n in filters)
    onboard = Curve("onboard", f"onboard_{angle}_deg", "onboard", ONBOARD_COLOUR, wraps_at, reference=not onboard_main)
    true = (Curve("truth", f"truth_{angle}_deg", "truth", TRUTH_COLOUR, wraps_at, reference=True),) if truth else ()
    return ((onboard,) + host if onboard_main else host[:1] + (onboard,) + host[1:]) + true


def attitude_plots(filters: tuple[str, ...], truth: bool = False, onboard_main: bool = False, others: tuple = ()) -> tuple[Plot, ...]:
    """``others``: (label, estimators shown, style) of each session beside the window's, whose curves are added."""
    return tuple(Plot(angle, "°", estimator_curves(filters, angle, truth=truth, onboard_main=onboard_main) + other_curves(others, angle))
                 for angle in ("pitch", "roll"))


def other_curves(others: tuple, angle: str, wraps_at: float | None = None) -> tuple[Curve, ...]:
    """Each other session's estimators shown (at first its first host estimator; the Estimators panel
    adds others) and onboard estimate, in its own pen style and named by it ("S2 AHF2"): the estimator's
    colour says which estimator, the style which session."""
    curves = []
    for label, shown, style in others:
        curves += [Curve(f"{label}:imu", f"{name}_{angle}_deg", f"{label} {estimation.label(name)}", colour(name),
                         wraps_at, style=style) for name in shown]
        curves.append(Curve(f"{label}:onboard", f"onboard_{angle}_deg", f"{label} onboard", ONBOARD_COLOUR, wraps_at, style=style))
    return tuple(curves)


def heading_plots(filters: tuple[str, ...], truth: bool = False, onboard_main: bool = False, others: tuple = ()) -> tuple[Plot, ...]:
    """Compass and GPS heading against the onboard one and the yaw of the estimators that have a heading
    (``gives_heading``), all 0..360°: the others' yaw is the gyro's integral from an arbitrary start (AHF2's
    ran 360° -> 325° against the onboard 235° on a PX4 hop), and is not drawn as one; ``others`` as
    ``attitude_plots``, their estimators chosen by the same rule."""
    sensors = (Curve("mag", "compass_heading_deg", "compass", HEADING_COLORS["compass"], 360.0),
               Curve("gps", "gps_heading_deg", "GPS", HEADING_COLORS["GPS"], 360.0))
    headed = tuple(name for name in filters if gives_heading(name))
    others_headed = tuple((label, tuple(name for name in shown if gives_heading(name)), style) for label, shown, style in others)
    return (Plot("heading", "°", sensors + estimator_curves(headed, "heading", 360.0, truth, onboard_main)
                 + other_curves(others_headed, "heading", 360.0)),)


def sensor_plots(aiding: frozenset[str] = frozenset()) -> tuple[Plot, ...]:
    """Accelerometer and gyroscope; the magnetometer and barometer too when ``aiding`` names them."""
    def axes(series: str, prefix: str, unit: str) -> tuple[Curve, ...]:
        return tuple(Curve(series, f"{prefix}_{a}_{unit}", a, c) for a, c in zip("xyz", AXIS_COLORS))

    plots = [Plot("accelerometer", "g", axes("imu", "acc", "g")), Plot("gyroscope", "°/s", axes("imu", "gyr", "dps"))]
    if "mag" in aiding:
        plots.append(Plot("magnetometer", "µT", axes("mag", "mag", "uT")))
    if "baro" in aiding:
        plots.append(Plot("pressure", "hPa", (Curve("baro", "baro_pressure_hPa", "barometer", "#444444"),)))
    return tuple(plots)


def diagnostic_plots() -> tuple[Plot, ...]:
    return (
        Plot("λ", "rad/s", (Curve("imu", "ahf_lam", estimation.label("ahf"), colour("ahf")),
                            Curve("onboard", "onboard_lam", "onboard", ONBOARD_COLOUR, reference=True))),
        Plot("acceleration error e_a", "", (Curve("imu", "ahf_e_a", estimation.label("ahf"), colour("ahf")),)),
    )


class LiveView(QtWidgets.QWidget):
    """``hidden``: legend labels switched off at first (the comparison estimators, say)."""

    def __init__(self, hidden: frozenset[str] = frozenset(), parent=None):
        super().__init__(parent)
        self.session: Session | None = None
        self.others: list[Other] = []  # the sessions beside it (``set_others``)
        self.series: dict[str, Series] = {}
        self._view = None
        self.frames_drawn = 0  # for the tests and the benchmark
        self._browsing: StackedPlots | None = None  # paused, and drawn whole to look back in time
        self._newest_s: float | None = None  # the newest sample's time at the last refresh (``_nothing_new``)
        self.mode_bands = ModeBands()  # an autopilot's flight modes under the curves
        self.window_box = QtWidgets.QComboBox()
        self.window_box.addItems(list(WINDOWS_S))
        self.window_box.setCurrentText(DEFAULT_WINDOW)
        self.window_box.currentTextChanged.connect(lambda _: self.redraw())
        self._window_before_log: str | None = None  # the window chosen before a flight log showed itself whole
        self.pause_button = QtWidgets.QPushButton("Pause view")
        self.pause_button.setCheckable(True)
        self.pause_button.setToolTip("Freeze the plots to zoom and pan; acquisition and recording go on")
        self.pause_button.toggled.connect(self._paused_changed)
        # The time window and the pause, placed by the host (the window: in the row the replay bar shares).
        self.view_controls = QtWidgets.QWidget()
        controls = QtWidgets.QHBoxLayout(self.view_controls)
        controls.setContentsMargins(0, 0, 0, 0)
        controls.addWidget(QtWidgets.QLabel("Time window"))
        controls.addWidget(self.window_box)
        controls.addWidget(self.pause_button)
        self.tabs = QtWidgets.QTabWidget()
        self._hidden = hidden  # remembered also for labels the current session lacks
        self._slow_hidden: frozenset[str] = frozenset()  # host estimators switched off for an IMU too slow for them
        self._slow_hz: float | None = None  # the IMU's rate when too slow for them (``sample_streams.slow_imu_hz``)
        # Drawn at first for the estimators a live session runs (the registry names them without loading
        # them): the app's usual first session then finds its curves there, not rebuilt (a third of a
        # second before its first data; bench/bench_first_frame.py).
        live = estimation.live_estimators()
        self.attitude = self._add_tab(StackedPlots(attitude_plots(live), hidden), "Attitude")
        self._curves_of = (live, False, False)  # the estimators, whether a truth is plotted, whether onboard is the main curve
        self._others_of: tuple = ()  # the other sessions' curves: (label, estimators shown, style) each
        self._sensor_aiding: frozenset[str] = frozenset()
        self._later: dict[str, QtWidgets.QWidget] = {}  # a tab not built yet -> the blank page under its title
        for name, title in LATER_TABS.items():
            if name == "channels":  # built now: the window restores its panes from the settings at once
                self.channels = self._add_tab(ChannelsView(), title)
            else:
                self._later[name] = QtWidgets.QWidget()
                self.tabs.addTab(self._later[name], title)
        for name in AIDING_TABS:  # shown once their data comes (``_show_aiding_tabs``)
            self.tabs.setTabVisible(self.tabs.indexOf(self._later[name]), False)
        self.tabs.currentChanged.connect(self._tab_changed)  # once every tab is there
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.tabs, 1)

    def __getattr__(self, name: str):
        """A tab of ``LATER_TABS`` asked for before it is built: every one of them built now."""
        later = self.__dict__.get("_later")
        if not later or name not in later:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        self._build_later_tabs()
        return self.__dict__[name]

    def _build_later_tabs(self) -> None:
        later, self._later = self._later, {}
        built = {"sensors": lambda: StackedPlots(sensor_plots(self._sensor_aiding)),
                 "diagnostics": lambda: StackedPlots(diagnostic_plots()),
                 "heading": lambda: StackedPlots(heading_plots(*self._curves_of, self._others_of), self._switched_off()),
                 "position": lambda: PositionView(fused_absent_hz=self._slow_hz), "vibration": VibrationView, "flight": FlightSectionsView}
        current = self.tabs.currentIndex()
        self.tabs.blockSignals(True)  # the current tab stays what it was; no half-built view is asked for
        for name, blank in later.items():
            index = self.tabs.indexOf(blank)
            title, visible = self.tabs.tabText(index), self.tabs.isTabVisible(index)
            self.tabs.removeTab(index)
            setattr(self, name, self._add_tab(built[name](), title, index))
            self.tabs.setTabVisible(index, visible)
            blank.deleteLater()
        self.tabs.setCurrentIndex(current)
        self.tabs.blockSignals(False)

    def _add_tab(self, plots: StackedPlots | PositionView, title: str, index: int = -1) -> StackedPlots | PositionView:
        plots.userInteracted.connect(lambda: self.pause_button.setChecked(True))
        self.tabs.insertTab(index, plots, title)
        return plots

    def _replace_tab(self, old: StackedPlots, new: StackedPlots) -> StackedPlots:
        index = self.tabs.indexOf(old)
        title = self.tabs.tabText(index)
        self.tabs.removeTab(index)
        old.deleteLater()
        return self._add_tab(new, title, index)

    def _show_whole(self, flight_log: bool) -> None:
        """A flight log in the whole-session window (``whole_flight``); the window chosen before comes back
        with the next other session."""
        if flight_log and self._window_before_log is None:
            self._window_before_log = self.window_box.currentText()
            self.window_box.setCurrentText(WHOLE_WINDOW)
        elif not flight_log and self._window_before_log is not None:
            self.window_box.setCurrentText(self._window_before_log)
            self._window_before_log = None

    @property
    def chosen_window(self) -> str:
        """The time window the user chose (remembered for the next start), not the one a flight log imposed."""
        return self._window_before_log or self.window_box.currentText()

    @property
    def window_s(self) -> float | None:
        return WINDOWS_S[self.window_box.currentText()]

    @property
    def paused(self) -> bool:
        return self.pause_button.isChecked()

    def set_session(self, session: Session | None) -> None:
        """Show ``session``, drawing from its start (a pause belonged to the session shown before); its
        estimators decide the attitude curves."""
        self.session = session
        self._view = None
        self._show_whole(is_flight_log(replayed_path(session)))
        self.pause_button.setChecked(False)
        self._browsing = None
        self.series = {}
        filters = session.view.filters if session is not None else self._curves_of[0]
        self._hidden, self._slow_hidden = self.hidden_labels(), frozenset()
        self._show_estimators((filters, session is not None and "truth" in session.view.catalogue, False))
        for plots in (self.attitude, self.sensors, self.diagnostics, self.heading, self.position, self.flight):
            plots.clear_data()
        self.flight.set_session(session)
        self.position.protocol = session.view.protocol if session is not None else None
        self.channels.set_session(session)
        self.vibration.set_session(session)
        self._show_aiding_tabs()

    def _show_estimators(self, shown: tuple) -> None:
        """The attitude and heading tabs rebuilt for ``shown`` (as ``_curves_of``) when it changed."""
        if shown == self._curves_of:
            return
        current = self.tabs.currentIndex()
        self.attitude = self._replace_tab(self.attitude, StackedPlots(attitude_plots(*shown, self._others_of), self._switched_off()))
        self.heading = self._replace_tab(self.heading, StackedPlots(heading_plots(*shown, self._others_of), self._switched_off()))
        self.tabs.setCurrentIndex(current)
        self._curves_of = shown

    def _follow_imu_rate(self, view) -> None:
        """An IMU too slow for the host estimators (``sample_streams.slow_imu_hz``): the onboard estimate the main
        curve, the host estimators switched off (the user may switch them on), no fused position; back when it
        is fast enough again."""
        self._slow_hz = slow_hz = slow_imu_hz(view)
        if "position" not in self._later:  # else told when built
            self.position.set_fused_absent(slow_hz)
        onboard_main = slow_hz is not None and newest_time_s(view.onboard) is not None
        if onboard_main == self._curves_of[2]:
            return
        self._hidden = self.hidden_labels()
        host = frozenset(estimation.label(name) for name in self._curves_of[0])
        self._slow_hidden = host - self._hidden if onboard_main else frozenset()
        self._show_estimators((*self._curves_of[:2], onboard_main))

    def _switched_off(self) -> frozenset[str]:
        return self._hidden | self._slow_hidden

    def set_others(self, others: list[Other]) -> None:
        """The sessions beside the window's: their attitude and heading curves on the Attitude and Heading
        tabs, their channels in the Channels tab, from their oldest rows kept."""
        self.others = list(others)
        if self.series:  # else made with the window's own at the next refresh
            self.series = {**{k: s for k, s in self.series.items() if ":" not in k}, **other_series(self.others)}
        curves = tuple((o.label, o.shown, o.style) for o in self.others)
        if curves != self._others_of:
            self._hidden = self.hidden_labels()
            current = self.tabs.currentIndex()
            self._others_of = curves
            self.attitude = self._replace_tab(self.attitude, StackedPlots(attitude_plots(*self._curves_of, curves), self._switched_off()))
            if "heading" not in self._later:  # built: else built with these curves when first shown
                self.heading = self._replace_tab(self.heading, StackedPlots(heading_plots(*self._curves_of, curves), self._switched_off()))
            self.tabs.setCurrentIndex(current)
        self.channels.set_others(self.others)

    def hidden_labels(self) -> frozenset[str]:
        """The attitude legend entries the user switched off, with those remembered from earlier sessions (not
        those switched off for an IMU too slow for them)."""
        present = {spec.label for spec, _ in self.attitude.curves}
        return frozenset((self._hidden - present) | (present - self.attitude.visible_labels() - self._slow_hidden))

    def set_visible(self, label: str, visible: bool) -> None:
        """Show or hide an estimator's curves on the attitude and heading tabs (remembered for a
        session to come when this one lacks the estimator)."""
        self._hidden = self._hidden | {label} if not visible else self._hidden - {label}
        self._slow_hidden -= {label}  # the user's choice now
        for plots in (self.attitude, self.heading):
            plots.set_visible(label, visible)

    def _tab_changed(self) -> None:
        if self.tabs.currentWidget() in self._later.values():  # a click on a tab not built yet
            self._build_later_tabs()
        self._show_aiding_sensors()
        self.redraw()

    def _show_aiding_sensors(self) -> None:
        """The Sensors tab with a plot for each aiding sensor that has delivered readings; rebuilt when
        it is shown (building plots takes a good part of a second, which the other tabs need not wait)."""
        aiding = frozenset(s for s in SENSOR_AIDING if s in self.series and self.series[s].taken)
        if aiding != self._sensor_aiding and self.tabs.currentWidget() is self.sensors:
            self._sensor_aiding = aiding  # first: replacing the tab changes the current one, which calls here
            current = self.tabs.currentIndex()
            self.sensors = self._replace_tab(self.sensors, StackedPlots(sensor_plots(aiding)))
            self.tabs.setCurrentIndex(current)

    def _show_aiding_tabs(self) -> None:
        self._show_aiding_sensors()
        for name, sources in AIDING_TABS.items():
            index = self.tabs.indexOf(getattr(self, name))
            shown = any(self.series[s].taken for s in sources if s in self.series)
            if self.tabs.isTabVisible(index) != shown:
                self.tabs.setTabVisible(index, shown)

    def _paused_changed(self, paused: bool) -> None:
        self.pause_button.setText("Resume view" if paused else "Pause view")
        if not paused:
            self._browsing = None
        self.redraw()

    def show_time(self, t_s: float | None) -> None:
        """Pause the view and centre it on ``t_s`` (None: the session's start), window wide."""
        self._browse(lambda low, high, first: (first, first + high - low) if t_s is None else
                     (t_s - (high - low) / 2, t_s + (high - low) / 2))

    def pan(self, fraction: float) -> None:
        """Pause the view and move it by ``fraction`` of its width (negative: back in time)."""
        self._browse(lambda low, high, first: (low + fraction * (high - low), high + fraction * (high - low)))

    def _browse(self, new_range) -> None:
        """Pause, draw every sample once (the live draw holds only the window's), set the time range."""
        plots = self.current_plots()
        clock = clock_series(self.series)
        if not isinstance(plots, (StackedPlots, ChannelsView, FlightSectionsView)) or clock is None or not plots.items:
            return
        low, high = plots.items[0].getViewBox().viewRange()[0]
        self.pause_button.setChecked(True)
        if self._browsing is not plots:
            plots.draw(self.series, None, None)
            self._browsing = plots
        plots.items[0].setXRange(*new_range(low, high, clock.start_s), padding=0)

    def refresh(self) -> bool:
        """Take the new rows; redraw the visible plots if anything grew. True when it drew."""
        if self.session is None:
            return False
        view = self.session.view
        if view is not self._view:  # a new session, or a replay restarted by a seek
            self._view = view
            self.series = {"imu": Series(view.imu, imu_quantities(view.filters)),
                           "onboard": Series(view.onboard, onboard_quantities), **aiding_series(view.tables),
                           **section_series(view.tables), **other_series(self.others)}
            if view.tables.get("truth") is not None:  # a simulator's log: its truth, dashed
                self.series["truth"] = Series(view.tables["truth"], truth_quantities)
        plots = self.current_plots()
        if self._nothing_new(plots):
            return False
        grew = {name for name, s in self.series.items() if s.take(self.session.lock)}
        if grew & {"imu", "onboard"}:
            self._follow_imu_rate(view)
        if grew - {"imu", "onboard"}:
            self._show_aiding_tabs()
        ends = [s.end_s for s in (self.series["imu"], self.series["onboard"]) if s.end_s is not None]
        self.mode_bands.update_spans(view.events, max(ends) if ends else None)
        if isinstance(plots, StackedPlots):
            self.mode_bands.show(plots)
        # A curve switched on after the data stopped (a replay at its end) is drawn all the same.
        if self.paused or not (grew or getattr(plots, "stale", False)):
            return False
        plots.draw(self.series, self.window_s, grew, **self._following(plots))
        self.frames_drawn += 1
        return True

    def _nothing_new(self, plots) -> bool:
        """The rows wait in their tables while the samples still arriving stay in the pixel column of the
        newest one drawn (``StackedPlots.shows_nothing_new``): a 30 s window gains a column about every
        tick of the redraw timer, a 10-minute one every 25. Once they stop arriving they are drawn."""
        if self.paused or not isinstance(plots, StackedPlots):
            return False
        newest_s = max((t for t in (self.series[name].newest_s(self.session.lock) for name in ("imu", "onboard"))
                        if t is not None), default=None)
        arriving, self._newest_s = newest_s != self._newest_s, newest_s
        return arriving and newest_s is not None and plots.shows_nothing_new(newest_s)

    def redraw(self) -> None:
        """Everything visible again (window, tab, visibility or pause changed); paused, every sample of
        the curves in sight (to zoom in), the time range kept."""
        plots = self.current_plots()
        if self.series and not self.paused:
            plots.draw(self.series, self.window_s, None, **self._following(plots))
        elif self.series and isinstance(plots, StackedPlots):
            plots.show_every_sample(self.series, self.window_s)

    @staticmethod
    def _following(plots) -> dict:
        """``draw``'s arguments for a view that follows the newest data: the samples that draw each pixel column."""
        return {"pixels": True} if isinstance(plots, StackedPlots) else {}

    def current_plots(self) -> StackedPlots | PositionView:
        return self.tabs.currentWidget()
