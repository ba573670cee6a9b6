"""The MCAP export read by the readers its users have, written by others: Foxglove's ``@mcap/core`` on
node with Lichtblick's channel parsing (tests/js), for every channel of a simulated session and of every
shared flight log; the ``mcap`` Python reader for the order of the messages and what a seek opens."""

import json
import subprocess
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from groundstation import quaternion
from groundstation.export.foxglove_topics import origin_ns
from groundstation.export.mcap_file import write_mcap
from groundstation.export.protobuf_rows import field_names
from groundstation.session_makers.load import load_session
from tests.export.conftest import DATASETS, simulated_recording

LOGS = sorted(p for p in (DATASETS / "flightlogs").glob("*") if p.suffix in (".bin", ".ulg", ".tlog"))


def check_tables_read_whole(read: dict, session) -> None:
    """Every channel parsed as Lichtblick does; every table's channel holds a message per row, a double
    per column, and per column the same count of finite values and the same sum as the session."""
    topics = read["topics"]
    errors = {t: e["error"] for t, e in topics.items() if "error" in e}
    assert not errors
    for name, columns in session.tables.items():
        if not len(columns["time_s"]):
            continue  # an empty table: a channel without messages, which the writer leaves out
        got = topics[f"/{name}"]
        assert got["count"] == len(columns["time_s"]), name
        fields = field_names(list(columns))
        assert got["fields"] == dict.fromkeys(fields, "double"), name
        for column, field in zip(columns, fields):
            values = np.where(np.isnan(columns["time_s"]), 0.0, columns[column]) if column == "time_s" else columns[column]
            finite = np.isfinite(values)
            count, total = got["sums"].get(field, [0, 0.0])
            assert count == finite.sum(), f"{name}.{column}"
            np.testing.assert_allclose(total, values[finite].sum(), rtol=1e-9, atol=1e-9, err_msg=f"{name}.{column}")


def test_every_channel_of_a_simulated_session_in_foxglove_and_lichtblick(sim_session, read_mcap_js, tmp_path):
    path = tmp_path / "flight.mcap"
    write_mcap(sim_session, path)
    read = read_mcap_js(path)
    check_tables_read_whole(read, sim_session)
    topics = read["topics"]
    assert topics["/events"]["count"] == len(sim_session.events) > 0
    imu = sim_session.tables["imu"]
    for name in ("ahf", "hf"):
        finite = np.isfinite(imu[f"{name}_qw"]).sum()
        assert topics[f"/attitude/{name}"]["count"] == finite > 1000
        assert set(topics[f"/attitude/{name}"]["fields"]) == {"time_s", "pitch_deg", "roll_deg", "yaw_deg"}
    assert topics["/tf"]["schemaName"] == "foxglove.FrameTransforms" and topics["/tf"]["count"] > 1000
    assert read["metadata"]["time"]["session_time_0_utc"] == sim_session.metadata["start_utc"]


@pytest.mark.parametrize("log", LOGS, ids=[p.name for p in LOGS])
def test_every_channel_of_a_shared_log_in_foxglove_and_lichtblick(log, read_mcap_js, exported_log):
    session, path = exported_log(log.name)
    read = read_mcap_js(path)
    check_tables_read_whole(read, session)
    if session.parameters:  # JSON: Lichtblick takes its schema; a parameter without a value is left out
        assert read["topics"]["/parameters"]["fields"] == {}


@pytest.fixture(scope="module")
def minute_session(tmp_path_factory):
    """60 s of the simulated hover."""
    return load_session(simulated_recording(tmp_path_factory.mktemp("minute") / "minute.gsrec", duration_s=60.0), exact=True)


def test_messages_in_log_time_order_and_a_seek_opens_few_chunks(minute_session, tmp_path):
    path = tmp_path / "minute.mcap"
    write_mcap(minute_session, path)
    with open(path, "rb") as stream:
        reader = make_reader(stream)
        written = [(channel.topic, message.log_time) for _, channel, message in reader.iter_messages(log_time_order=False)]
        summary = reader.get_summary()
    times = np.array([t for _, t in written])
    assert np.all(np.diff(times) >= 0)  # as written, across every channel
    tf = np.array([t for topic, t in written if topic == "/tf"])
    assert len(tf) > 5000 and np.all(np.diff(tf) >= 0)
    chunks = summary.chunk_indexes
    assert len(chunks) >= 8 and all(c.message_index_offsets for c in chunks)  # a message index per chunk
    middle = (times[0] + times[-1]) // 2
    opened = [c for c in chunks if c.message_start_time <= middle + 10**9 and c.message_end_time >= middle]
    assert len(opened) <= len(chunks) / 4, (len(opened), len(chunks))  # what a 1 s seek reads
    with open(path, "rb") as stream:  # and the reader finds that second's messages by the index
        second = Counter(c.topic for _, c, _ in make_reader(stream).iter_messages(starting_at=middle, ending_before=middle + 10**9))
    imu = origin_ns(minute_session.metadata) + np.rint(minute_session.tables["imu"]["time_s"] * 1e9)
    assert second["/imu"] == np.sum((imu >= middle) & (imu < middle + 10**9)) > 90


def test_the_json_parameters_schema_is_plain(tmp_path):
    """The one JSON channel: its values a plain "number" (no ["number", "null"]), NaN left out."""
    from groundstation.export.foxglove_topics import Topics
    import foxglove

    context = foxglove.Context()
    with foxglove.open_mcap(tmp_path / "p.mcap", context=context):
        Topics(context, {}, 0).parameters({"A": 1.5, "B": float("nan")})
    with open(tmp_path / "p.mcap", "rb") as stream:
        (schema, _, message), = make_reader(stream).iter_messages()
    assert json.loads(schema.data)["additionalProperties"] == {"type": "number"}
    assert json.loads(message.data) == {"A": 1.5}


def test_rerun_imports_imu_and_attitudes_as_series(sim_session, tmp_path):
    """Rerun's own MCAP import (the ``rerun mcap convert`` of its SDK) decodes every /imu column and every
    /attitude/<estimate> angle into a float64 series on the log-time timeline, value for value."""
    rerun_chunk = pytest.importorskip("rerun.chunk", reason="rerun-sdk (the test extra) is not installed")
    path = tmp_path / "flight.mcap"
    write_mcap(sim_session, path)
    rows = {}  # entity -> (log times, struct rows)
    for chunk in rerun_chunk.McapReader(path).stream():
        batch = chunk.to_record_batch()
        message = next((name for name in batch.schema.names if name.endswith(":message")), None)
        if message is not None:
            times, values = rows.setdefault(chunk.entity_path, ([], []))
            times += batch.column("message_log_time").cast("int64").to_pylist()
            values += batch.column(message).flatten().to_pylist()  # one message a row: list<struct> -> struct
    origin = origin_ns(sim_session.metadata)
    imu = sim_session.tables["imu"]
    expected = {"/imu": (imu["time_s"], imu)}
    for name in ("ahf", "hf", "onboard"):
        table = sim_session.tables["onboard" if name == "onboard" else "imu"]
        q = np.column_stack([table[c] for c in (["qw", "qx", "qy", "qz"] if name == "onboard" else [f"{name}_q{a}" for a in "wxyz"])])
        finite = np.isfinite(q).all(axis=1)
        yaw, pitch, roll = quaternion.euler_deg(q[finite])
        expected[f"/attitude/{name}"] = (table["time_s"][finite], {"pitch_deg": pitch, "roll_deg": roll, "yaw_deg": yaw})
    for entity, (time_s, columns) in expected.items():
        times, values = rows[entity]
        order = np.argsort(times, kind="stable")
        np.testing.assert_array_equal(np.array(times)[order], origin + np.rint(time_s * 1e9).astype(np.int64))
        for column, field in zip(columns, field_names(list(columns))):
            series = np.array([values[i][field] for i in order], dtype=float)
            np.testing.assert_array_equal(series, columns[column], err_msg=f"{entity}.{column}")
    rerun = Path(sys.executable).parent / "rerun"  # its CLI, from the same wheel: every channel's timeline in order
    check = subprocess.run([str(rerun), "mcap", "check", str(path)], capture_output=True, text=True, timeout=300)
    statuses = {line.split()[3]: line.split()[0] for line in check.stdout.splitlines() if line.startswith(("ok ", "PROBLEM "))}
    assert set(statuses) >= {"/imu", "/tf", "/attitude/ahf"} and set(statuses.values()) == {"ok"}, check.stdout
