"""The window's event list says what a session's CONFIG could not: an old firmware's unknown gyro
calibration (tests/data/README.md), and a lost CONFIG as a warning (issue 22)."""

from pathlib import Path

from groundstation.recording import open_recording
from groundstation.session_makers.replay import replay
from groundstation.ui.event_console import ALARMS, describe

from tests.recording.helpers import recording_without_config
from tests.ui.helpers import open_file, play_to_the_end

OLD_RECORDING = Path(__file__).resolve().parents[1] / "data" / "hover-raw-config-15-bytes.gsrec"


def test_the_event_list_says_an_old_configs_gyro_calibration_is_unknown():
    (config,) = [e for e in replay(open_recording(OLD_RECORDING)).events if e["kind"] == "config"]
    assert "gyro_calibration unknown" in describe(config) and "mode raw" in describe(config)


def test_a_lost_config_is_a_warning_in_the_event_list(window, qtbot, tmp_path):
    open_file(window, qtbot, recording_without_config(tmp_path))
    play_to_the_end(window, qtbot)
    window.event_console.refresh()
    table = window.event_console.table
    rows = [r for r in range(table.rowCount()) if "no CONFIG frame" in table.item(r, 2).text()]
    assert len(rows) == 1 and "±4 g inferred" in table.item(rows[0], 2).text()
    assert table.item(rows[0], 1).text() == "warning" and "warning" in ALARMS  # shown in red
