"""One log's rows of the folder dataset, and its tables beside them: what each worker does.

``summarise`` runs in a worker process (or a Dask worker): it opens the log, writes its tables under
``OUT/tables/<table>/log_id=<id>/`` and returns the log's rows (plain Python values, cheap to send back).
A log that cannot be read gives one row with its ``error``: it never stops the batch.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from groundstation.errors import UserError
from groundstation.names import path_name, under

# The columns of logs.parquet, in order: first the log's, then one estimator's figures.
LOG_COLUMNS = {
    "log_id": "string", "path": "string", "format": "string", "vehicle": "string", "firmware": "string",
    "duration_s": "double", "samples": "int64", "imu_rate_hz": "double", "link_loss_pct": "double",
    "warnings": "string", "error": "string",
    # the vibration view's figures over the whole log (analysis.vibration): RMS above 5 Hz, the strongest peak
    "vibration_accel_m_s2": "double", "vibration_gyro_deg_s": "double", "vibration_peak_hz": "double",
    "vibration_source": "string",
    # the flight report's findings (export.report_findings): how many, the worst severity and its title
    "findings": "int64", "worst_severity": "string", "worst_finding": "string",
    "estimator": "string", "reference": "string",  # reference: "truth", "onboard" or null (nothing to compare with)
    "incl_rmse_deg": "double", "incl_max_deg": "double", "heading_rmse_deg": "double", "heading_max_deg": "double",
    "pitch_rms_deg": "double", "pitch_max_deg": "double", "roll_rms_deg": "double", "roll_max_deg": "double",
}


def log_id(path: Path, root: Path) -> str:
    """A stable id of a log: the first 12 hex digits of the SHA-1 of its path under the folder."""
    return hashlib.sha1(path.relative_to(root).as_posix().encode()).hexdigest()[:12]


def log_fields(path: Path, root: Path) -> dict:
    from groundstation import formats

    file_format = formats.sniff(path)
    fields = {c: None for c in LOG_COLUMNS}
    fields.update(log_id=log_id(path, root), path=path.relative_to(root).as_posix(),
                  format=file_format.name if file_format else None)
    return fields


def summarise(path, root, out, filters=None, page: bool = False) -> list[dict]:
    """The rows of ``path`` (a row per estimator; one row with ``error`` when it cannot be read or anything
    on the way fails), its tables written under ``out/tables``; ``page``: its flight report too,
    ``out/reports/<log_id>.html``. A log that fails leaves none of its files behind."""
    path, root, out = Path(path), Path(root), Path(out)
    fields = log_fields(path, root)
    try:
        return _rows(path, out, filters, page, dict(fields))  # a copy: an error row carries the log's fields only
    except UserError as error:
        error_said = str(error)
    except Exception as error:  # a defect in a reader or a writer must cost this log only, and say what it was
        error_said = f"internal error ({type(error).__name__}: {error})"
    discard(out, fields["log_id"])
    return [{**fields, "error": error_said}]


def discard(out: Path, identifier: str) -> None:
    """What a log that failed had written: its tables' partitions and its report."""
    import shutil

    for partition in (out / "tables").glob(f"*/log_id={identifier}"):
        shutil.rmtree(partition, ignore_errors=True)
    page = out / "reports" / f"{identifier}.html"
    if page.is_file():  # (not there, or its folder not one: what failed may be its writing)
        page.unlink()


def _rows(path: Path, out: Path, filters, page: bool, fields: dict) -> list[dict]:
    from groundstation.autopilot.agreement import onboard_agreement
    from groundstation.export.report import NOT_RECORDED, firmware, vehicle, vibration_of, write_report
    from groundstation.export.report_findings import findings
    from groundstation.session_makers.load import load_session

    data = load_session(path, filters, exact=True)  # its tables, reports and scores: the estimators' values as computed
    said = {"vehicle": vehicle(data), "firmware": firmware(data)}
    fields.update({k: v for k, v in said.items() if v != NOT_RECORDED}, samples=len(data),
                  duration_s=data.duration_s(), imu_rate_hz=data.imu_rate_hz(), link_loss_pct=data.link_loss_pct(),
                  warnings="\n".join(data.warnings) or None)
    vibration, _ = vibration_of(data)
    fields.update(vibration_fields(vibration))
    found = findings(data, vibration)
    fields.update(findings=len(found), worst_severity=found[0].severity if found else None,
                  worst_finding=found[0].title if found else None)
    write_tables(data, out / "tables", fields["log_id"])
    if page:
        (out / "reports").mkdir(exist_ok=True)
        write_report(data, under(out, "reports", f"{fields['log_id']}.html"), fields["path"], overwrite=True)
    rows = []
    if data.true_q is not None:
        for name, scores in data.evaluate().items():
            rows.append({**fields, "estimator": name, "reference": "truth", **scores})
    elif data.has_onboard() and data.estimated:
        for name, figures in onboard_agreement(data).items():
            rows.append({**fields, "estimator": name, "reference": "onboard",
                         **{k: v for k, v in figures.items() if k in LOG_COLUMNS}})
    else:
        rows.extend({**fields, "estimator": name} for name in data.estimated)
    return rows or [fields]


def vibration_fields(summary) -> dict:
    """The log's vibration level (the largest axis' RMS above the cut-off, per sensor), its strongest peak
    and the table it was read from (``analysis.vibration``); empty when the log has too little IMU for a
    spectrum (``summary`` None)."""
    if summary is None:
        return {}
    levels = {sensor: max((v for v in axes.values() if v is not None), default=None)
              for sensor, axes in summary.levels.items()}
    strongest = max(summary.peaks, key=lambda p: p.amplitude, default=None)
    return {"vibration_accel_m_s2": levels.get("accel"), "vibration_gyro_deg_s": levels.get("gyro"),
            "vibration_peak_hz": strongest.frequency_hz if strongest else None, "vibration_source": summary.source}


def write_tables(data, folder: Path, identifier: str) -> None:
    """Each table with rows as ``folder/<table>/log_id=<identifier>/part-0.parquet`` (its columns as in
    every export: names with units; a missing value null, as ``export --out x.parquet`` writes it, so
    that SQL's avg() skips it where a NaN would make it NaN). ``<table>``: the table's name as a folder
    (``names.path_name``: a log names its topics, and ``../../x`` or 300 characters must not become a
    path), the name itself in the file's metadata (``table``, and ``label``: what the log calls it,
    ``caseTopic (ulog)``); every path checked to lie in ``folder``."""
    import pyarrow as pa

    for name, columns in data.tables.items():
        if not len(columns["time_s"]):
            continue
        target = under(folder, path_name(name), f"log_id={identifier}")
        target.mkdir(parents=True, exist_ok=True)
        said = {"table": name, "label": data.catalogue[name].label if name in data.catalogue else ""}
        _write_part(pa.table({c: pa.array(np.asarray(v, dtype=float), from_pandas=True) for c, v in columns.items()},
                             metadata={k: v.encode("utf-8", "backslashreplace") for k, v in said.items()}),
                    target / "part-0.parquet")


def unify_tables(folder: Path) -> None:
    """One schema per table across the logs under ``folder`` (``write_tables``' tables, once every log's
    are written): each log's part gets every column any log has for that table, in one order (as they
    first appear, logs in id order), a column it lacks as nulls. Readers that take one file's schema for
    all (DuckDB's read_parquet without union_by_name, polars' scan_parquet, pyarrow.dataset) then read
    every column; only the parts that lack a column are rewritten."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    for table in sorted(p for p in Path(folder).iterdir() if p.is_dir()):
        schemas = {part: pq.read_schema(part) for part in sorted(table.glob("log_id=*/part-0.parquet"))}
        names = list(dict.fromkeys(name for schema in schemas.values() for name in schema.names))
        for part, schema in schemas.items():
            if schema.names != names:
                own = pq.read_table(part)
                _write_part(pa.table({n: own[n] if n in schema.names else pa.nulls(own.num_rows, pa.float64())
                                      for n in names}, metadata=schema.metadata), part)


def _write_part(table, path: Path) -> None:
    import pyarrow.parquet as pq

    from groundstation.export.files import atomic_output

    with atomic_output(path, overwrite=True) as temporary:
        pq.write_table(table, temporary)
