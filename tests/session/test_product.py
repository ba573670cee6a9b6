"""One product, one shape, whoever made it: the batch path (a recording of the project's frames), the
pipeline (a recording of an autopilot's MAVLink), the dataset reader (a slice of a BROAD trial) and a
flight-log reader (a .tlog); and one view of it for the window, live or played back from a file."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groundstation import quaternion
from groundstation.autopilot.tlog import write_tlog
from groundstation.recording import RecordingWriter
from groundstation.session import view
from groundstation.session_makers.load import load_session
from groundstation.session_makers.factory import open_session
from groundstation.session.playback import RevealSession
from groundstation.session_parts.catalogue import IMU
from groundstation.sim.mavlink_aircraft import MavlinkAircraft
from groundstation.ui.series import attitude_deg
from tests.simulated import simulated_chunks, write_recording

TRIAL = Path(__file__).resolve().parents[2].parent / "shared" / "datasets" / "broad" / "02_undisturbed_slow_rotation_B.csv.gz"


def project_recording(tmp_path):
    path = tmp_path / "gs.gsrec"
    write_recording(path, simulated_chunks(3.0), {"filters": ["ahf", "hf"]})
    return path


def mavlink_recording(tmp_path):
    path = tmp_path / "mavlink.gsrec"
    with RecordingWriter(path, {"protocol": "mavlink", "filters": ["hf"]}) as writer:
        for chunk in MavlinkAircraft().advance(3.0):
            writer.write_chunk(10_000_000_000 + int(chunk.t_s * 1e9), chunk.data)
    return path


def dataset_csv(tmp_path):
    if not TRIAL.is_file():
        pytest.skip(f"{TRIAL} is absent (the shared datasets)")
    path = tmp_path / "trial.csv"
    frame = pd.read_csv(TRIAL)
    frame[frame.time_s < frame.time_s.iloc[0] + 5].to_csv(path, index=False)
    return path


def tlog(tmp_path):
    from tests.autopilot.mavlink_helpers import Sender, ardupilot_heartbeat

    ap, t0_us = Sender(), 1_700_000_000_000_000
    packets = [(t0_us, ardupilot_heartbeat(ap))]
    for i in range(100):
        packets.append((t0_us + i * 20_000, ap.raw_imu(3_000_000 + i * 20_000, 0, 0, -1000, 0, 0, 0, 1, 2, 3)))
        packets.append((t0_us + i * 20_000 + 1, ap.attitude(3_000 + i * 20, 0.01, 0.02, 0.03, 0, 0, 0)))
        if i % 10 == 5:
            packets.append((t0_us + i * 20_000 + 2, ap.vfr_hud(10.0 + i, 11.0, 90, 42, 100.0, 0.5)))
    path = tmp_path / "flight.tlog"
    write_tlog(path, packets)
    return path


@pytest.mark.parametrize("make", [project_recording, mavlink_recording, dataset_csv, tlog])
def test_every_maker_gives_the_tables_its_catalogue_describes(make, tmp_path):
    """Before: a dataset's catalogue named every frame's table but its product held only ``imu``, and a
    flight log's product had no ``onboard`` table (its estimate was a flat array beside the tables)."""
    data = load_session(make(tmp_path))
    assert list(data.tables) == list(data.catalogue.tables)
    for info in data.catalogue:
        columns = data.tables[info.name]
        assert tuple(columns) == info.column_names, info.name
        assert len({len(values) for values in columns.values()}) == 1, info.name
    assert {"imu", "onboard"} <= data.tables.keys()
    assert np.array_equal(data.time_s, data.tables["imu"]["time_s"])
    for name in data.estimated:  # the estimates are the imu table's columns, not a copy beside it
        q = data.quaternion(name)
        assert np.array_equal(q[:, 0], data.tables["imu"][f"{name}_qw"], equal_nan=True)


@pytest.mark.parametrize("make", [project_recording, mavlink_recording, dataset_csv, tlog])
def test_every_maker_holds_the_estimates_sized_for_showing_and_exact_when_asked(make, tmp_path):
    """Issue 35: an hour of the app's ten estimators held 274 MB of float64 columns. Held as float32 (137 MB), each
    value is the float64 one rounded (a quaternion within 6e-8 of it, far under a pixel); every other column stays
    float64, and a reader that writes them (an export, a report) loads them exact."""
    path = make(tmp_path)
    shown, exact = load_session(path), load_session(path, exact=True)
    assert shown.estimated
    sensors = set(IMU.column_names)
    for info in shown.catalogue:
        for name, values in shown.tables[info.name].items():
            exact_values = exact.tables[info.name][name]
            assert exact_values.dtype == np.float64, name
            if info.name == "imu" and name not in sensors:
                assert values.dtype == np.float32, name
                assert np.array_equal(values, exact_values.astype(np.float32), equal_nan=True), name
            else:
                assert values.dtype == np.float64 and np.array_equal(values, exact_values, equal_nan=True), name
    for name in shown.estimated:
        assert np.nanmax(np.abs(shown.quaternion(name) - exact.quaternion(name))) <= 6e-8, name


def test_the_window_shows_the_angles_the_export_writes(tmp_path):
    """One conversion, two presentations: the window's heading is the export's yaw on 0..360°."""
    from groundstation.export.columns import attitude_columns

    data = load_session(project_recording(tmp_path))
    q = data.quaternion("ahf")
    exported, shown = attitude_columns("ahf", q), attitude_deg("ahf", q)
    assert np.array_equal(exported["ahf_pitch_deg"], shown["ahf_pitch_deg"], equal_nan=True)
    assert np.array_equal(quaternion.heading_deg(exported["ahf_yaw_deg"]), shown["ahf_heading_deg"], equal_nan=True)
    yaw = exported["ahf_yaw_deg"][np.isfinite(exported["ahf_yaw_deg"])]
    assert yaw.min() > -180.0 and yaw.max() <= 180.0


def _view_attributes(session) -> set[str]:
    return {name for name in (*view.ProductView.__annotations__, "counters", "settings") if hasattr(session.view, name)}


def test_a_live_session_and_a_file_give_the_window_the_same_view(tmp_path):
    """Before: a file's session had ``pipeline`` made of stand-ins (``SimpleNamespace``) and the window
    asked ``isinstance(session, RevealSession)`` to know what it could do."""
    path = project_recording(tmp_path)
    played = RevealSession(load_session(path), path)
    with open_session("sim:?scenario=hover&seed=2", record=False) as live:
        expected = {*view.ProductView.__annotations__, "counters", "settings"}
        for session in (live, played):
            assert _view_attributes(session) == expected
            assert {"view", "seekable", "setup", "advance", "seek", "file"} <= set(dir(session))
            assert set(session.view.counters()) >= {"frames", "frames_lost", "crc_errors", "bytes_skipped"}
        assert not live.seekable and live.seek(1.0) is False
    assert played.seekable and played.file() == (path, played.source.duration_s)


def test_the_window_never_asks_which_kind_of_session_it_holds():
    """Before: ``isinstance(session, RevealSession)`` 7 times in main_window.py and once in replay_bar.py."""
    import ast

    asked = []
    for path in sorted((Path(__file__).resolve().parents[2] / "groundstation" / "ui").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "isinstance" and len(node.args) == 2:
                kinds = ast.unparse(node.args[1])
                if "Session" in kinds:
                    asked.append(f"{path.name}:{node.lineno} {kinds}")
    assert asked == []
