"""An export running in a worker thread: ``groundstation.export.request``'s ``run_export``.

No Qt here: the dialog polls ``fraction``, ``done``, ``message`` and ``error`` on its timer. The
request is checked when the job is made (a wrong folder or a missing pyarrow is said at once, before
any decoding). A cancel stops the decoding at its next progress report and the workbook writer within
a few thousand rows; the writers are atomic, so a cancelled or failed export leaves nothing behind.
"""

from __future__ import annotations

import threading
from pathlib import Path

from groundstation.errors import UserError
from groundstation.export import request as export


class ExportJob:
    """``load``: how the file is computed (``session_makers.load.load_session``, handed down from the window)."""

    def __init__(self, load, source: Path, out: Path, t_from: float | None = None, t_to: float | None = None,
                 rate_hz: float | None = None, overwrite: bool = False, filters=None, overrides=None):
        self._load = load
        self.request = export.export_request(source, out, filters=filters, overrides=overrides, t_from=t_from, t_to=t_to,
                                             rate_hz=rate_hz, overwrite=overwrite)
        self.source, self.out = self.request.source, self.request.out
        self.fraction = 0.0
        self.done = False
        self.message = ""  # what happened, for the user
        self.error: str | None = None
        self._decode_share = export.FORMATS[self.request.format].decode_share
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._run, name="groundstation-export", daemon=True)

    def start(self) -> ExportJob:
        self._thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    def wait(self, timeout_s: float | None = None) -> None:
        self._thread.join(timeout_s)

    def _progress(self, stage: str, done: int, total: int) -> None:
        share = done / max(total, 1)
        self.fraction = self._decode_share * share if stage == "decoding" else self._decode_share + (1 - self._decode_share) * share

    def _run(self) -> None:
        from groundstation.export.excel import ExportCancelled  # here: openpyxl need not load before the window shows

        try:
            self.message = export.run_export(self.request, self._load, self._progress, self._cancel).message
            self.fraction = 1.0
        except ExportCancelled:
            self.message = "cancelled; nothing was written"
        except UserError as error:
            self.error = str(error)
        except Exception as error:  # noqa: BLE001 — a worker's bug must reach the dialog, not vanish with the thread
            self.error = f"export failed: {type(error).__name__}: {error}"
        finally:
            self.done = True
