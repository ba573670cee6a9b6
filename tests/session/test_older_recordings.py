"""A recording made before CONFIG grew (tests/data/README.md) keeps its full scales, and says what its
CONFIG could not: its gyro calibration is unknown, in the session, its events, the Session sheet. A frame
type grown at its end is compatible (firmware_protocol.spec, compatibility per frame type): no warning."""

from pathlib import Path

import numpy as np

from firmware_protocol import SPEC
from groundstation.export.excel_session import describe_event, firmware
from groundstation.recording import open_recording
from groundstation.session_makers.load import load_session
from groundstation.session_makers.replay import replay

OLD_RECORDING = Path(__file__).resolve().parents[1] / "data" / "hover-raw-config-15-bytes.gsrec"
UNKNOWN = SPEC.frame("CONFIG").field("gyro_calibration").absent


def test_an_old_recording_converts_at_its_configs_full_scales_and_its_gyro_calibration_reads_unknown():
    data = load_session(OLD_RECORDING)
    pipeline = replay(open_recording(OLD_RECORDING))  # the live path, frame by frame
    for config in (data.config, pipeline.config):
        assert (config["accel_fs_g"], config["gyro_fs_dps"], config["gyro_calibration"]) == (4, 500, UNKNOWN)
    # The hovering craft feels 1 g (at the assumed ±2 g it would read 0.5 g).
    norm_g = np.linalg.norm([data.tables["imu"][f"acc_{a}_g"] for a in "xyz"], axis=0)
    assert len(norm_g) > 200 and abs(np.median(norm_g) - 1.0) < 0.05
    assert np.array_equal(norm_g, np.linalg.norm([pipeline.tables["imu"].column(f"acc_{a}_g") for a in "xyz"], axis=0))
    warnings = [e["message"] for e in data.events if e["kind"] == "warning"]
    assert warnings == []
    assert pipeline.decoder.stats.schema_mismatches == 0
    (event,) = [e for e in data.events if e["kind"] == "config"]
    assert "gyro calibration unknown" in describe_event(event)
    assert ["gyro calibration", "unknown"] in firmware(data)
