"""A CONFIG that changes the sensor's full scales or mounting without a device restart is not applied
silently (issue 22): the data keeps the scales in use, a ``config_conflict`` event says what changed, and
the user decides (``--accept-config-changes`` on files). One forged CONFIG (16 g for 4 g) rescaled every
later sample by 4x before. After a device restart a new CONFIG applies, as before."""

import numpy as np
import pytest

from groundstation.cli import main
from groundstation.recording import open_recording
from groundstation.session_makers.load import load_session
from groundstation.session_makers.replay import replay
from groundstation.sim.firmware import FirmwareSettings
from tests.crafted_files import forged_config_recording

AT_S = 4.0


def acc_norm_g(imu_time_s, acc) -> tuple[float, float]:
    """Median accelerometer norm before and after the forged CONFIG's time."""
    norm = np.linalg.norm(acc, axis=1)
    late = imu_time_s > AT_S + 0.5
    return float(np.nanmedian(norm[imu_time_s < AT_S - 0.5])), float(np.nanmedian(norm[late]))


def of_pipeline(pipeline):
    imu = pipeline.imu
    return imu.column("time_s"), np.column_stack([imu.column(f"acc_{a}_g") for a in "xyz"])


def of_data(data):
    imu = data.tables["imu"]
    return imu["time_s"], np.column_stack([imu[f"acc_{a}_g"] for a in "xyz"])


def conflicts(events):
    return [e for e in events if e["kind"] == "config_conflict"]


@pytest.fixture(scope="module")
def forged(tmp_path_factory):
    return forged_config_recording(tmp_path_factory.mktemp("forged"), at_s=AT_S, accel_fs_g=16)


def test_both_paths_keep_the_scales_in_use_and_say_what_changed(forged):
    pipeline = replay(open_recording(forged))
    data = load_session(forged)
    for name, (time_s, acc) in {"pipeline": of_pipeline(pipeline), "batch": of_data(data)}.items():
        before, after = acc_norm_g(time_s, acc)
        assert before == pytest.approx(1.0, abs=0.05) and after == pytest.approx(1.0, abs=0.05), name  # was 4.0 after
    assert conflicts(pipeline.events) == [{k: v for k, v in e.items() if k != "t_s"} for e in conflicts(data.events)]
    (event,) = conflicts(data.events)
    assert event["changes"] == ["accelerometer full scale ±4 g → ±16 g"] and "kept ±4 g" in event["message"]
    assert pipeline.sensor.accel_fs_g == 4 and pipeline.config_guard.held.accel_fs_g == 16


def test_accepting_applies_the_new_scales_on_both_paths(forged):
    pipeline = replay(open_recording(forged), accept_config_changes=True)
    data = load_session(forged, accept_config_changes=True)
    for time_s, acc in (of_pipeline(pipeline), of_data(data)):
        before, after = acc_norm_g(time_s, acc)
        assert before == pytest.approx(1.0, abs=0.05) and after == pytest.approx(4.0, abs=0.2)
    assert conflicts(pipeline.events) == [{k: v for k, v in e.items() if k != "t_s"} for e in conflicts(data.events)]
    assert "accepted" in conflicts(data.events)[0]["message"]


def test_the_user_answers_a_held_config_in_the_pipeline(forged):
    recording = open_recording(forged)
    pipeline = replay(recording)
    assert pipeline.config_guard.held is not None
    pipeline.resolve_config(accept=False, t_host_ns=1)
    assert pipeline.config_guard.held is None and pipeline.sensor.accel_fs_g == 4
    assert pipeline.events[-1]["kind"] == "config_kept"
    pipeline = replay(recording)
    pipeline.resolve_config(accept=True, t_host_ns=1)
    assert pipeline.sensor.accel_fs_g == 16 and pipeline.events[-1]["kind"] == "config_accepted"


def test_an_answer_recorded_live_is_replayed_where_it_was_given(tmp_path):
    answer_s = AT_S + 1.0
    path = forged_config_recording(tmp_path, at_s=AT_S, accel_fs_g=16,
                                   events=[(round(answer_s * 1e9), {"t_host_ns": round(answer_s * 1e9), "kind": "config_accepted"})])
    pipeline = replay(open_recording(path))
    data = load_session(path)
    assert [e for e in pipeline.events if e["kind"] == "config_accepted"] == [
        {k: v for k, v in e.items() if k != "t_s"} for e in data.events if e["kind"] == "config_accepted"]
    (forged_s,) = [e["t_s"] for e in data.events if e["kind"] == "config_conflict"]  # session times
    (accepted_s,) = [e["t_s"] for e in data.events if e["kind"] == "config_accepted"]
    assert accepted_s - forged_s == pytest.approx(answer_s - AT_S, abs=0.05)
    # Against the same recording kept at ±4 g throughout: equal up to the answer, 4x after it (counts
    # over 2048 LSB/g instead of 8192: powers of two, so exactly 4x).
    kept_time_s, kept = of_data(load_session(forged_config_recording(tmp_path, "kept", at_s=AT_S, accel_fs_g=16)))
    for time_s, acc in (of_pipeline(pipeline), of_data(data)):
        np.testing.assert_array_equal(time_s, kept_time_s)
        switch = int(np.argmax(np.any(acc != kept, axis=1)))  # the first row converted otherwise
        assert time_s[switch] == pytest.approx(accepted_s, abs=0.05)  # where the answer was given
        after = np.arange(len(time_s)) >= switch
        np.testing.assert_array_equal(acc[~after], kept[~after])
        np.testing.assert_array_equal(acc[after], 4 * kept[after])
    np.testing.assert_array_equal(of_pipeline(pipeline)[1], of_data(data)[1])  # the same rule, the same numbers


def test_after_a_device_restart_a_new_config_applies(tmp_path):
    path = forged_config_recording(tmp_path, at_s=AT_S, firmware=FirmwareSettings(reboot_after_s=2.0), accel_fs_g=16)
    data = load_session(path)
    pipeline = replay(open_recording(path))
    assert not conflicts(data.events) and not conflicts(pipeline.events)
    assert any(e["kind"] == "device_reset" for e in data.events)
    for time_s, acc in (of_pipeline(pipeline), of_data(data)):
        assert acc_norm_g(time_s, acc)[1] == pytest.approx(4.0, abs=0.2)


@pytest.mark.parametrize("command", [["export", "--out", "{out}"], ["evaluate"]])
def test_the_commands_say_so_and_accept_on_request(forged, tmp_path, command, capsys):
    args = [a.format(out=tmp_path / "out.csv") for a in command]
    assert main([args[0], str(forged), *args[1:]]) == 0
    printed = capsys.readouterr()
    assert "without a device restart" in printed.out + printed.err and "kept ±4 g" in printed.out + printed.err
    args = [a.replace("out.csv", "accepted.csv") for a in args]
    assert main([args[0], str(forged), *args[1:], "--accept-config-changes"]) == 0
    printed = capsys.readouterr()
    assert "accepted (--accept-config-changes)" in printed.out + printed.err


def test_the_guard_holds_until_a_restart_or_an_answer_and_says_each_conflict_once():
    from groundstation.session_makers.pipeline import ConfigGuard, SensorConfig

    real, forged = SensorConfig(accel_fs_g=4, gyro_fs_dps=500), SensorConfig(accel_fs_g=16, gyro_fs_dps=500, mounting=3)
    guard = ConfigGuard()
    assert guard.config(1, real) == (True, None)
    applies, event = guard.config(2, forged)
    assert not applies and event["changes"] == ["accelerometer full scale ±4 g → ±16 g", "mounting 1 → 3"]
    assert guard.config(3, real) == (True, None) and guard.held == forged  # the device's own CONFIG again
    assert guard.config(4, forged) == (False, None)  # said once
    assert guard.config(5, SensorConfig(accel_fs_g=8, gyro_fs_dps=500))[1] is not None  # another change: said
    guard.device_reset()
    assert guard.config(6, forged) == (True, None) and guard.held is None and guard.trusted == forged
