"""The estimators run a stretch at a time (session_makers.estimate_run): where a stretch ends changes no number.

The whole run (the ``imu`` table of ``load_session``) and the streamed one (an export's,
``stream_estimates``) run the same code, ``Estimator.run`` over stretches with the state carried, so
they are compared bit for bit, with stretches far shorter than the session (37 samples) so that every
break (a device reboot, settings changed while recording) and every stretch boundary falls inside one.
The oracle for the stretched run is the incremental pipeline (``replay``, one ``step`` per sample).
"""

import numpy as np
import pyarrow.parquet as pq
import pytest

from groundstation.export.columns import export_stretches, select_rows
from groundstation.export.request import export_request, run_export
from groundstation.export.tabular import write_parquet
from groundstation.session_makers import estimate_run
from groundstation.session_makers.load import load_session
from tests.session.test_batch import SENSORS, assert_same_session
from tests.simulated import simulated_chunks, write_recording

FILTERS = ("ahf", "hf", "ecf", "vqf", "ukf")  # ahf aids the heading and the position


@pytest.fixture(scope="module")
def eventful(tmp_path_factory):
    """10 s with every aiding sensor, a reboot at 5 s, and settings changed before, between and after it."""
    chunks = simulated_chunks(10.0, reboot_after_s=5.0, **SENSORS)
    t0, second = chunks[0][0], 1_000_000_000
    events = [
        (t0 + 2 * second, {"kind": "settings", "name": "hf", "settings": {"beta": 0.3}}),
        (t0 + 2 * second, {"kind": "settings", "name": "ahf", "settings": {"lambda_max": 0.5}}),
        (t0 + 7 * second, {"kind": "settings", "name": "vqf", "settings": {"tau_acc_s": 2.0}}),
    ]
    path = tmp_path_factory.mktemp("estimate_run") / "eventful.gsrec"
    write_recording(path, chunks, {"filters": list(FILTERS)}, events)
    return path


@pytest.fixture
def short_stretches(monkeypatch):
    monkeypatch.setattr(estimate_run, "STRETCH_SAMPLES", 37)
    monkeypatch.setattr(estimate_run, "STREAMED_STRETCH_SAMPLES", 23)


def test_short_stretches_give_the_incremental_pipeline_s_tables(eventful, short_stretches):
    assert_same_session(eventful, FILTERS)


def test_streamed_columns_are_the_whole_run_s_on_every_row_asked(eventful, short_stretches):
    whole = load_session(eventful, FILTERS, exact=True)  # float64, as the streamed ones are made
    streamed = load_session(eventful, FILTERS, stream_estimates=True)
    assert streamed.estimates.names == FILTERS  # every one, the aiding one too: its attitudes for the heading went with the readings
    assert not set(streamed.estimates.columns) & set(streamed.tables["imu"])  # not held
    imu = whole.tables["imu"]
    assert np.isnan(imu["time_s"]).sum() == 0 and np.isnan(imu["hf_qw"]).any()  # the reboot's gap row is among them
    rows = select_rows(whole.time_s, rate_hz=30)  # every third row: samples skipped between those asked
    for start in range(0, len(rows), 101):
        asked = rows[start:start + 101]
        columns = streamed.estimates.at(asked)
        assert list(columns) == list(streamed.estimates.columns)
        for name, values in columns.items():
            assert np.array_equal(values, imu[name][asked], equal_nan=True), name
    for name in streamed.tables["imu"]:
        assert np.array_equal(streamed.tables["imu"][name], imu[name], equal_nan=True), name


def test_the_streamed_run_goes_forward_only(eventful):
    streamed = load_session(eventful, FILTERS, stream_estimates=True)
    streamed.attitudes(np.arange(100, 200))
    with pytest.raises(ValueError, match="forward only"):
        streamed.attitudes(np.arange(150, 250))
    with pytest.raises(ValueError, match="a stretch of rows at a time"):
        streamed.attitudes()


def test_a_parquet_export_streams_and_writes_the_whole_session_s_bytes(eventful, short_stretches, tmp_path):
    out = tmp_path / "streamed.parquet"
    run_export(export_request(eventful, out, filters=list(FILTERS)), load_session)
    whole = load_session(eventful, FILTERS, exact=True)
    write_parquet(export_stretches(whole, np.arange(len(whole))), tmp_path / "whole.parquet")
    assert out.read_bytes() == (tmp_path / "whole.parquet").read_bytes()
    assert pq.read_table(out).num_rows == len(whole)


def test_without_readings_to_aid_every_estimator_streams(tmp_path):
    path = tmp_path / "plain.gsrec"
    write_recording(path, simulated_chunks(3.0), {"filters": ["ahf", "hf"]})
    streamed = load_session(path, ("ahf", "hf"), stream_estimates=True)
    assert streamed.estimates.names == ("ahf", "hf")
    whole = load_session(path, ("ahf", "hf"), exact=True)
    rows = np.arange(len(whole))
    for name, q in streamed.attitudes(rows).items():
        assert np.array_equal(q, whole.quaternion(name), equal_nan=True), name
