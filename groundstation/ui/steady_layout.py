"""Rows that come and go without moving the plots (issue 34: the progress bar, the replay bar and the banners
pushed the plots down and up, and a click aimed at a curve landed elsewhere).

- ``ReservedStrip``: the rows of one place (the replay bar, and over it while a file is computed the progress
  bar) in a strip of a fixed height, reserved whether or not one shows. The window puts it beside the time window
  and the pause, in a row every session uses: no band of nothing over the live plots.
- ``BannerOverlay``: the banners (an error, a stopped recording, a changed configuration) over the top of the
  plots, as wide as they are and as tall as the banners shown; hidden, and so not in the mouse's way, when none is.
"""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets


class ReservedStrip(QtWidgets.QWidget):
    """``rows`` in one cell, the later over the earlier (painted with their background), in a strip as tall as
    the tallest."""

    def __init__(self, *rows: QtWidgets.QWidget, parent=None):
        super().__init__(parent)
        layout = QtWidgets.QGridLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        for row in rows:
            layout.addWidget(row, 0, 0)
        for row in rows[1:]:
            row.setAutoFillBackground(True)  # hides the row beneath while it shows
        self.setFixedHeight(max(row.sizeHint().height() for row in rows))


class BannerOverlay(QtWidgets.QWidget):
    """``banners`` stacked over the top of ``host`` (a sibling: a splitter takes its children as panes)."""

    def __init__(self, host: QtWidgets.QWidget, banners: tuple[QtWidgets.QWidget, ...]):
        super().__init__(host.parentWidget())
        self.host = host
        self.banners = banners
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.setSpacing(2)
        for banner in banners:
            layout.addWidget(banner)
            banner.installEventFilter(self)
        host.installEventFilter(self)
        self._place()

    def eventFilter(self, watched, event) -> bool:  # noqa: N802 (Qt's name)
        kind = event.type()
        if kind in (QtCore.QEvent.ShowToParent, QtCore.QEvent.HideToParent):
            self._place()  # at once: whoever showed a banner finds it shown
        if kind in (QtCore.QEvent.ShowToParent, QtCore.QEvent.HideToParent, QtCore.QEvent.Resize,
                    QtCore.QEvent.Move, QtCore.QEvent.LayoutRequest):
            QtCore.QTimer.singleShot(0, self._place)  # and again once its text has set its height
        return False

    def _place(self) -> None:
        shown = any(not banner.isHidden() for banner in self.banners)
        if shown:
            width = self.host.width()
            height = self.layout().heightForWidth(width) if self.layout().hasHeightForWidth() else self.sizeHint().height()
            self.setGeometry(self.host.x(), self.host.y(), width, height)
            self.raise_()
        self.setVisible(shown)
