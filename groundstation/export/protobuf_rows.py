"""A table's rows as protobuf messages, the typed encoding every MCAP viewer decodes and plots.

Each column is a ``double`` field of one proto3 message, numbered from 1 in the table's column order and
named after the column (a character a protobuf name cannot hold, as the ``.`` of a ULog's nested field,
becomes ``_``). A row is written with every field, NaN included (a double holds NaN, so a missing value
reads back as NaN, bit for bit, as every other value), so all rows of a table have one length and a whole
table is encoded at once with numpy. The schema is a ``FileDescriptorSet`` (MCAP's ``protobuf`` schema
encoding). Both are written here by the wire format's few rules (varint keys, 8-byte doubles,
length-delimited strings and messages: protobuf.dev/programming-guides/encoding), so the project needs
neither protoc nor the protobuf runtime.
"""

from __future__ import annotations

import re

import numpy as np

PACKAGE = "groundstation"
_NOT_IN_NAME = re.compile(r"[^A-Za-z0-9_]")
_VARINT, _FIXED64, _LENGTH_DELIMITED = 0, 1, 2  # wire types
_TYPE_DOUBLE, _LABEL_OPTIONAL = 1, 1  # FieldDescriptorProto.Type / .Label


def _varint(value: int) -> bytes:
    out = bytearray()
    while True:
        byte, value = value & 0x7F, value >> 7
        out.append(byte | (0x80 if value else 0))
        if not value:
            return bytes(out)


def _key(number: int, wire_type: int) -> bytes:
    return _varint(number << 3 | wire_type)


def _delimited(number: int, data: bytes) -> bytes:
    return _key(number, _LENGTH_DELIMITED) + _varint(len(data)) + data


def _text(number: int, text: str) -> bytes:
    return _delimited(number, text.encode())


def _number(number: int, value: int) -> bytes:
    return _key(number, _VARINT) + _varint(value)


def field_names(columns) -> list[str]:
    """The protobuf field name of each column: the column's name where protobuf allows it, else with
    ``_`` for each character it does not (a leading digit gets one before it); unique in the message."""
    names: list[str] = []
    for column in columns:
        name = _NOT_IN_NAME.sub("_", column)
        name = f"_{name}" if not name or name[0].isdigit() else name
        names.append(name if name not in names else f"{name}_{len(names) + 1}")
    return names


def message_name(table: str) -> str:
    """The fully qualified message name of a table (``groundstation.imu``)."""
    return f"{PACKAGE}.{field_names([table])[0]}"


def descriptor_set(table: str, columns) -> bytes:
    """The ``FileDescriptorSet`` of a table's message (descriptor.proto's field numbers): one file, one
    message, a ``double`` per column."""
    fields = b"".join(_delimited(2, _text(1, name) + _number(3, number) + _number(4, _LABEL_OPTIONAL)
                                 + _number(5, _TYPE_DOUBLE))
                      for number, name in enumerate(field_names(columns), start=1))  # DescriptorProto.field
    message = _text(1, message_name(table).rpartition(".")[2]) + fields
    file = _text(1, f"{message_name(table)}.proto") + _text(2, PACKAGE) + _delimited(4, message) + _text(12, "proto3")
    return _delimited(1, file)


class RowEncoder:
    """Encodes rows of a table with these columns (in this order) as its message: ``encode`` gives every
    row's bytes in one buffer, ``size`` bytes each."""

    def __init__(self, columns):
        self.columns = list(columns)
        keys = [_key(number, _FIXED64) for number in range(1, len(self.columns) + 1)]
        self._dtype = np.dtype([part for i, key in enumerate(keys)
                                for part in ((f"k{i}", "u1", (len(key),)), (f"v{i}", "<f8"))])
        self._keys = [np.frombuffer(key, dtype=np.uint8) for key in keys]
        self.size = self._dtype.itemsize

    def encode(self, columns: dict[str, np.ndarray], rows: slice | np.ndarray = slice(None)) -> bytes:
        """The rows' messages, one after another (row ``i`` at ``i * size``)."""
        values = [np.asarray(columns[c], dtype=float)[rows] for c in self.columns]
        records = np.empty(len(values[0]) if values else 0, dtype=self._dtype)
        for i, (key, value) in enumerate(zip(self._keys, values)):
            records[f"k{i}"] = key
            records[f"v{i}"] = value
        return records.tobytes()
