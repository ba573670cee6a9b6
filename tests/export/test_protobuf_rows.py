"""A table's protobuf messages, read by Google's protobuf runtime (not by the code that writes them):
the schema is a valid FileDescriptorSet, every row decodes to its values bit for bit (NaN, infinities,
-0.0, the largest and smallest doubles), whatever the column names."""

import numpy as np
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

from groundstation.export.protobuf_rows import RowEncoder, descriptor_set, field_names, message_name


def message_class(table, columns):
    files = descriptor_pb2.FileDescriptorSet.FromString(descriptor_set(table, columns))
    pool = descriptor_pool.DescriptorPool()
    for file in files.file:
        pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(message_name(table)))


def test_rows_read_back_by_googles_runtime():
    rng = np.random.default_rng(7)
    # a ULog's nested field, a name protobuf cannot start with, two names that meet once cleaned, and enough
    # columns for field numbers past 15 (a two-byte key)
    columns = ["time_s", "esc_0.esc_rpm", "1st", "a.b", "a_b", *(f"c{i}" for i in range(20))]
    special = [np.nan, np.inf, -np.inf, -0.0, 1.7976931348623157e308, 5e-324]
    values = {c: np.concatenate([special, rng.normal(size=50) * 10.0 ** rng.integers(-300, 300, 50)]) for c in columns}
    encoder = RowEncoder(columns)
    buffer = encoder.encode(values)
    Message = message_class("esc_status", columns)
    names = field_names(columns)
    assert names[:5] == ["time_s", "esc_0_esc_rpm", "_1st", "a_b", "a_b_5"] and len(set(names)) == len(names)
    assert [f.name for f in Message.DESCRIPTOR.fields] == names
    rows = [Message.FromString(buffer[i * encoder.size:(i + 1) * encoder.size]) for i in range(len(buffer) // encoder.size)]
    assert len(rows) == 56
    for column, name in zip(columns, names):
        read = np.array([getattr(r, name) for r in rows])
        assert read.tobytes() == values[column].tobytes(), column  # bit for bit
    subset = encoder.encode(values, np.array([3, 1]))
    assert Message.FromString(subset[:encoder.size]).time_s == values["time_s"][3]
