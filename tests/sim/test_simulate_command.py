"""``groundstation simulate`` as a user runs it: files written, truth consistent with the bytes."""

import numpy as np
import pandas as pd
import pytest

import firmware_protocol as fp
from groundstation import quaternion as quat
from groundstation import units
from groundstation.cli import main
from groundstation.sim.profiles import PROFILES
from tests.cli_in_process import run_in_process


@pytest.mark.parametrize("name", PROFILES)
def test_every_profile_writes_bytes_and_a_truth_file_that_matches_them(tmp_path, name):
    out = tmp_path / f"{name}.bin"
    assert main(["simulate", "--scenario", name, "--duration", "12", "--seed", "2", "--loss", "0.05", "--out", str(out)]) == 0
    frames = fp.StreamDecoder().feed(out.read_bytes())
    truth = pd.read_csv(tmp_path / f"{name}.truth.csv.gz")
    imu = {f["t_us"]: f for f in frames if f.name == "IMU_RAW"}
    # Every sample in the truth (the board's clock runs 20 ppm fast: one more may fit); 5 % lost on the link.
    assert len(truth) in (1100, 1101) and 0.9 * 1100 < len(imu) < len(truth)
    # Each frame against the truth row at its time (a frame with no such row is a KeyError), all at once.
    rows = truth.set_index((truth["time_s"] * 1e6).round().astype(np.int64)).loc[list(imu)]
    counts = np.array([[f[k] for k in ("acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")] for f in imu.values()])
    assert np.allclose(rows[["acc_x_m_s2", "acc_y_m_s2", "acc_z_m_s2"]], units.accel_counts_to_m_s2(counts[:, :3], 4))
    assert np.allclose(rows[["gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s"]], units.gyro_counts_to_rad_s(counts[:, 3:], 500))
    q = truth[["true_qw", "true_qx", "true_qy", "true_qz"]].to_numpy()
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)
    # In the initial rest the craft is level, nose north; the sensor (default mounting: x forward,
    # z up) has +z up and +x north in ENU, and its accelerometer reads about +1 g on z.
    rest = truth[truth["moving"] == 0]
    r = quat.to_matrix(rest[["true_qw", "true_qx", "true_qy", "true_qz"]].to_numpy())
    assert len(rest) in (100, 101)
    assert np.allclose(r[:, :, 2], [0.0, 0.0, 1.0]) and np.allclose(r[:, :, 0], [0.0, 1.0, 0.0])
    assert np.allclose(rest["acc_z_m_s2"], 9.81, atol=0.4)


def test_same_seed_same_bytes_and_evaluate_scores_the_truth_file(tmp_path, capsys):
    a, b = tmp_path / "a.bin", tmp_path / "b.bin"
    for path in (a, b):
        assert main(["simulate", "--scenario", "slide", "--duration", "20", "--seed", "4", "--out", str(path)]) == 0
    assert a.read_bytes() == b.read_bytes()
    result = run_in_process(capsys, "evaluate", tmp_path / "a.truth.csv.gz", "--json", "--filters", "ahf,hf")
    assert result.returncode == 0, result.stderr
    assert '"ahf"' in result.stdout and "incl_rmse_deg" in result.stdout


@pytest.mark.parametrize("args, message", [
    (["--scenario", "slide", "--loss", "1.5"], "loss"),
    (["--scenario", "slide", "--gyro-fs", "300"], "full scale"),
    (["--scenario", "slide", "--sensors", "lidar"], "unknown sensor"),
    (["--scenario", "slide", "--duration", "-1"], "positive"),
])
def test_bad_options_get_a_clear_message_not_a_traceback(tmp_path, capsys, args, message):
    result = run_in_process(capsys, "simulate", *args, "--out", tmp_path / "x.bin")
    assert result.returncode == 2 and message in result.stderr and "Traceback" not in result.stderr


def test_unwritable_output_is_a_user_error(tmp_path, capsys):
    result = run_in_process(capsys, "simulate", "--duration", "3", "--out", tmp_path / "no" / "x.bin")
    assert result.returncode == 2 and "cannot write" in result.stderr and "Traceback" not in result.stderr
