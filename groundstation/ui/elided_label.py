"""A label that shows as much of its text as its room allows, cut in the middle with "…" (a recording's path
keeps its folder's start and its file's name; issue 34: at 1280 px the status bar cut it at the end), the
whole text in its tooltip. In a status bar it asks for its whole text's width but makes do with ``MIN_CHARS``."""

from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

MIN_CHARS = 12  # the least it shrinks to, in average characters


class ElidedLabel(QtWidgets.QLabel):
    def __init__(self, text: str = "", parent=None):
        super().__init__(parent)
        self._full = ""
        self.setSizePolicy(QtWidgets.QSizePolicy.Preferred, QtWidgets.QSizePolicy.Preferred)
        self.setText(text)

    def setText(self, text: str) -> None:  # noqa: N802 (Qt's name)
        if text == self._full:
            return
        self._full = text
        self.setToolTip(text)
        self.updateGeometry()
        self._elide()

    def text(self) -> str:
        """The whole text (what is shown may be cut: ``shown``)."""
        return self._full

    def shown(self) -> str:
        return super().text()

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802
        hint = super().sizeHint()
        return QtCore.QSize(self.fontMetrics().horizontalAdvance(self._full) + 2 * self.margin() + 4, hint.height())

    def minimumSizeHint(self) -> QtCore.QSize:  # noqa: N802
        return QtCore.QSize(self.fontMetrics().averageCharWidth() * MIN_CHARS, super().minimumSizeHint().height())

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802
        super().resizeEvent(event)
        self._elide()

    def _elide(self) -> None:
        room = self.contentsRect().width() - 2 * self.margin()
        super().setText(self.fontMetrics().elidedText(self._full, QtCore.Qt.ElideMiddle, max(room, 0)))
