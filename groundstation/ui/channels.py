"""Plot any channel: the list of every column of every table of the session, and plot panes the user
fills from it (double-click a channel, or "Add to pane"); the panes share the live view's time
axis and window. The layout (which channels in which pane) is kept as a list of lists of
"table.column" names, which the window remembers in its settings.

The channels are the session's catalogue (``ProductView.catalogue``, derived from the protocol spec and
the estimators): each listed by its label and unit.
"""

from __future__ import annotations

import json

from PySide6 import QtCore, QtWidgets

from groundstation.session.view import Session
from groundstation.session.view import ProductView
from groundstation.ui.plots import PALETTE, Curve, Plot, StackedPlots
from groundstation.ui.series import Series

PALETTE_HEX = tuple(PALETTE.values())  # the channels' curves take the palette's colours in turn

PREFIX = "channel:"  # the series of a table's plotted columns, beside the live view's own series


def channel_names(view: ProductView) -> set[str]:
    """Every "table.column" the session can plot (all columns but the time)."""
    return {f"{table.name}.{column.name}" for table, column in view.catalogue.channels()}


def pane_plots(panes: list[list[str]]) -> tuple[Plot, ...]:
    """One plot per pane, a curve per "table.column", coloured in turn from the palette."""
    plots = []
    for index, channels in enumerate(panes):
        curves = tuple(Curve(PREFIX + name.split(".", 1)[0], name.split(".", 1)[1], name,
                             PALETTE_HEX[i % len(PALETTE_HEX)]) for i, name in enumerate(channels))
        plots.append(Plot(f"pane {index + 1}", "", curves))
    return tuple(plots)


class ChannelsView(QtWidgets.QWidget):
    userInteracted = QtCore.Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.session: Session | None = None
        self.panes: list[list[str]] = [[]]
        self.selected_pane = 0
        self.series: dict[str, Series] = {}
        self.tree = QtWidgets.QTreeWidget()
        self.tree.setHeaderLabel("channels (double-click to plot)")
        self.tree.itemDoubleClicked.connect(lambda item, _: self.add(item.data(0, QtCore.Qt.UserRole)))
        self.pane_box = QtWidgets.QComboBox()
        self.pane_box.currentIndexChanged.connect(self._pane_selected)
        buttons = {"Add to pane": self._add_selected, "New pane": self.new_pane,
                   "Clear pane": self.clear_pane, "Remove pane": self.remove_pane}
        controls = QtWidgets.QGridLayout()
        controls.addWidget(QtWidgets.QLabel("pane"), 0, 0)
        controls.addWidget(self.pane_box, 0, 1)
        for index, (text, slot) in enumerate(buttons.items()):
            button = QtWidgets.QPushButton(text)
            button.clicked.connect(slot)
            controls.addWidget(button, 1 + index // 2, index % 2)
        left = QtWidgets.QWidget()
        left_layout = QtWidgets.QVBoxLayout(left)
        left_layout.setContentsMargins(0, 0, 0, 0)
        left_layout.addWidget(self.tree, 1)
        left_layout.addLayout(controls)
        self.splitter = QtWidgets.QSplitter()
        self.splitter.addWidget(left)
        self.stacked = self._new_plots()
        self.splitter.addWidget(self.stacked)
        self.splitter.setStretchFactor(1, 1)
        self.splitter.setSizes([220, 800])
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.splitter)
        self._fill_pane_box()

    # -- what the live view asks of a tab --------------------------------------------------------

    @property
    def items(self):
        return self.stacked.items

    @property
    def stale(self) -> bool:
        return self.stacked.stale

    def clear_data(self) -> None:
        self.stacked.clear_data()

    def draw(self, series: dict[str, Series], window_s: float | None, grew: set[str] | None) -> None:
        """Take the plotted tables' new rows, then draw with the live view's IMU series as the clock."""
        if self.session is None:
            return
        taken = {name for name, s in self.series.items() if s.take(self.session.lock)}
        self.stacked.draw({"imu": series["imu"], **self.series}, window_s, None if grew is None else taken | {"imu"})

    # -- the session and the layout ----------------------------------------------------------------

    def set_session(self, session: Session | None) -> None:
        self.session = session
        self.tree.clear()
        if session is not None:
            parents: dict[str, QtWidgets.QTreeWidgetItem] = {}
            for table, column in session.view.catalogue.channels():
                if table.name not in parents:
                    parents[table.name] = QtWidgets.QTreeWidgetItem([table.name])  # the label is a sentence
                    parents[table.name].setToolTip(0, table.label)
                    self.tree.addTopLevelItem(parents[table.name])
                child = QtWidgets.QTreeWidgetItem([column.header])
                child.setData(0, QtCore.Qt.UserRole, f"{table.name}.{column.name}")
                child.setToolTip(0, column.description or f"{table.name}.{column.name}")
                parents[table.name].addChild(child)
        self.stacked.clear_data()  # the same panes: only their data is new (plots are slow to build)
        self._make_series()

    def layout_json(self) -> str:
        return json.dumps(self.panes)

    def restore_layout(self, stored: str | None) -> None:
        """Panes as ``layout_json`` wrote them; anything unreadable leaves one empty pane."""
        try:
            panes = json.loads(stored) if stored else [[]]
            if not (isinstance(panes, list) and panes and all(isinstance(p, list) and all(isinstance(c, str) and "." in c
                                                                                          for c in p) for p in panes)):
                raise ValueError
        except ValueError:
            panes = [[]]
        self.panes = panes
        self.selected_pane = 0
        self._rebuild()

    def add(self, channel: str | None, pane: int | None = None) -> None:
        """Plot ``channel`` ("table.column") in ``pane`` (the selected one by default)."""
        pane = self.selected_pane if pane is None else pane
        if channel and channel not in self.panes[pane]:
            self.panes[pane].append(channel)
            self._rebuild()

    def new_pane(self) -> None:
        self.panes.append([])
        self.selected_pane = len(self.panes) - 1
        self._rebuild()

    def clear_pane(self) -> None:
        self.panes[self.selected_pane] = []
        self._rebuild()

    def remove_pane(self) -> None:
        if len(self.panes) > 1:
            del self.panes[self.selected_pane]
            self.selected_pane = min(self.selected_pane, len(self.panes) - 1)
            self._rebuild()

    def _add_selected(self) -> None:
        for item in self.tree.selectedItems():
            self.add(item.data(0, QtCore.Qt.UserRole))

    def _pane_selected(self, index: int) -> None:
        if index >= 0:
            self.selected_pane = index

    def _fill_pane_box(self) -> None:
        self.pane_box.blockSignals(True)
        self.pane_box.clear()
        self.pane_box.addItems([f"pane {i + 1}" for i in range(len(self.panes))])
        self.pane_box.setCurrentIndex(self.selected_pane)
        self.pane_box.blockSignals(False)

    def _new_plots(self) -> StackedPlots:
        plots = StackedPlots(pane_plots(self.panes))
        plots.userInteracted.connect(self.userInteracted)
        return plots

    def _rebuild(self) -> None:
        """New plots for the panes, and the series they draw."""
        old, self.stacked = self.stacked, self._new_plots()
        self.splitter.replaceWidget(1, self.stacked)
        old.deleteLater()
        self._fill_pane_box()
        self._make_series()

    def _make_series(self) -> None:
        """A series for each plotted table of the session, holding only its plotted columns (from its
        first row: a channel added later shows its past too)."""
        self.series = {}
        if self.session is None:
            return
        known = channel_names(self.session.view)
        wanted: dict[str, list[str]] = {}
        for channel in (c for pane in self.panes for c in pane if c in known):
            table, column = channel.split(".", 1)
            wanted.setdefault(table, []).append(column)
        for table, columns in wanted.items():
            self.series[PREFIX + table] = Series(self.session.view.tables[table], lambda rows, names, columns=tuple(
                columns): {c: rows[:, names.index(c)] for c in columns})
