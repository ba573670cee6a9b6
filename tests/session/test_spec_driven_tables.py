"""The protocol spec drives the session's tables: a frame added to the spec reaches the session, the CSV
and the workbook with no Python written for it, and no downlink frame is ever dropped."""

import numpy as np
import pandas as pd
from openpyxl import load_workbook

from firmware_protocol import SPEC, encode, make_frame
from firmware_protocol.codec import new_frame
from firmware_protocol.spec import SPEC_PATH, load_spec
from groundstation.export.columns import export_columns
from groundstation.export.excel import write_workbook
from groundstation.export.tabular import write_csv
from groundstation.recording import RecordingWriter, open_recording
from groundstation.session_parts.catalogue import COMPUTED_FROM
from groundstation.session_makers.load import from_pipeline
from groundstation.session_makers.pipeline import Pipeline

ESC_ID = min(set(range(1, 256)) - {t.id for t in SPEC.frames})  # free in any version of the spec, not a fixed 0x08
ESC_FRAME = """
[[frames]]
name = "ESC"
id = ESC_ID
direction = "down"
description = "Motor controller telemetry."
fields = [
  { name = "t_us", type = "uint32_t", unit = "us", description = "device time" },
  { name = "rpm", type = "uint16_t", unit = "rpm", description = "motor speed" },
  { name = "current", type = "int16_t", scale = 0.01, unit = "A", description = "motor current" },
]
""".replace("ESC_ID", str(ESC_ID))
ESC_RATE_HZ, IMU_RATE_HZ, SECONDS = 10, 100, 3


def esc_spec():
    return load_spec(SPEC_PATH.read_text(encoding="utf-8") + ESC_FRAME)


def flight_bytes(spec) -> list[bytes]:
    """CONFIG, then level IMU samples at 100 Hz and ESC telemetry at 10 Hz (rpm 1000 + 10 k, current k/100 A)."""
    config = make_frame("CONFIG", 0, protocol_version=SPEC.protocol_version, schema_fingerprint=spec.fingerprint,
                        fw_major=1, fw_minor=0, fw_patch=0, accel_fs_g=2, gyro_fs_dps=250, rate_hz=IMU_RATE_HZ,
                        mode=0, mounting=1, gyro_calibration=1)
    frames, seq = [encode(config)], 1
    for k in range(SECONDS * IMU_RATE_HZ):
        t_us = 1_000_000 + k * 10_000
        imu = make_frame("IMU_RAW", seq & 0xFF, t_us=t_us, acc_x=0, acc_y=0, acc_z=16384, gyr_x=0, gyr_y=0, gyr_z=0,
                         temperature=2500)
        frames.append(encode(imu))
        seq += 1
        if k % (IMU_RATE_HZ // ESC_RATE_HZ) == 0:
            n = k // (IMU_RATE_HZ // ESC_RATE_HZ)
            frames.append(encode(new_frame(spec.frame("ESC"), seq & 0xFF, (t_us, 1000 + 10 * n, n))))
            seq += 1
    return frames


def test_a_frame_added_to_the_spec_reaches_the_session_the_csv_and_the_workbook(tmp_path):
    spec = esc_spec()
    path = tmp_path / "esc.gsrec"
    with RecordingWriter(path, {"source": "test", "filters": ["ahf"]}) as writer:
        for i, data in enumerate(flight_bytes(spec)):
            writer.write_chunk(i * 5_000_000, data)
    recording = open_recording(path)
    pipeline = Pipeline(("ahf",), spec=spec)
    for t_host_ns, data in recording.chunks():
        pipeline.feed(t_host_ns, data)
    assert pipeline.decoder.stats.unknown_types == 0
    data = from_pipeline(recording, pipeline)

    esc = data.tables["esc"]
    n = SECONDS * ESC_RATE_HZ
    assert data.catalogue["esc"].column_names == ("time_s", "rpm_rpm", "current_A")
    np.testing.assert_array_equal(esc["rpm_rpm"], 1000 + 10 * np.arange(n))
    np.testing.assert_allclose(esc["current_A"], np.arange(n) * 0.01)  # the spec's scale, applied
    np.testing.assert_allclose(esc["time_s"], np.arange(n) / ESC_RATE_HZ, atol=1e-9)

    write_csv(export_columns(data), tmp_path / "esc.csv")
    csv = pd.read_csv(tmp_path / "esc.csv")
    readings = csv["esc_current_A"].dropna()
    assert len(readings) == n
    np.testing.assert_allclose(readings.to_numpy(), np.arange(n) * 0.01)
    assert np.allclose(csv["time_s"][readings.index], esc["time_s"])  # each on the IMU row at its time

    write_workbook(data, tmp_path / "esc.xlsx")
    sheet = load_workbook(tmp_path / "esc.xlsx")["Sensors"]
    header = next(sheet.iter_rows(values_only=True))
    column = header.index("esc current (A)")
    values = [row[column] for row in sheet.iter_rows(min_row=2, values_only=True) if row[column] is not None]
    np.testing.assert_allclose(values, np.arange(n) * 0.01)


def test_every_downlink_frame_of_the_spec_has_a_table():
    catalogue = Pipeline(("ahf",)).catalogue
    for frame_type in SPEC.frames:
        if frame_type.direction != "down":
            continue
        table = COMPUTED_FROM.get(frame_type.name, frame_type.name.lower())
        assert table in catalogue, f"{frame_type.name} would be dropped"
        if frame_type.name not in COMPUTED_FROM:  # every field, in the spec's unit, after session time
            fields = [f for f in frame_type.fields if f.name != "t_us"]
            columns = catalogue[table].columns
            assert columns[0].name == "time_s"
            assert [(c.label, c.unit) for c in columns[1 : len(fields) + 1]] == [(f.name.replace("_", " "), f.unit) for f in fields]
