"""A logged message's field in a session table: the column named ``field``, or ``field_<unit>`` as
``session_parts.catalogue.message_table`` names it (``Vcc`` -> ``Vcc_V``, ``Clip`` -> ``Clip``)."""

from __future__ import annotations

import numpy as np


def message_field(columns: dict, field: str) -> np.ndarray | None:
    """The field's values as floats; None when the table has no such field."""
    for name, values in columns.items():
        if name == field or name.startswith(field + "_"):
            return np.asarray(values, dtype=float)
    return None
