"""A lost CONFIG is said (issue 22): a recording whose only CONFIG frames are in damaged records is
converted at an accelerometer full scale inferred from 1 g at rest, and every command says so."""

import subprocess
import sys

import numpy as np
import pytest

from groundstation.recording import open_recording
from groundstation.session.data import load_session
from groundstation.session.replay import replay

from tests.recording.helpers import recording_without_config

INFERRED = "accelerometer full scale ±4 g inferred"  # the simulated board's (at the assumed ±2 g: 0.5 g at rest)


def gs(*args):
    return subprocess.run([sys.executable, "-m", "groundstation", *map(str, args)], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def without_config(tmp_path_factory):
    return recording_without_config(tmp_path_factory.mktemp("lost-config"))


def test_both_paths_warn_and_convert_at_the_inferred_scale(without_config):
    data = load_session(without_config)
    assert data.config is None and data.damage
    norm_g = np.linalg.norm([data.sensors[f"acc_{a}_g"] for a in "xyz"], axis=0)
    assert abs(np.median(norm_g) - 1.0) < 0.05
    pipeline = replay(open_recording(without_config))
    live = [e["message"] for e in pipeline.events if e["kind"] == "warning"]
    batch = [e["message"] for e in data.events if e["kind"] == "warning"]
    assert live == batch and len(batch) == 1
    assert INFERRED in batch[0] and "±250 °/s" in batch[0]  # the gyro's assumed, and said so


@pytest.mark.parametrize("command", [["export", "--out", "{out}"], ["evaluate"], ["replay"]])
def test_every_command_prints_the_warning(without_config, tmp_path, command):
    args = [a.format(out=tmp_path / "out.csv") for a in command]
    run = gs(args[0], without_config, *args[1:])
    assert run.returncode == 0, run.stderr
    printed = run.stdout + run.stderr
    assert "warning: no CONFIG frame" in printed and INFERRED in printed
    assert "unreadable" in printed or "skipped" in printed  # the damage as well
