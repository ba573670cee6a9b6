"""Live MAVLink = its .tlog (issue 20): a live session from the simulated aircraft on a real
pseudo-terminal, recorded, saved with ``groundstation import REC --out x.tlog`` and opened again: the
same tables, rows and values as the recording opened itself.

Both go through the pipeline's MAVLink front-end; what differs is only what the .tlog cannot hold:
its receive times are whole microseconds (the recording's nanoseconds, truncated), so the host-time
column (``host_time_s``) may differ by up to 1 µs; every other value is equal bit for bit."""

import dataclasses
import os

import numpy as np
import pytest

from groundstation.recording import open_recording
from groundstation.session_makers.load import load_session
from groundstation.sim.mavlink_aircraft import MavlinkAircraft
from groundstation.sim.stream import Scenario
from mavlink_helpers import pty_session
from tests.cli_in_process import run_in_process

SCENARIO = dataclasses.replace(Scenario(), profile="flight", duration_s=60.0, seed=5)
FILTERS = ("ahf", "hf")
HOST_TIME_COLUMNS = {"host_time_s"}  # from the receive time: a .tlog keeps it in whole µs
RECEIVE_TIME_TOLERANCE_S = 1e-6


@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals are POSIX only")
def test_a_live_session_and_its_tlog_open_to_the_same_tables_and_rows(tmp_path, capsys):
    session = pty_session(MavlinkAircraft(SCENARIO), 3.0, filters=FILTERS, recordings_dir=tmp_path)
    recording = session.recording_path
    assert open_recording(recording).metadata["protocol"] == "mavlink"
    tlog = tmp_path / "x.tlog"
    done = run_in_process(capsys, "import", recording, "--out", tlog)
    assert done.returncode == 0, done.stderr

    live, logged = load_session(recording, filters=FILTERS), load_session(tlog, filters=FILTERS)
    # some 2 s at 50 Hz once the stream requests took effect (the session opens on a running link)
    assert len(live.tables["imu"]["time_s"]) > 75 and len(live.tables["onboard"]["time_s"]) > 50
    assert sorted(logged.tables) == sorted(live.tables)
    assert logged.filters == live.filters
    for name, table in live.tables.items():
        assert logged.catalogue[name].column_names == live.catalogue[name].column_names, name
        assert list(logged.tables[name]) == list(table), name
        for column, values in table.items():
            other = logged.tables[name][column]
            assert other.shape == values.shape, f"{name}.{column}"
            if column in HOST_TIME_COLUMNS:
                np.testing.assert_allclose(other, values, rtol=0, atol=RECEIVE_TIME_TOLERANCE_S, err_msg=f"{name}.{column}")
            else:
                np.testing.assert_array_equal(other, values, err_msg=f"{name}.{column}")
