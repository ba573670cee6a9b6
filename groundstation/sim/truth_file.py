"""The truth of a simulated session in the dataset CSV layout, so ``groundstation evaluate`` scores it.

Columns (``/work/shared/datasets/README.md``, ``groundstation.datasets``): ``time_s`` (the device
timestamp of each sample, s, as the host reads it from the frames: clock drift and jitter
included); ``gyr_{x,y,z}_rad_s`` and ``acc_{x,y,z}_m_s2`` on the sensor axes, exactly the values the
host gets by decoding each ``IMU_RAW`` frame and converting its counts with ``groundstation.units``;
``true_q{w,x,y,z}`` rotating sensor-axis vectors into east-north-up, taken at the true instant of
each read; ``moving`` 1 after the profile's initial rest (the part an evaluation scores; for
``static`` that is the rest the paper's static test scores). ``time_s`` goes on across the board's
resets and clock jumps; ``board_clock_us`` (the 32-bit timestamp the board put on the sample) and
``board_epoch`` (how many resets and clock jumps came before it) say what the board's own clock read,
so a session matches every sample to its truth however the clock restarted (``session.data``).

Every sample the board streamed is a row, also those the link then lost: the file is the truth of
the flight; the raw byte file beside it is what the link delivered.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from groundstation import mounting as mountings
from groundstation import quaternion as quat
from groundstation import units
from groundstation.sim.profiles import REST_S

# v_enu = R v_ned: east = ned y, north = ned x, up = -ned z (a proper rotation).
Q_ENU_FROM_NED = quat.from_matrix(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]))
AXES = ("x", "y", "z")


class TruthTable:
    """Collects the firmware's ``on_samples`` blocks; ``write(path)`` (``.csv`` or ``.csv.gz``)."""

    def __init__(self, accel_fs_g: int, gyro_fs_dps: int, mounting: int):
        self.accel_fs_g, self.gyro_fs_dps = accel_fs_g, gyro_fs_dps
        self._q_body_from_sensor = quat.from_matrix(mountings.matrix(mounting))
        self._blocks: list[dict[str, np.ndarray]] = []

    def __call__(self, t_dev_us, truth, raw, board_us, board_epoch: int) -> None:
        q_enu = quat.multiply(Q_ENU_FROM_NED, quat.multiply(truth.q_body_to_ned, self._q_body_from_sensor))
        gyr = units.gyro_counts_to_rad_s(raw.gyr_counts, self.gyro_fs_dps)
        acc = units.accel_counts_to_m_s2(raw.acc_counts, self.accel_fs_g)
        block = {"time_s": np.asarray(t_dev_us) * 1e-6}
        block.update({f"gyr_{a}_rad_s": gyr[:, i] for i, a in enumerate(AXES)})
        block.update({f"acc_{a}_m_s2": acc[:, i] for i, a in enumerate(AXES)})
        block.update({f"true_q{c}": q_enu[:, i] for i, c in enumerate("wxyz")})
        block["moving"] = (truth.t_s >= REST_S).astype(np.int8)
        block["board_clock_us"] = np.asarray(board_us) & 0xFFFFFFFF
        block["board_epoch"] = np.full(len(block["time_s"]), board_epoch)
        self._blocks.append(block)

    def frame(self) -> pd.DataFrame:
        return pd.DataFrame({k: np.concatenate([b[k] for b in self._blocks]) for k in self._blocks[0]})

    def write(self, path) -> None:
        self.frame().to_csv(path, index=False, float_format="%.10g")
