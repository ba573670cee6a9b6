"""The SAMPLES record payload: a block of named float64 columns, values kept bit for bit.

    JSON length (uint32) | JSON {"columns": [names...], "rows": N} | N float64 per column, column after column

Imported datasets travel this way so that evaluating the recording sees exactly the CSV's numbers
(NaN cells included).
"""

from __future__ import annotations

import json
import struct

import numpy as np

from groundstation.recording.format import MAX_PAYLOAD_BYTES

JSON_LENGTH = struct.Struct("<I")
FLOAT64_LE = np.dtype("<f8")
# A damaged block (one flipped bit fails its CRC) loses its rows, so blocks are small: 64 KiB of
# values is ~500 rows of a 16-column trial, 0.5 % of framing. (Earlier versions wrote 4 MiB blocks,
# so one bit cost two thirds of a typical trial; the reader takes blocks of any size.)
BLOCK_BYTES = 64 * 1024


def as_float64_columns(columns: dict[str, object]) -> dict[str, np.ndarray]:
    """Checks names and lengths; integer and boolean columns are converted only when exact."""
    if not columns:
        raise ValueError("write_samples needs at least one column")
    out = {}
    for name, values in columns.items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"sample column names must be non-empty strings, not {name!r}")
        array = np.asarray(values)
        if array.ndim != 1 or array.dtype.kind not in "biuf":
            raise ValueError(f"sample column {name!r} must be a 1-D numeric array, not {array.dtype} {array.shape}")
        converted = array.astype(FLOAT64_LE)
        if array.dtype.kind in "iu" and not np.array_equal(converted.astype(array.dtype), array):
            raise ValueError(f"sample column {name!r} has integers that float64 cannot hold exactly")
        out[name] = converted
    lengths = {len(v) for v in out.values()}
    if len(lengths) != 1:
        raise ValueError(f"sample columns differ in length: {sorted(lengths)}")
    return out


def encode_blocks(columns: dict[str, np.ndarray]) -> list[bytes]:
    """Payloads of the SAMPLES records for ``columns`` (from ``as_float64_columns``), in row order."""
    names = list(columns)
    n_rows = len(columns[names[0]])
    rows_per_block = max(1, BLOCK_BYTES // (8 * len(names)))
    payloads = []
    for start in range(0, max(n_rows, 1), rows_per_block):
        stop = min(start + rows_per_block, n_rows)
        header = json.dumps({"columns": names, "rows": stop - start}).encode()
        parts = [JSON_LENGTH.pack(len(header)), header]
        parts += [columns[name][start:stop].tobytes() for name in names]
        payload = b"".join(parts)
        if len(payload) > MAX_PAYLOAD_BYTES:
            raise ValueError(f"too many sample columns ({len(names)}) for one record")
        payloads.append(payload)
    return payloads


def decode_block(payload: memoryview) -> dict[str, np.ndarray]:
    """The columns of one SAMPLES payload; ValueError says what is inconsistent."""
    if len(payload) < JSON_LENGTH.size:
        raise ValueError("samples block too short for its header")
    (json_length,) = JSON_LENGTH.unpack_from(payload)
    data_start = JSON_LENGTH.size + json_length
    try:
        header = json.loads(bytes(payload[JSON_LENGTH.size:data_start]))
        names, n_rows = list(header["columns"]), int(header["rows"])
        if not all(isinstance(name, str) for name in names):
            raise TypeError
    except (ValueError, KeyError, TypeError):
        raise ValueError("samples block header is not valid JSON with 'columns' and 'rows'") from None
    if len(payload) - data_start != 8 * n_rows * len(names) or len(set(names)) != len(names):
        raise ValueError(f"samples block size does not match its {len(names)} columns of {n_rows} rows")
    values = np.frombuffer(payload, dtype=FLOAT64_LE, count=n_rows * len(names), offset=data_start)
    return {name: values[i * n_rows:(i + 1) * n_rows] for i, name in enumerate(names)}
