"""Names from a log kept apart (issue 31.9): ULog topics and DataFlash types that differ only in case, and
export columns that a table's prefix would make one, are never merged: each keeps its rows (counted by
pyulog and pymavlink's DFReader, reading the same crafted files), the later one gets a suffix, and the
session's warnings say so."""

from collections import Counter

import numpy as np
import pandas as pd
from pymavlink import DFReader
from pyulog import ULog

from groundstation.cli import main
from groundstation.session_makers.load import load_session
from tests.autopilot.mavlink_helpers import BOOT_US, px4_flight, write_ulog
from tests.crafted_files import dataflash_types, ulog_topics

FILTERS = ("ahf2",)


def test_ulog_topics_that_differ_in_case_are_two_tables(tmp_path):
    path = tmp_path / "case.ulg"
    ulog_topics(path, ["caseTopic", "casetopic"])
    rows = {d.name: len(d.data["timestamp"]) for d in ULog(str(path)).data_list}
    data = load_session(path, FILTERS)
    assert len(data.tables["casetopic"]["time_s"]) == rows["caseTopic"]  # the first keeps the name
    assert len(data.tables["casetopic__2"]["time_s"]) == rows["casetopic"]
    said = [w for w in data.warnings if "casetopic__2" in w]
    assert len(said) == 1 and "'caseTopic'" in said[0] and "'casetopic'" in said[0]


def test_dataflash_types_that_differ_in_case_are_two_tables(tmp_path):
    path = tmp_path / "case.bin"
    dataflash_types(path, ["ABC", "Abc"])
    reader, rows = DFReader.DFReader_binary(str(path), zero_time_base=False), Counter()
    while (msg := reader.recv_msg()) is not None:
        rows[msg.get_type()] += 1
    data = load_session(path, FILTERS)
    assert len(data.tables["abc"]["time_s"]) == rows["ABC"] and len(data.tables["abc__2"]["time_s"]) == rows["Abc"]
    assert any("'Abc'" in w and "abc__2" in w for w in data.warnings)


def test_export_columns_that_a_prefix_would_merge_are_kept_apart(tmp_path, capsys):
    """Topic ``foo`` field ``bar_baz`` and topic ``foo_bar`` field ``baz``: both ``foo_bar_baz`` in a CSV or
    Parquet export; and topic ``ahf2`` field ``qw`` would overwrite the estimator's ``ahf2_qw``."""
    flight, _ = px4_flight(duration_s=2.0)
    def topic(field, value, rows):
        return [("uint64_t", "timestamp"), ("float", field)], {"timestamp": BOOT_US + 20_000 * np.arange(rows), field: np.full(rows, value)}
    path = tmp_path / "prefix.ulg"
    write_ulog(path, {**flight, "foo": topic("bar_baz", 1.0, 10), "foo_bar": topic("baz", 2.0, 20), "ahf2": topic("qw", 7.0, 5)})
    counts = {d.name: len(d.data["timestamp"]) for d in ULog(str(path)).data_list}
    for suffix in (".csv", ".parquet"):
        out = tmp_path / f"prefix{suffix}"
        assert main(["export", str(path), "--out", str(out), "--filters", "ahf2"]) == 0
        said = capsys.readouterr().out
        frame = pd.read_csv(out) if suffix == ".csv" else pd.read_parquet(out)
        assert frame["foo_bar_baz"].count() == counts["foo"] and (frame["foo_bar_baz"].dropna() == 1.0).all()
        assert frame["foo_bar_baz__2"].count() == counts["foo_bar"] and (frame["foo_bar_baz__2"].dropna() == 2.0).all()
        assert frame["ahf2_qw"].notna().all() and (frame["ahf2_qw"].abs() <= 1.0).all()  # the estimator's, whole
        assert frame["ahf2_qw__2"].count() == counts["ahf2"]
        assert "warning:" in said and "'foo_bar_baz__2'" in said and "'ahf2_qw__2'" in said


def test_a_topic_named_as_a_session_table_keeps_both(tmp_path):
    """A topic ``truth`` beside the simulator's truth (``vehicle_attitude_groundtruth``): the session's
    ``truth`` table stays the simulator's, the topic is ``truth_log``."""
    path = tmp_path / "truth.ulg"
    rows = ulog_topics(path, ["truth"])
    attitude = {d.name: len(d.data["timestamp"]) for d in ULog(str(path)).data_list}["vehicle_attitude_groundtruth"]
    data = load_session(path, FILTERS)
    assert len(data.tables["truth_log"]["time_s"]) == rows["truth"]
    assert len(data.tables["truth"]["time_s"]) == attitude and "qw" in data.tables["truth"]


def test_columns_that_flattening_or_units_would_merge_are_kept_apart(tmp_path):
    """A ULog array ``a[2]`` beside a field ``a_0`` (both column ``a_0`` once flattened), and a field ``Alt``
    in metres beside a field ``Alt_m`` (both ``Alt_m`` once the unit is a suffix)."""
    from groundstation.session_parts.catalogue import message_table

    flight, _ = px4_flight(duration_s=2.0)
    rows = 10
    fields = [("uint64_t", "timestamp"), ("float[2]", "a"), ("float", "a_0")]
    columns = {"timestamp": BOOT_US + 10_000 * np.arange(rows), "a": np.tile([1.0, 2.0], (rows, 1)), "a_0": np.full(rows, 3.0)}
    path = tmp_path / "flat.ulg"
    write_ulog(path, {**flight, "arr": (fields, columns)})
    raw = next(d for d in ULog(str(path)).data_list if d.name == "arr").data
    data = load_session(path, FILTERS)
    table = data.tables["arr"]
    assert list(table) == ["time_s", "a_0", "a_1", "a_0__2"]
    np.testing.assert_array_equal(table["a_0"], raw["a[0]"])
    np.testing.assert_array_equal(table["a_0__2"], raw["a_0"])
    assert any("'a_0__2'" in w for w in data.warnings)
    renamed = []
    info = message_table("alt", "ALT", ["Alt", "Alt_m"], {"Alt": "m"}, renamed)
    assert info.column_names == ("time_s", "Alt_m", "Alt_m__2") and len(renamed) == 1 and "'Alt_m'" in renamed[0]
