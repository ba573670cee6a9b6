"""MCAP export read back by an independent reader (``mcap`` with its protobuf decoder): every row and
time stamp of every table equal to the session's, every attitude on /tf, every event on /events."""

import json
import math
from collections import defaultdict

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

from groundstation.export.foxglove_topics import origin_ns
from groundstation.export.mcap_file import write_mcap
from groundstation.export.protobuf_rows import field_names
from groundstation.export.request import export_request, run_export
from groundstation.session_makers.load import load_session
from groundstation.session.product import event_time_s
from tests.cli_in_process import run_in_process
from tests.export.conftest import START_UTC


def read_mcap(path, log_time_order=True):
    """topic -> list of (log_time_ns, decoded message): JSON by json, protobuf by Google's protobuf runtime
    from the file's own FileDescriptorSet (``mcap_protobuf``)."""
    out = defaultdict(list)
    factory = DecoderFactory()
    with open(path, "rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=log_time_order):
            if channel.message_encoding == "json":
                decoded = json.loads(message.data)
            else:
                decoded = factory.decoder_for(channel.message_encoding, schema)(message.data)
            out[channel.topic].append((message.log_time, decoded))
    return out


def column_values(messages, columns) -> dict[str, np.ndarray]:
    """A table's columns from its messages: each column's protobuf field (``field_names``)."""
    return {c: np.array([getattr(m, f) for _, m in messages], dtype=float) for c, f in zip(columns, field_names(columns))}


def test_every_row_and_time_stamp_read_back(sim_session, tmp_path):
    path = tmp_path / "flight.mcap"
    write_mcap(sim_session, path)
    topics = read_mcap(path)
    origin = origin_ns({"start_utc": START_UTC})
    assert origin == 1714564800 * 10**9  # 2024-05-01T12:00:00Z, by hand
    checked = 0
    for name, columns in sim_session.tables.items():
        messages = topics.get(f"/{name}", [])
        assert len(messages) == len(columns["time_s"]), name
        read = column_values(messages, list(columns))
        untimed = np.isnan(columns["time_s"])  # a CONFIG before the first sample: at the session's start, time 0
        for column, values in columns.items():
            expected = np.where(untimed, 0.0, values) if column == "time_s" else values
            np.testing.assert_array_equal(read[column], expected, err_msg=f"{name}.{column}")  # bit for bit, NaN as NaN
        times = np.array([t for t, _ in messages], dtype=np.int64)
        expected = origin + np.rint(np.where(untimed, 0.0, columns["time_s"]) * 1e9).astype(np.int64)
        np.testing.assert_array_equal(times, expected, err_msg=name)
        checked += len(messages)
    assert checked > 2000 and len(sim_session.tables["imu"]["time_s"]) > 1000


def test_attitudes_as_frame_transforms(sim_session, tmp_path):
    path = tmp_path / "flight.mcap"
    write_mcap(sim_session, path)
    topics = read_mcap(path)
    transforms = topics["/tf"]
    attitudes = sim_session.attitudes()
    assert {"ahf", "hf", "onboard"} <= set(attitudes)
    by_frame = defaultdict(list)
    for log_time, message in transforms:
        for transform in message.transforms:
            assert transform.parent_frame_id == "ned"
            stamp = transform.timestamp.seconds * 10**9 + transform.timestamp.nanos
            assert stamp == log_time
            r = transform.rotation
            by_frame[transform.child_frame_id].append((log_time, (r.w, r.x, r.y, r.z)))
    origin = origin_ns(sim_session.metadata)
    for name, q in attitudes.items():
        table = sim_session.tables["onboard" if name == "onboard" else "imu"]  # each at its own rows
        columns = ["qw", "qx", "qy", "qz"] if name == "onboard" else [f"{name}_q{c}" for c in "wxyz"]
        q = np.column_stack([table[c] for c in columns])
        finite = np.isfinite(q).all(axis=1)
        got = by_frame[name]
        assert len(got) == finite.sum() > 1000, name
        np.testing.assert_array_equal(np.array([v for _, v in got]), q[finite])
        np.testing.assert_array_equal([t for t, _ in got], origin + np.rint(table["time_s"][finite] * 1e9))
    pitch = np.array([m.pitch_deg for _, m in topics["/attitude/ahf"]])
    q = attitudes["ahf"]
    expected = np.degrees(np.arcsin(np.clip(2 * (q[:, 0] * q[:, 2] - q[:, 3] * q[:, 1]), -1, 1)))  # ZYX pitch
    np.testing.assert_allclose(pitch, expected[np.isfinite(q).all(axis=1)], atol=1e-9)


def test_events_as_foxglove_logs(sim_session, tmp_path):
    path = tmp_path / "flight.mcap"
    write_mcap(sim_session, path)
    logs = read_mcap(path)["/events"]
    assert len(logs) == len(sim_session.events) > 0
    origin = origin_ns(sim_session.metadata)
    for (log_time, log), event in zip(logs, sim_session.events):
        assert log.name == event["kind"]
        assert log_time == origin + round(event_time_s(event) * 1e9)
    settings = [log for _, log in logs if log.name == "settings"]
    assert settings and "hf" in settings[0].message


def test_time_range_and_rate(sim_recording, tmp_path):
    out = tmp_path / "part.mcap"
    result = run_export(export_request(sim_recording, out, t_from=5.0, t_to=8.0), load_session)
    assert out.exists() and "messages" in result.message
    imu = [m for _, m in read_mcap(out)["/imu"]]
    assert imu and all(5.0 <= m.time_s <= 8.0 for m in imu)
    from groundstation.errors import UserError
    with pytest.raises(UserError, match="--rate does not apply to MCAP"):
        export_request(sim_recording, tmp_path / "x.mcap", rate_hz=10)


def test_cli_exports_a_flight_log_and_refuses_cleanly(tmp_path, capsys):
    from tests.export.conftest import DATASETS
    log = DATASETS / "flightlogs" / "px4_fmuv5_quad_hop.ulg"
    if not log.exists():
        pytest.skip("flight logs not found")
    out = tmp_path / "hop.mcap"
    done = run_in_process(capsys, "export", log, "--out", out)
    assert done.returncode == 0, done.stderr
    topics = read_mcap(out)
    session = load_session(log, exact=True)
    onboard = session.tables["onboard"]["time_s"]
    assert len(topics["/onboard"]) == len(onboard) > 0
    times = np.array([t for t, _ in topics["/onboard"]])
    assert times.min() >= origin_ns(session.metadata) > 1.6e18  # the log's GPS time (2023), not 1970
    np.testing.assert_allclose(np.diff(times) / 1e9, np.diff(onboard), atol=1e-9)
    again = run_in_process(capsys, "export", log, "--out", out)
    assert again.returncode == 2 and "exists" in again.stderr and "Traceback" not in again.stderr
    assert len(again.stderr.strip().splitlines()) == 1


def test_an_autopilot_logs_parameters(tmp_path):
    from tests.export.conftest import DATASETS
    log = DATASETS / "flightlogs" / "px4_fmuv5_quad_hop.ulg"
    if not log.exists():
        pytest.skip("flight logs not found")
    session = load_session(log, ["ahf"], exact=True)
    assert session.parameters
    write_mcap(session, tmp_path / "hop.mcap")
    (_, values), = read_mcap(tmp_path / "hop.mcap")["/parameters"]
    assert values == {k: v for k, v in session.parameters.items() if math.isfinite(v)}  # no value: left out
    with open(tmp_path / "hop.mcap", "rb") as stream:
        metadata = {m.name: m.metadata for m in make_reader(stream).iter_metadata()}
    assert float(metadata["parameters"]["MC_ROLL_P"]) == session.parameters["MC_ROLL_P"]


def test_the_config_channel_says_each_unit_once_and_has_a_time(sim_session, tmp_path):
    """The spec's CONFIG fields that carry their unit in their names (``accel_fs_g`` in g, ``gyro_fs_dps``
    in deg/s, ``rate_hz`` in Hz) keep them as they are, not ``accel_fs_g_g``; the CONFIG that came before
    the first sample is at the session's start (time_s 0), not at no time."""
    write_mcap(sim_session, tmp_path / "flight.mcap")
    (log_time, config), = read_mcap(tmp_path / "flight.mcap")["/config"]
    fields = [f.name for f in config.DESCRIPTOR.fields]
    assert {"accel_fs_g", "gyro_fs_dps", "rate_hz"} <= set(fields)
    assert not [f for f in fields if f.lower().endswith(("_g_g", "_dps_deg_s", "_hz_hz"))]
    assert config.accel_fs_g == sim_session.config["accel_fs_g"] and config.rate_hz == sim_session.config["rate_hz"]
    assert config.time_s == 0.0 and log_time == origin_ns(sim_session.metadata)
