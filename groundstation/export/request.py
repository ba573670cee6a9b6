"""The one way to export a session, for the CLI's ``export`` and the app's export dialog alike, and the
export formats' registry (``FORMATS``): a new format is its writer module and one ``register`` line here;
the CLI's help, the app's export dialog and the README's formats table (checked by a test) derive from it.

``export_request`` checks everything the user chose before any decoding (format, source, destination
folder and its permission, overwrite, Parquet's optional pyarrow, time range and rate), so a mistake
costs no waiting; ``run_export`` decodes and writes atomically (``files.atomic_output``), so a failure
or a cancel leaves nothing at the destination.

    request = export_request("flight.gsrec", "flight.xlsx", t_from=10, t_to=70)   # UserError if wrong
    result = run_export(request, load_session, progress=lambda stage, done, total: ..., cancel=threading.Event())
"""

from __future__ import annotations

import dataclasses
import os
import secrets
from collections.abc import Callable
from pathlib import Path

from groundstation.errors import UserError
from groundstation.formats import resolve


@dataclasses.dataclass(frozen=True)
class ExportFormat:
    suffix: str  # lower case with the dot: the destination's name chooses the format by it
    name: str  # what the user calls it
    # (data, request, writing(done, total), cancel) -> (what was written, for "wrote OUT: ...", warnings), or
    # "module:function" naming it: imported when used, so that this module stays light (``groundstation --help``)
    write: str | Callable
    decode_share: float  # of a progress bar, the decoding's (the writing takes the rest): a workbook is slow to write
    streamed: bool = False  # rows written a stretch at a time as the estimators run along (``stream_estimates``): the
    #                         export's memory does not grow with the session's length
    every_row: bool = False  # every row of every table at its own rate: ``--rate`` does not apply

    def writer(self) -> Callable:
        return resolve(self.write)


FORMATS: dict[str, ExportFormat] = {}  # by suffix


def register(export_format: ExportFormat) -> ExportFormat:
    FORMATS[export_format.suffix] = export_format
    return export_format


register(ExportFormat(".xlsx", "Excel", "groundstation.export.excel:export_workbook", decode_share=0.4))
register(ExportFormat(".csv", "CSV", "groundstation.export.tabular:export_csv", decode_share=0.9, streamed=True))
register(ExportFormat(".parquet", "Parquet", "groundstation.export.tabular:export_parquet", decode_share=0.9, streamed=True))
register(ExportFormat(".mcap", "MCAP", "groundstation.export.mcap_file:export_mcap", decode_share=0.5, every_row=True))


def either(words) -> str:
    """``a, b, c or d``: a choice as a help line says it."""
    words = list(words)
    return " or ".join([", ".join(words[:-1]), words[-1]]) if len(words) > 1 else "".join(words)


@dataclasses.dataclass(frozen=True)
class ExportRequest:
    source: Path
    out: Path
    filters: list[str] | None = None  # None: the file's own or the default set, those its data met (``met``)
    overrides: dict[str, dict[str, float]] = dataclasses.field(default_factory=dict)  # --set
    t_from: float | None = None
    t_to: float | None = None
    rate_hz: float | None = None
    overwrite: bool = False
    accept_config_changes: bool = False  # a CONFIG changing the scales without a device restart applies

    @property
    def format(self) -> str:
        return self.out.suffix.lower()


@dataclasses.dataclass(frozen=True)
class ExportResult:
    message: str  # "wrote OUT: ..."
    warnings: list[str]  # what the source recording had lost and the session's warnings (SessionData.warnings)


def export_request(source, out, *, filters=None, overrides=None, t_from=None, t_to=None, rate_hz=None,
                   overwrite: bool = False, accept_config_changes: bool = False) -> ExportRequest:
    """The request, once everything in it is known to be possible; UserError says what is not."""
    request = ExportRequest(Path(source), Path(out), filters, dict(overrides or {}), t_from, t_to, rate_hz, overwrite,
                            accept_config_changes)
    if request.format not in FORMATS:
        raise UserError(f"{request.out.name}: the name must end in {either(FORMATS)}")
    from groundstation.export.columns import check_row_options  # numpy: not at the top (see ExportFormat.write)

    check_row_options(t_from, t_to, rate_hz)
    if FORMATS[request.format].every_row and rate_hz is not None:
        raise UserError(f"--rate does not apply to {FORMATS[request.format].name}: it keeps every row of every table "
                        "at its own rate")
    if not request.source.is_file():
        raise UserError(f"{request.source}: no such file")
    if request.out.resolve() == request.source.resolve():
        raise UserError(f"{request.out} is the file being exported; choose another name")
    check_destination(request.out, overwrite)
    return request


def check_destination(out: Path, overwrite: bool) -> None:
    """The folder exists and takes a new file (tried, not guessed from permission bits); ``out`` is free."""
    folder = out.parent
    if not folder.is_dir():
        raise UserError(f"cannot write {out}: the folder {folder} does not exist")
    if out.is_dir():
        raise UserError(f"cannot write {out}: it is a folder")
    if out.exists() and not overwrite:
        raise UserError(f"{out} exists; choose another name or pass --overwrite")
    probe = folder / f".{out.name}.{secrets.token_hex(4)}.probe"
    try:
        os.close(os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
    except OSError as error:
        raise UserError(f"cannot write in {folder}: {error.strerror}") from None
    probe.unlink()


def met(data):
    """``data`` with only the estimators whose needs its data met (``SessionData.aiding``): without a
    magnetometer HF+mag is HF and ECF+mag is ECF, without GPS the unscented filters are tilt filters,
    and a column of each would only repeat another. Asked for by name (``filters``), they are exported."""
    from groundstation.estimation import runnable

    return dataclasses.replace(data, filters=runnable(data.aiding(), data.filters))


def run_export(request: ExportRequest, load: Callable, progress: Callable[[str, int, int], None] | None = None,
               cancel=None) -> ExportResult:
    """Computes ``request.source`` with ``load`` (``session_makers.load.load_session``: the caller's, so that the
    exports import no maker of sessions; exact: the estimators' columns as computed, float64) and writes ``request.out`` with its format's writer; ``progress(stage,
    done, total)`` with stage "decoding" then "writing"; ``cancel`` (a ``threading.Event``) raises
    ExportCancelled, nothing written."""
    from groundstation.estimation import unmet_warnings
    from groundstation.export.files import ExportCancelled  # not excel's module: openpyxl and pandas are ~70 MB
    report = progress or (lambda stage, done, total: None)

    def decoding(done: int, total: int) -> None:
        if cancel is not None and cancel.is_set():
            raise ExportCancelled("export cancelled; nothing was written")
        report("decoding", done, total)

    export_format = FORMATS[request.format]
    data = load(request.source, request.filters, request.overrides, decoding, request.accept_config_changes,
                stream_estimates=export_format.streamed, exact=True)
    decoding(1, 1)
    # asked for by name, an estimator without its aiding is exported, and said to be little use so
    asked = () if request.filters is None else data.filters
    if request.filters is None:
        data = met(data)
    doubted = unmet_warnings(asked, data.aiding(), request.source)
    written, warnings = export_format.writer()(data, request, lambda done, total: report("writing", done, total), cancel)
    return ExportResult(f"wrote {request.out}: {written}", [*data.warnings, *doubted, *warnings])
