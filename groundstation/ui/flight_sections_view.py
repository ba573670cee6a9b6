"""The Flight tab: a flight log's sections (``autopilot.sections``) as a flyer reads them in Mission Planner
or Flight Review: the attitude asked for against the one had, the same for the body rates, the battery, the
GPS quality and the actuator outputs. A row of buttons picks the page (``sections.pages_of``: the ones the
session has; the report draws the same); its plots share the session's time axis and window as every other
tab's. The tab shows once the session has a section (``live_view.AIDING_TABS``).
"""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

from groundstation.autopilot.sections import NAMES, Page, pages_of
from groundstation.session.view import Session
from groundstation.ui.navigation import columns_of
from groundstation.ui.plots import Curve, Plot, StackedPlots
from groundstation.ui.series import Series

PREFIX = "section:"  # a section table's series in the live view's series, apart from the aiding ones ("gps")
SERIES = tuple(PREFIX + name for name in NAMES)
NONE_TEXT = "No flight sections in this session (an autopilot's setpoints, battery, GPS and outputs)"


def section_series(tables: dict) -> dict[str, Series]:
    """A ``Series`` for each section table the session has, every column as it is (already in its unit)."""
    return {PREFIX + name: Series(tables[name], _as_is) for name in NAMES if tables.get(name) is not None}


def _as_is(rows, columns: tuple[str, ...]) -> dict:
    return {name: values for name, values in columns_of(rows, columns).items() if name != "time_s"}


def page_plots(page: Page) -> tuple[Plot, ...]:
    return tuple(Plot(f.title, f.unit, tuple(Curve(PREFIX + t.table, t.column, t.label, t.colour, f.wraps_at) for t in f.traces))
                 for f in page.figures)


class FlightSectionsView(QtWidgets.QWidget):
    """A button per page the session has, and that page's plots (a ``StackedPlots`` the live view draws through
    ``draw``, as it draws any tab)."""

    userInteracted = QtCore.Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.buttons = QtWidgets.QButtonGroup(self)
        self._bar = QtWidgets.QHBoxLayout()
        self._bar.setContentsMargins(4, 2, 4, 2)
        self._bar.addStretch(1)
        self.plots: StackedPlots | None = None  # the page's plots; None: the session has no section
        self._shown: QtWidgets.QWidget = QtWidgets.QLabel(NONE_TEXT, alignment=QtCore.Qt.AlignCenter)
        self._layout = QtWidgets.QVBoxLayout(self)
        self._layout.setContentsMargins(0, 0, 0, 0)
        self._layout.addLayout(self._bar)
        self._layout.addWidget(self._shown, 1)
        self.page: Page | None = None

    def set_session(self, session: Session | None) -> None:
        """Offer the pages ``session`` has; show the one shown before if it has it, else its first."""
        for button in self.buttons.buttons():
            self.buttons.removeButton(button)
            self._bar.removeWidget(button)
            button.deleteLater()
        pages = pages_of(session.view.catalogue) if session is not None else []
        for i, page in enumerate(pages):
            button = QtWidgets.QPushButton(page.title, checkable=True)
            button.clicked.connect(lambda _=False, p=page: self.show_page(p))
            self.buttons.addButton(button)
            self._bar.insertWidget(i, button)
        same = [p for p in pages if self.page is not None and p.title == self.page.title]
        self.show_page((same or pages or [None])[0])

    def show_page(self, page: Page | None) -> None:
        self.page = page
        for button in self.buttons.buttons():
            button.setChecked(page is not None and button.text() == page.title)
        if page is None and self.plots is None:
            return
        old = self._shown
        if page is not None:
            self.plots = self._shown = StackedPlots(page_plots(page))
            self.plots.userInteracted.connect(self.userInteracted)
        else:
            self.plots, self._shown = None, QtWidgets.QLabel(NONE_TEXT, alignment=QtCore.Qt.AlignCenter)
        self._layout.replaceWidget(old, self._shown)
        old.deleteLater()

    # -- what the live view asks of a tab --------------------------------------------------------

    @property
    def items(self) -> list:
        return self.plots.items if self.plots is not None else []

    @property
    def stale(self) -> bool:
        return self.plots is not None and self.plots.stale

    def draw(self, series: dict[str, Series], window_s: float | None, grew: set[str] | None) -> None:
        if self.plots is not None:
            self.plots.draw(series, window_s, grew)

    def clear_data(self) -> None:
        if self.plots is not None:
            self.plots.clear_data()
