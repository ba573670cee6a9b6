"""File > Flight report…: the current (or last) session's file computed in a worker thread and written
as a flight report (``export.report``), the window told where when it is done. Qt-free: the window
polls ``done`` on a timer, as it does for an export."""

from __future__ import annotations

import threading
from pathlib import Path

from groundstation.errors import UserError
from groundstation.export.report import write_report
from groundstation.export.request import check_destination


class ReportJob:
    """``load``: how the file is computed (``session_makers.load.load_session``, handed down from the window);
    ``setup``: the estimators and forced settings the window shows (None: the file's own)."""

    def __init__(self, load, source: Path, out: Path, setup: tuple = (None, None)):
        self.source, self.out = Path(source), Path(out)
        if self.out.suffix.lower() not in (".html", ".htm"):
            self.out = self.out.with_suffix(".html")
        check_destination(self.out, overwrite=True)  # the file dialog has asked before replacing one
        self._load, self._setup = load, setup
        self.done = False
        self.message = ""
        self.error: str | None = None
        self._thread = threading.Thread(target=self._run, name="groundstation-report", daemon=True)

    def start(self) -> ReportJob:
        self._thread.start()
        return self

    def wait(self, timeout_s: float | None = None) -> None:
        self._thread.join(timeout_s)

    def _run(self) -> None:
        try:
            data = self._load(self.source, *self._setup, exact=True)
            self.message = f"Flight report of {self.source.name} written to {write_report(data, self.out, self.source.name, overwrite=True)}"
        except UserError as error:
            self.error = str(error)
        except Exception as error:  # noqa: BLE001 — a worker's bug must reach the window, not vanish with the thread
            self.error = f"flight report failed: {type(error).__name__}: {error}"
        finally:
            self.done = True
