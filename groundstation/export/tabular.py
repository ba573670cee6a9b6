"""CSV and Parquet from the export columns."""

from __future__ import annotations

import pandas as pd

from groundstation.errors import UserError
from groundstation.export.files import atomic_output

CSV_FLOAT_FORMAT = "%.10g"  # fixed, so identical input gives byte-identical files


def write_csv(columns: dict, path, overwrite: bool = False) -> None:
    with atomic_output(path, overwrite) as temporary:
        pd.DataFrame(columns).to_csv(temporary, index=False, float_format=CSV_FLOAT_FORMAT, lineterminator="\n")


def write_parquet(columns: dict, path, overwrite: bool = False) -> None:
    try:
        import pyarrow  # noqa: F401  (pandas needs it; checked first for a clear message)
    except ImportError:
        raise UserError("Parquet export needs pyarrow: pip install 'groundstation[parquet]'") from None
    with atomic_output(path, overwrite) as temporary:
        pd.DataFrame(columns).to_parquet(temporary, index=False)
