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
    """The rows of ``path`` (a row per estimator; one row with ``error`` when it cannot be read), its
    tables written under ``out/tables``; ``page``: its flight report too, ``out/reports/<log_id>.html``."""
    from groundstation.autopilot.agreement import onboard_agreement
    from groundstation.export.report import NOT_RECORDED, firmware, vehicle, vibration_of, write_report
    from groundstation.export.report_findings import findings
    from groundstation.session.load import load_session

    path, root, out = Path(path), Path(root), Path(out)
    fields = log_fields(path, root)
    try:
        data = load_session(path, filters)
    except UserError as error:
        return [{**fields, "error": str(error)}]
    except Exception as error:  # a defect in a reader must cost this log only, and say what it was
        return [{**fields, "error": f"internal error while reading ({type(error).__name__}: {error})"}]
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
        write_report(data, out / "reports" / f"{fields['log_id']}.html", fields["path"], overwrite=True)
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
    every export: names with units)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from groundstation.export.files import atomic_output

    for name, columns in data.tables.items():
        if not len(columns["time_s"]):
            continue
        target = folder / name / f"log_id={identifier}"
        target.mkdir(parents=True, exist_ok=True)
        table = pa.table({c: pa.array(np.asarray(v, dtype=float)) for c, v in columns.items()})
        with atomic_output(target / "part-0.parquet", overwrite=True) as temporary:
            pq.write_table(table, temporary)
