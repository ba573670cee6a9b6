"""Plot any channel, as PlotJuggler users expect: the list of every column of every table of the
session, filtered as one types in its search box; plot panes the user fills from it (drag a channel
onto a pane, double-click it, or "Add to pane"), sharing the live view's time axis and window; XY
plots of one channel against another (east against north); custom series, an expression of channels
(``custom_series``); named layouts saved and chosen from the Layouts menu.

A layout is the panes (lists of "table.column" names), the XY pairs and the custom series' expressions,
as JSON (``layout_json``); the window remembers the last one, and the named ones, in its settings.
A custom series that cannot be computed (a layout's expression refused by this version's checks, a
channel this session lacks, or past its time budget at a redraw) is switched off for the session and
said above the panes; the others draw on.
The channels are the session's catalogue (``ProductView.catalogue``, derived from the protocol spec and
the estimators): each listed by its label and unit. The sessions beside the window's (``set_others``)
list theirs under their name ("S2:imu.acc_x_g"), plotted on the window's time axis (``session.timeline``).
"""

from __future__ import annotations

import json
from collections.abc import Callable

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from groundstation.analysis.expression import Expression, ExpressionError, at_or_before
from groundstation.session.view import ProductView, Session
from groundstation.ui.custom_series import (BUDGET_S, CUSTOM, ExpressionDerive, expression_sources, expression_tables,
                                            try_on_latest_rows)
from groundstation.palette import PALETTE
from groundstation.ui.plots import LEFT_AXIS_PX, Curve, Plot, StackedPlots
from groundstation.ui.series import Series
from groundstation.ui.session_series import Other, SessionSeries

PALETTE_HEX = tuple(PALETTE.values())  # the channels' curves take the palette's colours in turn

PREFIX = "channel:"  # the series of a table's plotted columns, beside the live view's own series
MIME = "application/x-groundstation-channels"  # dragged channels: "table.column" names, one a line
LAYOUTS_KEY = "channel_layouts"  # the named layouts in the window's settings: JSON, name -> layout


def channel_names(view: ProductView, session: str = "") -> set[str]:
    """Every "table.column" the session can plot (all columns but the time); "S2:table.column" for a
    ``session`` beside the window's."""
    prefix = f"{session}:" if session else ""
    return {f"{prefix}{table.name}.{column.name}" for table, column in view.catalogue.channels()}


def series_key(channel: str) -> str:
    """The series a channel's curve reads: its table's, or a custom series' own."""
    table = channel.split(".", 1)[0]
    return PREFIX + (channel if table == CUSTOM else table)


def pane_plots(panes: list[list[str]]) -> tuple[Plot, ...]:
    """One plot per pane, a curve per "table.column", coloured in turn from the palette."""
    plots = []
    for index, channels in enumerate(panes):
        curves = tuple(Curve(series_key(name), name.split(".", 1)[1], name, PALETTE_HEX[i % len(PALETTE_HEX)])
                       for i, name in enumerate(channels))
        plots.append(Plot(f"pane {index + 1}", "", curves))
    return tuple(plots)


def read_layout(stored) -> dict:
    """A layout as ``ChannelsView.layout_json`` wrote it (or the older list of panes); ValueError if it is none."""
    layout = json.loads(stored) if isinstance(stored, str) else stored
    if isinstance(layout, list):
        layout = {"panes": layout}
    channel = lambda c: isinstance(c, str) and "." in c  # noqa: E731
    panes, xy, custom = layout.get("panes"), layout.get("xy", []), layout.get("custom", {})
    if not (isinstance(panes, list) and panes and all(isinstance(p, list) and all(map(channel, p)) for p in panes)
            and isinstance(xy, list) and all(isinstance(p, list) and len(p) == 2 and all(map(channel, p)) for p in xy)
            and isinstance(custom, dict) and all(isinstance(k, str) and isinstance(v, str) for k, v in custom.items())):
        raise ValueError("not a channels layout")
    return {"panes": panes, "xy": xy, "custom": custom}


class ChannelTree(QtWidgets.QTreeWidget):
    """The channel list; its channels drag as ``MIME``."""

    def __init__(self):
        super().__init__()
        self.setHeaderLabel("channels (drag onto a pane, or double-click)")
        self.setSelectionMode(QtWidgets.QAbstractItemView.ExtendedSelection)
        self.setDragEnabled(True)
        self.setDragDropMode(QtWidgets.QAbstractItemView.DragOnly)

    def mimeTypes(self) -> list[str]:
        return [MIME]

    def mimeData(self, items) -> QtCore.QMimeData:
        names = [item.data(0, QtCore.Qt.UserRole) for item in items if item.data(0, QtCore.Qt.UserRole)]
        data = QtCore.QMimeData()
        data.setData(MIME, "\n".join(names).encode())
        data.setText("\n".join(names))
        return data


def dropped_channels(data: QtCore.QMimeData) -> list[str]:
    return [n for n in bytes(data.data(MIME)).decode().splitlines() if n] if data.hasFormat(MIME) else []


class PanePlots(StackedPlots):
    """The panes; channels dropped on one are plotted in it (``dropped``: the names and the pane)."""

    dropped = QtCore.Signal(list, int)

    def __init__(self, plots, parent=None):
        super().__init__(plots, parent=parent)
        self.setAcceptDrops(True)

    def dragEnterEvent(self, event) -> None:
        if dropped_channels(event.mimeData()):
            event.acceptProposedAction()

    def dragMoveEvent(self, event) -> None:
        if dropped_channels(event.mimeData()):
            event.acceptProposedAction()

    def dropEvent(self, event) -> None:
        names = dropped_channels(event.mimeData())
        if not names:
            return
        y = self.mapToScene(event.position().toPoint()).y()
        # The pane under the pointer: the last whose top is above it (the legend's row counts as the first pane).
        pane = sum(1 for item in self.items[1:] if item.sceneBoundingRect().top() <= y)
        event.acceptProposedAction()
        self.dropped.emit(names, pane)


class XYPlots(pg.GraphicsLayoutWidget):
    """One plot per pair: the second channel against the first over the live view's window, the
    second's table sampled at the first's times (its newest row at or before each)."""

    def __init__(self, pairs: list[list[str]], parent=None):
        super().__init__(parent)
        self.setBackground("w")
        self.pairs = [tuple(p) for p in pairs]
        self.curves: list[pg.PlotDataItem] = []
        for index, (x, y) in enumerate(self.pairs):
            item = self.addPlot(row=0, col=index)
            item.setLabel("bottom", x)
            item.setLabel("left", y)
            item.getAxis("left").setWidth(LEFT_AXIS_PX)
            item.showGrid(x=True, y=True, alpha=0.2)
            self.curves.append(item.plot(pen=pg.mkPen(PALETTE_HEX[index % len(PALETTE_HEX)], width=1)))

    def draw(self, series: dict[str, Series], window_s: float | None) -> None:
        for (x, y), curve in zip(self.pairs, self.curves):
            sx, sy = series.get(series_key(x)), series.get(series_key(y))
            qx, qy = x.split(".", 1)[1], y.split(".", 1)[1]
            if sx is None or sy is None or not (sx.has(qx) and sy.has(qy)):
                continue
            t, xs = sx.data(qx, window_s)
            if sy is sx:
                ys = sy.data(qy, window_s)[1].astype(float)
            else:
                ys = at_or_before(t, *sy.data(qy, None if window_s is None else window_s + 60.0))  # and the row before
            curve.setData(np.asarray(xs, dtype=float), ys, connect="finite")


class CustomSeriesDialog(QtWidgets.QDialog):
    """Name and expression of a custom series; a bad expression is said here, and the dialog stays.
    ``check``: raises ExpressionError for an expression that cannot be plotted (None: no session yet)."""

    def __init__(self, check: Callable[[str], None] | None, taken: set[str], parent=None):
        super().__init__(parent)
        self.setWindowTitle("New custom series")
        self.setMinimumWidth(560)  # the hint and the reasons in a few lines, not a column of words
        self.check, self.taken = check, taken
        self.name = QtWidgets.QLineEdit(placeholderText="roll_difference_deg")
        self.expression = QtWidgets.QLineEdit(placeholderText="ahf2_roll_deg - onboard_roll_deg")
        self.message = QtWidgets.QLabel(wordWrap=True)
        self.message.setStyleSheet("color:#8b0000")
        self.message.setTextFormat(QtCore.Qt.PlainText)  # it quotes typed text
        buttons = QtWidgets.QDialogButtonBox(QtWidgets.QDialogButtonBox.Ok | QtWidgets.QDialogButtonBox.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        form = QtWidgets.QFormLayout(self)
        form.addRow("name", self.name)
        form.addRow("expression", self.expression)
        form.addRow(QtWidgets.QLabel("channels as table.column or a column's own name, the Attitude tab's "
                                     "angles (ahf2_roll_deg), another session's after its name (S2:imu.acc_z_g, S2:ahf2_roll_deg); "
                                     "+ - * / **; abs, sqrt, sin, cos, arctan2, degrees …", wordWrap=True))
        form.addRow(self.message)
        form.addRow(buttons)

    def _say(self, text: str) -> None:
        self.message.setText(text)
        self.adjustSize()  # the message's lines shown whole: a wrapped label does not grow its dialog by itself

    def accept(self) -> None:
        name = self.name.text().strip()
        if not name.isidentifier():
            self._say("the name: letters, digits and _, not starting with a digit (roll_difference_deg)")
            return
        if name in self.taken:
            self._say(f"there is a custom series {name} already")
            return
        if self.check is None:
            self._say("connect, start the demo or open a file first: the channels come from the session")
            return
        try:
            self.check(self.expression.text())
        except ExpressionError as error:
            self._say(str(error))
            return
        super().accept()


class ChannelsView(QtWidgets.QWidget):
    userInteracted = QtCore.Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.session: Session | None = None
        self.others: list[Other] = []  # the sessions beside it, whose channels are listed too
        self.settings: QtCore.QSettings | None = None  # where the named layouts are kept (``use_settings``)
        self.panes: list[list[str]] = [[]]
        self.xy: list[list[str]] = []
        self.custom: dict[str, str] = {}  # name -> expression
        self.disabled: dict[str, str] = {}  # custom series switched off for this session: name -> why
        self.budget_s = BUDGET_S  # each custom series' computation at a redraw
        self.selected_pane = 0
        self.series: dict[str, Series] = {}
        self.search = QtWidgets.QLineEdit(placeholderText="search channels")
        self.search.setClearButtonEnabled(True)
        self.search.textChanged.connect(self._filter)
        self.tree = ChannelTree()
        self.tree.itemDoubleClicked.connect(lambda item, _: self.add(item.data(0, QtCore.Qt.UserRole)))
        self.pane_box = QtWidgets.QComboBox()
        self.pane_box.currentIndexChanged.connect(self._pane_selected)
        buttons = {"Add to pane": self._add_selected, "New pane": self.new_pane,
                   "Clear pane": self.clear_pane, "Remove pane": self.remove_pane,
                   "XY of 2 selected": self._xy_selected, "Custom series…": self.new_custom}
        controls = QtWidgets.QGridLayout()
        controls.addWidget(QtWidgets.QLabel("pane"), 0, 0)
        controls.addWidget(self.pane_box, 0, 1)
        for index, (text, slot) in enumerate(buttons.items()):
            button = QtWidgets.QPushButton(text)
            button.clicked.connect(lambda _=False, slot=slot: slot())
            controls.addWidget(button, 1 + index // 2, index % 2)
        self.layouts_menu = QtWidgets.QMenu("Layouts", self)
        self.layouts_menu.aboutToShow.connect(self._fill_layouts_menu)
        layouts = QtWidgets.QToolButton(text="Layouts", popupMode=QtWidgets.QToolButton.InstantPopup)
        layouts.setMenu(self.layouts_menu)
        controls.addWidget(layouts, 1 + len(buttons) // 2, 0, 1, 2)
        left = QtWidgets.QWidget()
        left_layout = QtWidgets.QVBoxLayout(left)
        left_layout.setContentsMargins(0, 0, 0, 0)
        left_layout.addWidget(self.search)
        left_layout.addWidget(self.tree, 1)
        left_layout.addLayout(controls)
        self.note = QtWidgets.QLabel(wordWrap=True, visible=False)  # the custom series switched off, and why
        self.note.setStyleSheet("color:#8b0000")
        self.note.setTextFormat(QtCore.Qt.PlainText)  # the reasons quote typed text
        self.right = QtWidgets.QSplitter(QtCore.Qt.Vertical)
        self.stacked = self._new_plots()
        self.xy_plots = XYPlots([])
        self.right.addWidget(self.stacked)
        self.right.addWidget(self.xy_plots)
        self.splitter = QtWidgets.QSplitter()
        self.splitter.addWidget(left)
        self.splitter.addWidget(self.right)
        self.splitter.setStretchFactor(1, 1)
        self.splitter.setSizes([220, 800])
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.note)
        layout.addWidget(self.splitter, 1)  # the note as tall as its lines, the rest to the panes
        self._rebuild()

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
        taken = set()
        for key, s in list(self.series.items()):
            try:
                if s.take(self.session.lock):
                    taken.add(key)
            except ExpressionError as error:  # a custom series past its time budget: off, the others draw on
                del self.series[key]
                self._disable(key.removeprefix(f"{PREFIX}{CUSTOM}."), str(error))
        self.stacked.draw({"imu": series["imu"], **self.series}, window_s, None if grew is None else taken | {"imu"})
        if self.xy and (grew is None or taken):
            self.xy_plots.draw(self.series, window_s)

    # -- the session and the layout ----------------------------------------------------------------

    def set_session(self, session: Session | None) -> None:
        self.session = session
        self.disabled = {}  # another session: its channels may be there, its rows fewer
        self._fill_tree()
        self.stacked.clear_data()  # the same panes: only their data is new (plots are slow to build)
        self._make_series()

    def set_others(self, others: list[Other]) -> None:
        """The sessions beside the window's: their channels listed and plotted under their name, and named
        in custom series (judged again: a session's channels may have come, or gone with it)."""
        self.others = list(others)
        self.disabled = {}
        self._fill_tree()
        self.stacked.clear_data()
        self._make_series()

    def _fill_tree(self) -> None:
        self.tree.clear()
        if self.session is None:
            return
        parents: dict[str, QtWidgets.QTreeWidgetItem] = {}
        entries = [(t.name, t.label, f"{t.name}.{c.name}", c.header, c.description) for t, c in self.session.view.catalogue.channels()]
        entries += [(o.name(t.name), f"{t.label} ({o.session.source.description})", f"{o.name(t.name)}.{c.name}", c.header,
                     c.description) for o in self.others for t, c in o.session.view.catalogue.channels()]
        entries += [(CUSTOM, "custom series (expressions)", f"{CUSTOM}.{name}", name, text) for name, text in self.custom.items()]
        for table, label, channel, header, description in entries:
            if table not in parents:
                parents[table] = QtWidgets.QTreeWidgetItem([table])  # the label is a sentence
                parents[table].setToolTip(0, label)
                parents[table].setFlags(parents[table].flags() & ~QtCore.Qt.ItemIsDragEnabled)
                self.tree.addTopLevelItem(parents[table])
            child = QtWidgets.QTreeWidgetItem([header])
            child.setData(0, QtCore.Qt.UserRole, channel)
            child.setToolTip(0, description or channel)
            parents[table].addChild(child)
        self._filter(self.search.text())

    def _filter(self, text: str) -> None:
        """Show the channels whose name or label holds every word typed (any case), and their tables."""
        words = text.lower().split()
        for i in range(self.tree.topLevelItemCount()):
            parent = self.tree.topLevelItem(i)
            shown = 0
            for j in range(parent.childCount()):
                child = parent.child(j)
                haystack = f"{child.data(0, QtCore.Qt.UserRole)} {child.text(0)}".lower()
                match = all(word in haystack for word in words)
                child.setHidden(not match)
                shown += match
            parent.setHidden(not shown)
            parent.setExpanded(bool(words) and bool(shown))

    def layout_json(self) -> str:
        return json.dumps({"panes": self.panes, "xy": self.xy, "custom": self.custom})

    def restore_layout(self, stored: str | None) -> None:
        """A layout as ``layout_json`` wrote it (or the older list of panes); anything unreadable leaves one empty pane."""
        try:
            layout = read_layout(stored) if stored else None
        except ValueError:
            layout = None
        layout = layout or {"panes": [[]], "xy": [], "custom": {}}
        self.panes, self.xy, self.custom = layout["panes"], layout["xy"], layout["custom"]
        self.disabled = {}
        self.selected_pane = 0
        self._fill_tree()
        self._rebuild()

    def use_settings(self, settings: QtCore.QSettings) -> None:
        """The window's settings: the last layout ("channel_panes") now, the named layouts when asked."""
        self.settings = settings
        self.restore_layout(settings.value("channel_panes"))

    def named_layouts(self) -> dict[str, str]:
        try:
            stored = json.loads(self.settings.value(LAYOUTS_KEY) or "{}") if self.settings is not None else {}
        except ValueError:
            return {}  # a damaged settings file must not break the menu
        return stored if isinstance(stored, dict) else {}

    def save_layout(self, name: str) -> None:
        if self.settings is not None and name.strip():
            self.settings.setValue(LAYOUTS_KEY, json.dumps({**self.named_layouts(), name.strip(): self.layout_json()}))

    def _fill_layouts_menu(self) -> None:
        menu = self.layouts_menu
        menu.clear()
        menu.addAction("Save layout as…").triggered.connect(lambda _=False: self._ask_layout_name())
        named = self.named_layouts()
        if named:
            menu.addSeparator()
        for name, stored in sorted(named.items()):
            menu.addAction(name).triggered.connect(lambda _=False, s=stored: self.restore_layout(s))

    def _ask_layout_name(self) -> None:
        name, ok = QtWidgets.QInputDialog.getText(self, "Save layout", "name of this layout")
        if ok:
            self.save_layout(name)

    def add(self, channel: str | None, pane: int | None = None) -> None:
        """Plot ``channel`` ("table.column") in ``pane`` (the selected one by default)."""
        pane = self.selected_pane if pane is None else pane
        if channel and channel not in self.panes[pane]:
            self.panes[pane].append(channel)
            self._rebuild()

    def add_xy(self, x: str, y: str) -> None:
        """An XY plot of ``y`` against ``x`` ("table.column" each)."""
        if [x, y] not in self.xy:
            self.xy.append([x, y])
            self._rebuild()

    def add_custom(self, name: str, expression: str) -> None:
        """A custom series ``name`` (listed under "custom"); plot it as any channel: "custom.NAME"."""
        self.custom[name] = expression
        self._fill_tree()
        self._make_series()

    def check_expression(self, text: str) -> None:
        """``text`` as an expression of the sessions' channels, tried once on its latest rows (ExpressionError: why not)."""
        sources = expression_sources(self.session.view, self.others)
        try_on_latest_rows(Expression(text, sources), sources, expression_tables(self.session.view, self.session.lock, self.others))

    def new_custom(self) -> CustomSeriesDialog:
        """The dialog asking a custom series' name and expression (checked against the session's channels)."""
        dialog = CustomSeriesDialog(self.check_expression if self.session is not None else None, set(self.custom), self)
        dialog.accepted.connect(lambda: self.add_custom(dialog.name.text().strip(), dialog.expression.text()))
        dialog.open()
        return dialog

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

    def _xy_selected(self) -> None:
        chosen = [c for c in (item.data(0, QtCore.Qt.UserRole) for item in self.tree.selectedItems()) if c]
        if len(chosen) == 2:
            self.add_xy(*chosen)

    def _dropped(self, channels: list[str], pane: int) -> None:
        self.selected_pane = min(pane, len(self.panes) - 1)
        for channel in channels:
            self.add(channel)

    def _pane_selected(self, index: int) -> None:
        if index >= 0:
            self.selected_pane = index

    def _fill_pane_box(self) -> None:
        self.pane_box.blockSignals(True)
        self.pane_box.clear()
        self.pane_box.addItems([f"pane {i + 1}" for i in range(len(self.panes))])
        self.pane_box.setCurrentIndex(self.selected_pane)
        self.pane_box.blockSignals(False)

    def _new_plots(self) -> PanePlots:
        plots = PanePlots(pane_plots(self.panes))
        plots.userInteracted.connect(self.userInteracted)
        plots.dropped.connect(self._dropped)
        return plots

    def _rebuild(self) -> None:
        """New plots for the panes and the XY pairs, and the series they draw."""
        old, self.stacked = self.stacked, self._new_plots()
        self.right.replaceWidget(0, self.stacked)
        old.deleteLater()
        old, self.xy_plots = self.xy_plots, XYPlots(self.xy)
        self.right.replaceWidget(1, self.xy_plots)
        old.deleteLater()
        self.xy_plots.setVisible(bool(self.xy))
        if self.xy:  # the time panes and the XY plots share the height, 3 to 2
            height = max(self.right.height(), 500)
            self.right.setSizes([height * 3 // 5, height * 2 // 5])
        self._fill_pane_box()
        self._make_series()

    def _make_series(self) -> None:
        """A series for each plotted table of the session, holding only its plotted columns (from its
        oldest row kept: a channel added later shows its past too), and one per plotted custom series;
        a custom series that this session cannot compute is switched off and said."""
        self.series = {}
        if self.session is None:
            self._show_disabled()
            return
        view = self.session.view
        known = channel_names(view).union(*(channel_names(o.session.view, o.label) for o in self.others))
        sources = expression_sources(view, self.others)
        tables = expression_tables(view, self.session.lock, self.others)
        derives: dict[str, ExpressionDerive] = {}
        for name, text in self.custom.items():
            if name not in self.disabled:
                try:
                    derives[name] = ExpressionDerive(name, Expression(text, sources), sources, tables, self.budget_s)
                except ExpressionError as error:
                    self.disabled[name] = str(error)
        wanted: dict[str, list[str]] = {}
        plotted = [c for pane in self.panes for c in pane] + [c for pair in self.xy for c in pair]
        for channel in dict.fromkeys(plotted):
            table, column = channel.split(".", 1)
            if channel in known:
                wanted.setdefault(table, []).append(column)
            elif table == CUSTOM and column in derives:
                rows, lock = tables[derives[column].table]
                self.series[series_key(channel)] = SessionSeries(rows, derives[column], lock)
        for table, columns in wanted.items():  # "S2:imu": session S2's table imu, on the window's axis
            derive = lambda rows, names, columns=tuple(columns): {c: rows[:, names.index(c)] for c in columns}  # noqa: E731
            rows, lock = tables[table]
            self.series[PREFIX + table] = SessionSeries(rows, derive, lock)
        self._show_disabled()

    def _disable(self, name: str, reason: str) -> None:
        self.disabled[name] = reason
        self._show_disabled()

    def _show_disabled(self) -> None:
        """The note above the panes: each custom series switched off, and why."""
        self.note.setText("\n".join(f"custom series {name} is off: {reason}" for name, reason in self.disabled.items()))
        self.note.setVisible(bool(self.disabled))
