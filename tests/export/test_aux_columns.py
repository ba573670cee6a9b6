"""Magnetometer, barometer and GPS readings in the CSV: each on the first IMU row at or after it."""

import numpy as np
import pandas as pd

from groundstation.export.columns import export_columns, select_rows
from groundstation.export.tabular import write_csv


def test_each_reading_lands_once_on_the_next_imu_row_of_the_csv(sim_session, tmp_path):
    path = tmp_path / "aux.csv"
    write_csv(export_columns(sim_session), path)
    csv = pd.read_csv(path)
    for table_name, column, csv_column in (("mag_raw", "mag_z_uT", "mag_z_uT"), ("baro", "pressure_Pa", "baro_pressure_Pa"),
                                           ("gps", "lat_deg", "gps_lat_deg"), ("mag_raw", "heading_deg", "mag_heading_deg")):
        table = sim_session.tables[table_name]
        filled = csv[csv_column].notna().to_numpy()
        rows = np.searchsorted(sim_session.time_s, table["time_s"])
        # Where lost IMU frames make two readings share a row, the later one is kept.
        readings_inside = (rows < len(sim_session)) & np.append(rows[1:] != rows[:-1], True)
        readings_inside &= np.isfinite(table[column])  # e.g. no heading before the first attitude
        assert filled.sum() == readings_inside.sum() > 0, csv_column
        assert readings_inside.sum() >= 0.98 * len(rows), csv_column  # 1% frame loss on this link
        assert np.allclose(csv[csv_column][filled], table[column][readings_inside], rtol=1e-9), csv_column
        # The row is the first IMU sample at or after the reading: the row before it is earlier.
        row_times = csv["time_s"].to_numpy()
        at = np.flatnonzero(filled)
        reading_times = table["time_s"][readings_inside]
        assert np.all(row_times[at] >= reading_times - 1e-9), csv_column
        assert np.all(row_times[np.maximum(at - 1, 0)][at > 0] < reading_times[at > 0] + 1e-9), csv_column


def test_a_decimated_range_keeps_only_the_readings_on_its_rows(sim_session):
    rows = select_rows(sim_session.time_s, 2.0, 6.0, 10.0)
    columns = export_columns(sim_session, rows)
    assert len(columns["gps_lat_deg"]) == len(rows)
    full = export_columns(sim_session)["gps_lat_deg"]
    assert np.array_equal(columns["gps_lat_deg"], full[rows], equal_nan=True)
