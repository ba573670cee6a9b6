"""Reader of the dataset CSV layout (../shared/datasets/README.md), plain or gzip'd.

Columns: ``time_s``; ``gyr_{x,y,z}_rad_s``; ``acc_{x,y,z}_m_s2``; optional ``mag_{x,y,z}_uT``; optional
``true_q{w,x,y,z}`` (w first; rotates IMU-frame vectors into an east-north-up earth frame; empty cells
where the reference lost track, read as NaN); optional ``moving`` (0/1). The sessions issue reuses this
for its CSV import.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd

GYR = ["gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s"]
ACC = ["acc_x_m_s2", "acc_y_m_s2", "acc_z_m_s2"]
MAG = ["mag_x_uT", "mag_y_uT", "mag_z_uT"]
TRUE_Q = ["true_qw", "true_qx", "true_qy", "true_qz"]


class DatasetError(ValueError):
    """The file is missing, unreadable or not in the dataset CSV layout; the message says which."""


@dataclasses.dataclass(frozen=True)
class Trial:
    time_s: np.ndarray  # (N,)
    gyr_rad_s: np.ndarray  # (N, 3), IMU axes
    acc_m_s2: np.ndarray  # (N, 3), IMU axes, specific force
    mag_uT: np.ndarray | None  # (N, 3) or None
    true_q: np.ndarray | None  # (N, 4), IMU -> ENU, NaN rows where the reference was lost
    moving: np.ndarray | None  # (N,) bool

    def __len__(self) -> int:
        return len(self.time_s)


def read_csv(path) -> Trial:
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f"{path}: no such file")
    try:
        frame = pd.read_csv(path, compression="infer")
    except (OSError, EOFError, UnicodeDecodeError, pd.errors.ParserError, pd.errors.EmptyDataError) as error:
        raise DatasetError(f"{path}: not a readable CSV file ({str(error).strip()})") from None
    missing = [c for c in ["time_s", *GYR, *ACC] if c not in frame.columns]
    if missing:
        raise DatasetError(f"{path}: not in the dataset CSV layout; missing columns {', '.join(missing)}")
    if len(frame) == 0:
        raise DatasetError(f"{path}: has a header but no samples")

    def numeric(columns):
        values = frame[columns].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=float)
        return values

    def optional(columns):
        return numeric(columns) if all(c in frame.columns for c in columns) else None

    time_s = numeric(["time_s"])[:, 0]
    if not np.all(np.isfinite(time_s)):
        raise DatasetError(f"{path}: time_s has empty or non-numeric cells")
    moving = optional(["moving"])
    return Trial(
        time_s=time_s,
        gyr_rad_s=numeric(GYR),
        acc_m_s2=numeric(ACC),
        mag_uT=optional(MAG),
        true_q=optional(TRUE_Q),
        moving=None if moving is None else moving[:, 0] == 1.0,
    )
