"""An export running in a worker thread: decode the session, select rows, write the file.

No Qt here: the dialog polls ``fraction``, ``done``, ``message`` and ``error`` on its timer. A cancel
stops the decoding at its next progress report; the writers are atomic, so a cancelled or failed
export leaves nothing at the destination.
"""

from __future__ import annotations

import threading
from pathlib import Path

from groundstation.errors import UserError
from groundstation.export.columns import export_columns, select_rows
from groundstation.export.tabular import write_csv, write_parquet
from groundstation.session.data import load_session

# suffix -> (menu label, writer(columns, path, overwrite)); the Excel exporter joins here when it lands.
FORMATS = {".csv": ("CSV", write_csv), ".parquet": ("Parquet", write_parquet)}
DECODE_SHARE = 0.9  # of the progress bar: decoding is most of the time, writing the rest


class Cancelled(Exception):
    pass


class ExportJob:
    def __init__(self, source: Path, out: Path, t_from: float | None = None, t_to: float | None = None,
                 rate_hz: float | None = None, overwrite: bool = False):
        if out.suffix.lower() not in FORMATS:
            raise UserError(f"{out.name}: the name must end in {', '.join(FORMATS)}")
        self.source, self.out = Path(source), Path(out)
        self.t_from, self.t_to, self.rate_hz, self.overwrite = t_from, t_to, rate_hz, overwrite
        self.fraction = 0.0
        self.done = False
        self.message = ""  # what happened, for the user
        self.error: str | None = None
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._run, name="groundstation-export", daemon=True)

    def start(self) -> ExportJob:
        self._thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    def wait(self, timeout_s: float | None = None) -> None:
        self._thread.join(timeout_s)

    def _progress(self, done: int, total: int) -> None:
        if self._cancel.is_set():
            raise Cancelled
        self.fraction = DECODE_SHARE * done / max(total, 1)

    def _run(self) -> None:
        try:
            data = load_session(self.source, progress=self._progress)
            self._progress(1, 1)
            columns = export_columns(data, select_rows(data.time_s, self.t_from, self.t_to, self.rate_hz))
            FORMATS[self.out.suffix.lower()][1](columns, self.out, self.overwrite)
            self.fraction = 1.0
            self.message = f"wrote {self.out}: {len(columns['time_s'])} rows, {len(columns)} columns"
        except Cancelled:
            self.message = "cancelled; nothing was written"
        except UserError as error:
            self.error = str(error)
        except Exception as error:  # noqa: BLE001 — a worker's bug must reach the dialog, not vanish with the thread
            self.error = f"export failed: {type(error).__name__}: {error}"
        finally:
            self.done = True
