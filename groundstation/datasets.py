"""Reader of the dataset CSV layout (../shared/datasets/README.md), plain or gzip'd.

Columns: ``time_s``; ``gyr_{x,y,z}_rad_s``; ``acc_{x,y,z}_m_s2``; optional ``mag_{x,y,z}_uT``; optional
``true_q{w,x,y,z}`` (w first; rotates IMU-frame vectors into an east-north-up earth frame; empty cells
where the reference lost track, read as NaN); optional ``moving`` (0/1). The sessions issue reuses this
for its CSV import.
"""

from __future__ import annotations

import dataclasses
import zlib
from pathlib import Path

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
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


# Beyond these a value is corruption or the wrong unit, not motion: the fastest MEMS gyroscopes read
# 4000 deg/s (70 rad/s), high-g accelerometers 400 g, magnetometers under 5 mT.
SENSOR_LIMITS = ((GYR, 200.0, "rad/s"), (ACC, 5000.0, "m/s²"), (MAG, 10_000.0, "µT"))


def read_csv(path) -> Trial:
    path = Path(path)
    if not path.is_file():
        raise DatasetError(f"{path}: no such file")
    import pandas as pd  # here: the app's start and the commands that read no CSV need not wait for pandas

    try:
        frame = pd.read_csv(path, compression="infer")
    except (OSError, EOFError, zlib.error, UnicodeDecodeError, pd.errors.ParserError, pd.errors.EmptyDataError) as error:
        raise DatasetError(f"{path}: not a readable CSV file ({str(error).strip()})") from None
    known = [c for c in ["time_s", *GYR, *ACC, *MAG, *TRUE_Q, "moving"] if c in frame.columns]
    return trial_from_columns({name: numeric_column(frame[name], path) for name in known}, path)


def numeric_column(cells: pd.Series, path) -> np.ndarray:
    """float64 values of a CSV column; empty cells are NaN, any other text is an error (with its line)."""
    import pandas as pd

    values = pd.to_numeric(cells, errors="coerce")
    text = values.isna() & cells.notna()
    if text.any():
        row = int(np.flatnonzero(text.to_numpy())[0])
        raise DatasetError(f"{path}: {cells.name} has text where a number belongs (row {row + 1}: {cells.iloc[row]!r})")
    return values.to_numpy(dtype=float)


def trial_from_columns(columns: dict[str, np.ndarray], where) -> Trial:
    """A trial from named float64 columns (a dataset CSV, an imported recording's samples), checked:
    the required columns are there, time increases from row to row, every sensor has values and none
    is beyond what a sensor can read. DatasetError says what is wrong, and where."""
    missing = [c for c in ["time_s", *GYR, *ACC] if c not in columns]
    if missing:
        raise DatasetError(f"{where}: not in the dataset CSV layout; missing columns {', '.join(missing)}")
    time_s = columns["time_s"]
    if len(time_s) == 0:
        raise DatasetError(f"{where}: has a header but no samples")
    if not np.all(np.isfinite(time_s)):
        raise DatasetError(f"{where}: time_s has empty or non-numeric cells")
    backwards = np.flatnonzero(np.diff(time_s) <= 0)
    if len(backwards):
        row = int(backwards[0]) + 1
        raise DatasetError(f"{where}: time_s must increase from row to row, but row {row + 1} ({time_s[row]:g} s) "
                           f"follows {time_s[row - 1]:g} s (rows shuffled, or two recordings joined?)")
    for names, limit, unit in SENSOR_LIMITS:
        for name in names if all(n in columns for n in names) else ():
            values = columns[name]
            if np.isnan(values).all():
                raise DatasetError(f"{where}: {name} has no values (every cell is empty)")
            wild = np.flatnonzero(~(np.abs(values) <= limit) & ~np.isnan(values))
            if len(wild):
                raise DatasetError(f"{where}: {name} reads {values[wild[0]]:g} {unit} in row {wild[0] + 1}, beyond any "
                                   f"sensor (±{limit:g} {unit}): a corrupt file, or not in {unit}?")

    def optional(names):
        return np.column_stack([columns[n] for n in names]) if all(n in columns for n in names) else None

    return Trial(
        time_s=time_s,
        gyr_rad_s=optional(GYR),
        acc_m_s2=optional(ACC),
        mag_uT=optional(MAG),
        true_q=optional(TRUE_Q),
        moving=None if "moving" not in columns else columns["moving"] == 1.0,
    )
