"""The batch path (session_makers.batch) against the incremental pipeline fed chunk by chunk (replay).

The incremental pipeline is the oracle: every table bit for bit (NaN where it has NaN), every event
in order, the link's counters and per-second figures, the last CONFIG and the estimators' settings
at the start and the end. Recordings come from the simulator, clean and damaged, with device reboots
and clock jumps, with settings changed while recording, cut so that the first CONFIG is missing, and
with every aiding sensor (magnetometer, barometer, GPS: the compass heading and the position table).

Bit for bit holds on every CPU because both paths run the same code for every rule (docs/session.md,
"Two paths, one result"): where one path has arrays and the other numbers, only additions and
multiplications meet (correctly rounded in IEEE 754, and NumPy never fuses two ufuncs into an FMA);
transcendental functions (the barometer's ``pow``, the heading's ``atan2``), whose SIMD versions may
differ from libm's in the last bit (AVX-512), run as the same scalar calls on both paths.
"""

import math
import subprocess
import sys

import numpy as np
import pytest

from firmware_protocol import StreamDecoder, encode
from groundstation.recording import open_recording
from groundstation.session_makers.batch import batch_replay
from groundstation.session_makers.load import from_pipeline, load_session
from groundstation.session_makers.replay import replay
from groundstation.session.product import exact_estimates
from tests.simulated import simulated_chunks, write_recording

SENSORS = dict(mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=5)
FILTERS = ("ahf", "hf", "ecf", "mcf", "kf")


def event_key(event: dict) -> str:
    return repr({k: ("nan" if isinstance(v, float) and math.isnan(v) else v) for k, v in event.items()})


def assert_same_session(path, filters=FILTERS, forced=None):
    recording = open_recording(path)
    incremental = replay(recording, filters, forced)
    with exact_estimates():  # the estimators' columns as computed, float64 (held apart: ``held_estimates``)
        batch = batch_replay(recording, filters, forced)
    assert list(batch.tables) == list(incremental.tables)
    for name, table in incremental.tables.items():
        columns = {**batch.tables[name].to_dict(), **(batch.held_estimates if name == "imu" else {})}
        assert tuple(columns) == table.columns, name
        for column, expected in table.to_dict().items():
            assert columns[column].dtype == expected.dtype and np.array_equal(columns[column], expected, equal_nan=True), column
    assert [event_key(e) for e in batch.events] == [event_key(e) for e in incremental.events]
    assert batch.decoder.stats == incremental.decoder.stats
    assert np.array_equal(batch.link.per_second.array(), incremental.link.per_second.array())
    assert batch.config == incremental.config
    np.testing.assert_equal(batch.bank.at_start, incremental.bank.at_start)
    np.testing.assert_equal(batch.settings(), incremental.settings())
    assert batch.sensor == incremental.sensor
    return incremental, batch


SCENARIOS = {
    "clean": dict(),
    "reboot": dict(reboot_after_s=4.0),
    "clock_jump": dict(clock_jump_after_s=5.0),
    "bad_link_and_reboot": dict(loss=0.05, burst_loss=0.05, ber=3e-4, truncate=0.01, reboot_after_s=6.0),
    "usb_batches_raw_only": dict(usb_batch_ms=8.0, latency_ms=5.0, jitter_ms=3.0, mode="raw"),
    "estimated_only": dict(mode="estimated"),
    "200_hz_other_mounting_and_scales": dict(rate_hz=200, mounting=7, accel_fs_g=8, gyro_fs_dps=2000),
}


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_batch_equals_incremental(tmp_path, scenario):
    path = tmp_path / "s.gsrec"
    write_recording(path, simulated_chunks(10.0, **SENSORS, **SCENARIOS[scenario]), {"filters": list(FILTERS)})
    incremental, _ = assert_same_session(path)
    kinds = {e["kind"] for e in incremental.events}
    if "reboot" in scenario:
        assert "device_reset" in kinds and incremental.decoder.stats.restarts == 1
    if scenario == "clock_jump":
        assert "clock_jump" in kinds
    if scenario.startswith("bad_link"):
        assert incremental.decoder.stats.crc_errors > 0 and incremental.decoder.stats.frames_lost > 0
    if scenario != "estimated_only":  # every aiding table is there and the position was computed
        assert np.isfinite(incremental.tables["position"].column("pos_n_m")).sum() > 100
        assert np.isfinite(incremental.tables["mag_raw"].column("heading_deg")).sum() > 100


def test_settings_changed_while_recording_and_forced_settings(tmp_path):
    """Changes before the first chunk, between chunks (twice at one time), across a reboot, after the
    last chunk, and for an estimator that does not run; ``--set`` on top of them."""
    chunks = simulated_chunks(10.0, reboot_after_s=5.0, **SENSORS)
    t0 = chunks[0][0]
    second = 1_000_000_000
    events = [
        (t0 - 1, {"kind": "settings", "name": "ahf", "settings": {"lambda_max": 0.5}}),
        (t0 + 2 * second, {"kind": "settings", "name": "hf", "settings": {"beta": 0.3}}),
        (t0 + 2 * second, {"kind": "settings", "name": "ecf", "settings": {"kp": 2.0}}),
        (t0 + 5 * second + 3_000_000, {"kind": "settings", "name": "ahf", "settings": {"lambda_max": 0.2}}),
        (t0 + 7 * second, {"kind": "settings", "name": "vqf", "settings": {"tau_acc_s": 2.0}}),
        (t0 + 60 * second, {"kind": "settings", "name": "hf", "settings": {"beta": 0.1}}),
        (t0 + 3 * second, {"kind": "note", "text": "informational"}),
    ]
    path = tmp_path / "settings.gsrec"
    write_recording(path, chunks, {"filters": ["ahf", "hf", "ecf"]}, events)
    incremental, _ = assert_same_session(path, ("ahf", "hf", "ecf"), forced={"ecf": {"ki": 0.01}})
    assert sum(e["kind"] == "settings" for e in incremental.events) == 5
    assert incremental.settings()["hf"]["beta"] == 0.1 and incremental.settings()["ecf"]["ki"] == 0.01


def test_a_recording_without_its_first_config_holds_then_assumes_then_follows_config(tmp_path):
    """Cut after the boot CONFIG: IMU samples are held for a second, then converted with the assumed
    scales (a warning), and from the CONFIG after the reboot with the board's."""
    chunks = simulated_chunks(8.0, reboot_after_s=4.0, **SENSORS)
    path = tmp_path / "cut.gsrec"
    write_recording(path, chunks[5:], {"filters": ["ahf", "hf"]})
    incremental, _ = assert_same_session(path, ("ahf", "hf"))
    messages = [e.get("message", "") for e in incremental.events]
    assert any(m.startswith("no CONFIG frame") for m in messages)


def test_samples_held_until_a_late_config_are_released_by_it(tmp_path):
    """The boot CONFIG arrives 0.4 s late (its own chunk): the samples before it wait and are converted with it."""
    chunks = simulated_chunks(4.0, **SENSORS)
    decoder = StreamDecoder()
    config = next(f for _, data in chunks for f in decoder.feed(data) if f.name == "CONFIG")
    config_bytes = encode(config)
    first = next(i for i, (_, data) in enumerate(chunks) if config_bytes in data)
    chunks[first] = (chunks[first][0], chunks[first][1].replace(config_bytes, b""))
    late = next(i for i, (t, _) in enumerate(chunks) if t > chunks[0][0] + 400_000_000)
    chunks.insert(late, (chunks[late][0], config_bytes))
    path = tmp_path / "late.gsrec"
    write_recording(path, chunks, {"filters": ["ahf"]})
    incremental, _ = assert_same_session(path, ("ahf",))
    assert not any(e.get("message", "").startswith("no CONFIG") for e in incremental.events)


def test_load_session_takes_the_batch_path_and_gives_what_a_replay_gives(tmp_path):
    """SessionData of a simulated recording with its truth: the same arrays as from a replay, and progress is reported."""
    path = tmp_path / "truth.gsrec"
    subprocess.run([sys.executable, "-m", "groundstation", "simulate", "--duration", "6", "--reboot-after", "3",
                    "--sensors", "mag,baro", "--out", str(path)], check=True, capture_output=True)
    calls = []
    data = load_session(path, ("ahf", "hf"), progress=lambda done, total: calls.append((done, total)))
    expected = from_pipeline(open_recording(path), replay(open_recording(path), ("ahf", "hf")))
    for name in ("time_s", "true_q", "moving"):
        assert np.array_equal(getattr(data, name), getattr(expected, name), equal_nan=True), name
    for name in (*expected.filters, "onboard"):
        assert np.array_equal(data.quaternion(name), expected.quaternion(name), equal_nan=True), name
    assert calls[-1][0] == calls[-1][1] and len(calls) > 2
    assert [d for d, _ in calls] == sorted(d for d, _ in calls)  # progress never goes back
