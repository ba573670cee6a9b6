"""An export running in a worker thread: decode the session, select rows, write the file.

No Qt here: the dialog polls ``fraction``, ``done``, ``message`` and ``error`` on its timer. A cancel
stops the decoding at its next progress report and the workbook writer within a few thousand rows;
the writers are atomic, so a cancelled or failed export leaves nothing at the destination.
"""

from __future__ import annotations

import threading
from pathlib import Path

from groundstation.errors import UserError
from groundstation.export.columns import export_columns, select_rows
from groundstation.export.excel import ExportCancelled, write_workbook
from groundstation.export.tabular import write_csv, write_parquet
from groundstation.session.data import SessionData, load_session

# suffix -> (menu label, share of the progress bar the decoding takes; the writing takes the rest)
FORMATS = {".xlsx": ("Excel", 0.4), ".csv": ("CSV", 0.9), ".parquet": ("Parquet", 0.9)}


class ExportJob:
    def __init__(self, source: Path, out: Path, t_from: float | None = None, t_to: float | None = None,
                 rate_hz: float | None = None, overwrite: bool = False):
        self.suffix = out.suffix.lower()
        if self.suffix not in FORMATS:
            raise UserError(f"{out.name}: the name must end in {', '.join(FORMATS)}")
        self.source, self.out = Path(source), Path(out)
        self.t_from, self.t_to, self.rate_hz, self.overwrite = t_from, t_to, rate_hz, overwrite
        self.fraction = 0.0
        self.done = False
        self.message = ""  # what happened, for the user
        self.error: str | None = None
        self._decode_share = FORMATS[self.suffix][1]
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._run, name="groundstation-export", daemon=True)

    def start(self) -> ExportJob:
        self._thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    def wait(self, timeout_s: float | None = None) -> None:
        self._thread.join(timeout_s)

    def _decoding(self, done: int, total: int) -> None:
        if self._cancel.is_set():
            raise ExportCancelled
        self.fraction = self._decode_share * done / max(total, 1)

    def _writing(self, done: int, total: int) -> None:
        self.fraction = self._decode_share + (1.0 - self._decode_share) * done / max(total, 1)

    def _run(self) -> None:
        try:
            data = load_session(self.source, progress=self._decoding)
            self._decoding(1, 1)
            written = self._workbook(data) if self.suffix == ".xlsx" else self._table(data)
            self.fraction = 1.0
            self.message = f"wrote {self.out}: {written}"
        except ExportCancelled:
            self.message = "cancelled; nothing was written"
        except UserError as error:
            self.error = str(error)
        except Exception as error:  # noqa: BLE001 — a worker's bug must reach the dialog, not vanish with the thread
            self.error = f"export failed: {type(error).__name__}: {error}"
        finally:
            self.done = True

    def _table(self, data: SessionData) -> str:
        columns = export_columns(data, select_rows(data.time_s, self.t_from, self.t_to, self.rate_hz))
        (write_csv if self.suffix == ".csv" else write_parquet)(columns, self.out, self.overwrite)
        return f"{len(columns['time_s'])} rows, {len(columns)} columns"

    def _workbook(self, data: SessionData) -> str:
        sheets = write_workbook(data, self.out, t_from=self.t_from, t_to=self.t_to, rate_hz=self.rate_hz,
                                overwrite=self.overwrite, progress=self._writing, cancel=self._cancel)
        return "sheets " + ", ".join(sheets)
