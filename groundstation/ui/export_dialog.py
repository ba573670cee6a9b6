"""The export dialog: format, file, time range, rate; progress and Cancel while ``ExportJob`` runs.

The file goes where the user's last export went (remembered in the settings), at first into their
Documents folder (their home without one), not beside the recording in the app's data folder, where
a user would not look for it.
"""

from __future__ import annotations

from pathlib import Path

from PySide6 import QtCore, QtWidgets

from groundstation.errors import UserError
from groundstation.export.request import FORMATS
from groundstation.ui.export_job import ExportJob

POLL_MS = 100
STATUS_LINES = 4
MIN_WIDTH_PX = 560
FOLDER_KEY = "export_folder"  # in the window's settings


def default_folder(settings: QtCore.QSettings | None) -> Path:
    """The folder of the last export if it still exists, else Documents, else home."""
    remembered = settings.value(FOLDER_KEY) if settings is not None else None
    documents = QtCore.QStandardPaths.writableLocation(QtCore.QStandardPaths.DocumentsLocation)
    for folder in (remembered, documents):
        if folder and Path(folder).is_dir():
            return Path(folder)
    return Path.home()


class ExportDialog(QtWidgets.QDialog):
    def __init__(self, load, source: Path, duration_s: float, parent=None, setup: tuple = (None, None),
                 settings: QtCore.QSettings | None = None):
        """``load``: how the file is computed (``session_makers.load.load_session``); ``setup``: the estimators
        and forced settings it is computed with (None: its own), those the window shows; ``settings``:
        where the export folder is remembered."""
        super().__init__(parent)
        self.settings = settings
        self._load = load
        self.setWindowTitle(f"Export {source.name}")
        self.source = Path(source)
        self.setup = setup
        self.job: ExportJob | None = None
        self.format_box = QtWidgets.QComboBox()
        for export_format in FORMATS.values():
            self.format_box.addItem(f"{export_format.name} ({export_format.suffix})", export_format.suffix)
        self.format_box.currentIndexChanged.connect(self._format_changed)
        name = self.source.with_suffix(self.format_box.currentData()).name
        self.path_edit = QtWidgets.QLineEdit(str(default_folder(settings) / name))
        browse = QtWidgets.QPushButton("Browse…")
        browse.clicked.connect(self._browse)
        self.t_from = self._seconds(0.0, duration_s)
        self.t_to = self._seconds(duration_s, duration_s)
        self.rate = QtWidgets.QSpinBox(minimum=0, maximum=1000, suffix=" Hz", specialValueText="every sample")
        self.overwrite = QtWidgets.QCheckBox("replace an existing file")
        self.progress = QtWidgets.QProgressBar(maximum=1000)
        self.status = QtWidgets.QLabel()
        self.status.setWordWrap(True)
        self.export_button = QtWidgets.QPushButton("Export")
        self.export_button.setDefault(True)
        self.export_button.clicked.connect(self.start)
        self.cancel_button = QtWidgets.QPushButton("Close")
        self.cancel_button.clicked.connect(self._cancel_or_close)
        file_row = QtWidgets.QHBoxLayout()
        file_row.addWidget(self.path_edit, 1)
        file_row.addWidget(browse)
        range_row = QtWidgets.QHBoxLayout()
        for widget in (self.t_from, QtWidgets.QLabel("to"), self.t_to):
            range_row.addWidget(widget)
        form = QtWidgets.QFormLayout()
        form.addRow("Format", self.format_box)
        form.addRow("File", file_row)
        form.addRow("Time range", range_row)
        form.addRow("Rate", self.rate)
        form.addRow("", self.overwrite)
        buttons = QtWidgets.QHBoxLayout()
        buttons.addStretch(1)
        buttons.addWidget(self.export_button)
        buttons.addWidget(self.cancel_button)
        # Room for the result (a path and a few figures) from the start: a word-wrapped label that
        # grows later takes its lines from the fields above it, the dialog does not grow for it.
        self.status.setMinimumHeight(STATUS_LINES * self.status.fontMetrics().lineSpacing())
        self.setMinimumWidth(MIN_WIDTH_PX)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(form)
        layout.addWidget(self.progress)
        layout.addWidget(self.status)
        layout.addLayout(buttons)
        self.timer = QtCore.QTimer(self, interval=POLL_MS, timeout=self._poll)
        self._format_changed()  # the first format's rate box

    @staticmethod
    def _seconds(value: float, maximum: float) -> QtWidgets.QDoubleSpinBox:
        box = QtWidgets.QDoubleSpinBox(decimals=1, maximum=max(maximum, 0.1), suffix=" s")
        box.setValue(value)
        return box

    def _format_changed(self) -> None:
        self.path_edit.setText(str(Path(self.path_edit.text()).with_suffix(self.format_box.currentData())))
        self.rate.setEnabled(not FORMATS[self.format_box.currentData()].every_row)  # MCAP keeps every row

    def _browse(self) -> None:
        suffix = self.format_box.currentData()
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Export to", self.path_edit.text(), f"*{suffix}")
        if path:
            self.path_edit.setText(path if path.endswith(suffix) else path + suffix)

    def start(self) -> None:
        whole = self.t_from.value() == 0.0 and self.t_to.value() == self.t_to.maximum()
        try:
            self.job = ExportJob(self._load, self.source, Path(self.path_edit.text()), None if whole else self.t_from.value(),
                                 None if whole else self.t_to.value(),
                                 (self.rate.value() or None) if self.rate.isEnabled() else None,
                                 self.overwrite.isChecked(), *self.setup).start()
        except UserError as error:
            self.status.setText(str(error))
            return
        if self.settings is not None:
            self.settings.setValue(FOLDER_KEY, str(self.job.out.parent.resolve()))
        self.export_button.setEnabled(False)
        self.cancel_button.setText("Cancel")
        self.status.setText("exporting…")
        self.timer.start()

    def _poll(self) -> None:
        job = self.job
        self.progress.setValue(int(1000 * job.fraction))
        if not job.done:
            return
        self.timer.stop()
        self.status.setText(job.error or job.message)
        self.export_button.setEnabled(True)
        self.cancel_button.setText("Close")

    def _cancel_or_close(self) -> None:
        if self.job is not None and not self.job.done:
            self.job.cancel()
            self.status.setText("cancelling…")
        else:
            self.accept()

    def closeEvent(self, event) -> None:
        if self.job is not None:
            self.job.cancel()  # the thread ends at its next progress report; its file is never half-written
        super().closeEvent(event)
