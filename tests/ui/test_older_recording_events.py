"""The window's event list names an old recording's unknown gyro calibration (tests/data/README.md)."""

from pathlib import Path

from groundstation.recording import open_recording
from groundstation.session.replay import replay
from groundstation.ui.event_console import describe

OLD_RECORDING = Path(__file__).resolve().parents[1] / "data" / "hover-raw-config-15-bytes.gsrec"


def test_the_event_list_says_an_old_configs_gyro_calibration_is_unknown():
    (config,) = [e for e in replay(open_recording(OLD_RECORDING)).events if e["kind"] == "config"]
    assert "gyro_calibration unknown" in describe(config) and "mode raw" in describe(config)
