"""Each session rule exists once and both paths call it (issue 20): the batch path runs the pipeline's
aiding stage's rules (hand-over of readings to the IMU samples, compass heading, position) on whole
columns and gives what the pipeline's calls return, call for call (issue 25: no Python call per sample);
it waits for CONFIG through the pipeline's own rule, with the same arguments in the same order; and the
pipeline reads frames by field name, so a spec that orders the fields otherwise gives the same session.
"""

import math

import numpy as np
import pytest

from firmware_protocol import SPEC, StreamDecoder, encode
from firmware_protocol.codec import new_frame
from firmware_protocol.spec import SPEC_PATH, load_spec
from groundstation.recording import open_recording
from groundstation.session_parts import aiding as aiding_module
from groundstation.session_makers import pipeline as pipeline_module
from groundstation.session_makers.batch import batch_replay
from groundstation.session_parts.catalogue import POSITION
from groundstation.session_makers.pipeline import Pipeline
from groundstation.session_makers.replay import replay
from tests.simulated import simulated_chunks, write_recording

SENSORS = dict(mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=5)


def plain(value):
    """Arguments and results comparable across paths: floats (NaN equal), tuples, dicts, None."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (tuple, list, np.ndarray)):
        return tuple(plain(v) for v in value)
    if isinstance(value, float) and math.isnan(value):
        return "nan"
    return value


def recording_calls(monkeypatch, cls, names):
    """Every call of ``names`` on instances of ``cls``: (instance number, method, arguments, result)."""
    calls, instances = [], {}
    for name in names:
        method = getattr(cls, name)

        def called(self, *args, _method=method, _name=name):
            result = _method(self, *args)
            calls.append((instances.setdefault(id(self), len(instances)), _name, plain(args), plain(result)))
            return result

        monkeypatch.setattr(cls, name, called)
    return calls


@pytest.mark.parametrize("piece", [1, 7, 64, 1 << 16])
def test_the_batch_path_gives_what_the_pipelines_aiding_stage_gives_call_for_call(tmp_path, monkeypatch, piece):
    """With a reboot: restarts, readings waiting for samples, heading and position. The batch path runs
    the stage's rules on columns (the hand-over, ``reading_heading_rad``, the position filter's
    ``advance`` compiled), a piece of samples at a time (pieces of every size: their ends fall on readings,
    on the reboot, anywhere): what each of the pipeline's calls returned, it gives, to the last bit."""
    monkeypatch.setattr(aiding_module, "_PIECE", piece)
    path = tmp_path / "aided.gsrec"
    write_recording(path, simulated_chunks(8.0, reboot_after_s=4.0, **SENSORS), {"filters": ["ahf", "hf"]})
    recording = open_recording(path)
    calls = recording_calls(monkeypatch, aiding_module.Aiding, ("restart", "magnetometer", "position_step", "take_for_estimators"))
    replay(recording, ("ahf", "hf"))
    live = list(calls)
    handed_in_batch = []
    handed_to_samples = aiding_module.handed_to_samples
    monkeypatch.setattr(aiding_module, "handed_to_samples", lambda *args: handed_in_batch.append(handed_to_samples(*args)) or handed_in_batch[-1])
    batch = batch_replay(recording, ("ahf", "hf"))
    assert len([c for c in live if c[1] == "restart"]) >= 1
    position = [c[3] for c in live if c[1] == "position_step"]
    assert len(position) > 300
    rows = np.column_stack([batch.tables["position"].column(c) for c in POSITION.column_names[1:]])
    assert plain(rows[~np.isnan(rows).all(axis=1)]) == tuple(position)  # not the reboot's gap row
    headings = [c[3] for c in live if c[1] == "magnetometer"]
    read = np.isfinite(batch.tables["mag_raw"].column("mag_x_uT"))
    assert plain(batch.tables["mag_raw"].column("heading_deg")[read]) == tuple(headings)
    handed = [c[3] for c in live if c[1] == "take_for_estimators"]
    (mag, gps), = handed_in_batch
    taken = lambda values: [None if np.isnan(row).all() else tuple(row) for row in values.tolist()]  # noqa: E731
    assert plain(list(zip(taken(mag), taken(gps)))) == tuple(handed)
    assert sum(m is not None for m, _ in handed) > 100 and sum(g is not None for _, g in handed) > 10


def test_the_batch_path_waits_for_config_through_the_pipelines_rule(tmp_path, monkeypatch):
    """A recording cut after its boot CONFIG: the samples wait, then the assumed scales apply, sample for sample."""
    path = tmp_path / "cut.gsrec"
    write_recording(path, simulated_chunks(4.0, **SENSORS)[5:], {"filters": ["ahf"]})
    recording = open_recording(path)
    calls = recording_calls(monkeypatch, pipeline_module.ConfigWait, ("sample",))
    replay(recording, ("ahf",))
    live, calls[:] = [(args[1], result is None) for _, _, args, result in calls], []
    batch_replay(recording, ("ahf",))
    assert len(live) > 50 and live[-1][1] is False  # the wait expired
    assert [(args[1], result is None) for _, _, args, result in calls] == live


def reordered_spec():
    """The project's spec with IMU_RAW's and ATTITUDE's fields in another order (the timestamp stays first)."""
    text = SPEC_PATH.read_text(encoding="utf-8")

    def move_after_timestamp(block_name, field_names):
        nonlocal text
        start = text.index(f'name = "{block_name}"')
        end = text.index("[[frames]]", start)
        block = text[start:end]
        lines = block.splitlines(keepends=True)
        moved = [line for name in field_names for line in lines if f'name = "{name}"' in line]
        kept = [line for line in lines if line not in moved]
        at = next(i for i, line in enumerate(kept) if 'name = "t_us"' in line) + 1
        text = text[:start] + "".join(kept[:at] + moved + kept[at:]) + text[end:]

    move_after_timestamp("IMU_RAW", ("temperature", "gyr_z", "gyr_y", "gyr_x"))
    move_after_timestamp("ATTITUDE", ("flags", "lambda_gain", "q_z"))
    return load_spec(text)


def test_the_pipeline_reads_frames_by_field_name():
    spec = reordered_spec()
    assert spec.frame("IMU_RAW").field_names[1] == "temperature" and spec.frame("ATTITUDE").field_names[1] == "flags"
    chunks = simulated_chunks(3.0, **SENSORS)
    decoder = StreamDecoder()
    original, other = Pipeline(("ahf",)), Pipeline(("ahf",), spec=spec)
    for t, data in chunks:
        frames = decoder.feed(data, t)
        again = b""
        for frame in frames:
            frame_type = spec.frame(frame.name)
            values = frame.values
            again += encode(new_frame(frame_type, frame.seq, tuple(values[name] for name in frame_type.field_names)))
        original.feed(t, data)
        other.feed(t, again)
    for name in ("imu", "onboard"):
        assert len(original.tables[name]) > 200
        assert np.array_equal(other.tables[name].array(), original.tables[name].array(), equal_nan=True), name
    assert SPEC.frame("IMU_RAW").field_names[1] == "acc_x"
