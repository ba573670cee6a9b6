"""A lost CONFIG is said (issue 22): a recording whose only CONFIG frames are in damaged records is
converted at an accelerometer full scale inferred from 1 g at rest, and every command says so."""

import numpy as np
import pytest

from groundstation.recording import open_recording
from groundstation.session_makers.load import load_session
from groundstation.session_makers.pipeline import SensorConfig, without_config
from groundstation.session_makers.replay import replay

from tests.cli_in_process import run_in_process
from tests.recording.helpers import recording_without_config

INFERRED = "accelerometer full scale ±4 g inferred"  # the simulated board's (at the assumed ±2 g: 0.5 g at rest)


@pytest.fixture
def gs(capsys):
    return lambda *args: run_in_process(capsys, *args)


@pytest.fixture(scope="module")
def damaged(tmp_path_factory):
    return recording_without_config(tmp_path_factory.mktemp("lost-config"))


def test_both_paths_warn_and_convert_at_the_inferred_scale(damaged):
    data = load_session(damaged)
    assert data.config is None and data.damage
    norm_g = np.linalg.norm([data.tables["imu"][f"acc_{a}_g"] for a in "xyz"], axis=0)
    assert abs(np.median(norm_g) - 1.0) < 0.05
    pipeline = replay(open_recording(damaged))
    live = [e["message"] for e in pipeline.events if e["kind"] == "warning"]
    batch = [e["message"] for e in data.events if e["kind"] == "warning"]
    assert live == batch and len(batch) == 1
    assert INFERRED in batch[0] and "±250 °/s" in batch[0]  # the gyro's assumed, and said so


@pytest.mark.parametrize("command", [["export", "--out", "{out}"], ["evaluate"], ["replay"]])
def test_every_command_prints_the_warning(damaged, tmp_path, gs, command):
    args = [a.format(out=tmp_path / "out.csv") for a in command]
    run = gs(args[0], damaged, *args[1:])
    assert run.returncode == 0, run.stderr
    printed = run.stdout + run.stderr
    assert "warning: no CONFIG frame" in printed and INFERRED in printed
    assert "unreadable" in printed or "skipped" in printed  # the damage as well


@pytest.mark.parametrize("norms_counts, fs_g, said", [
    ([2048.0 + (i % 5) for i in range(100)], 16, "±16 g inferred"),  # 2048 LSB/g at ±16 g (MPU-6050 datasheet)
    ([8192.0 if i % 2 else 4096.0 for i in range(100)], 2, "were not still"),
    ([12288.0] * 100, 2, "is 1 g at no full scale"),  # 1.5 g at ±4 g, 0.75 g at ±2 g
])
def test_the_accelerometer_scale_is_inferred_only_from_a_still_stretch_at_1_g(norms_counts, fs_g, said):
    sensor, message = without_config(SensorConfig(), norms_counts)
    assert sensor == SensorConfig(accel_fs_g=fs_g) and said in message and message.startswith("no CONFIG frame")
