"""CSV and Parquet from the export columns."""

from __future__ import annotations

import importlib.util

import pandas as pd

from groundstation.errors import UserError
from groundstation.export.files import atomic_output

CSV_FLOAT_FORMAT = "%.10g"  # fixed, so identical input gives byte-identical files


def write_csv(columns: dict, path, overwrite: bool = False) -> None:
    with atomic_output(path, overwrite) as temporary:
        pd.DataFrame(columns).to_csv(temporary, index=False, float_format=CSV_FLOAT_FORMAT, lineterminator="\n")


def require_pyarrow() -> None:
    """Parquet needs the optional pyarrow (pandas uses it): a clear message, not pandas' ImportError."""
    if importlib.util.find_spec("pyarrow") is None:
        raise UserError("Parquet export needs pyarrow: pip install 'groundstation[parquet]'")


def write_parquet(columns: dict, path, overwrite: bool = False) -> None:
    require_pyarrow()
    with atomic_output(path, overwrite) as temporary:
        pd.DataFrame(columns).to_parquet(temporary, index=False)
