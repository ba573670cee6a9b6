"""Names from a log never become paths (issue 37.1, 37.3): a folder run (``evaluate DIR --out OUT``, local and
on Dask) writes each table under ``OUT/tables/`` in a folder made by ``names.path_name``, whatever the log
calls it: a ULog topic that climbs out of OUT, a DataFlash type named ``/tmp``, a 300-character topic.
Nothing is written outside OUT, the batch finishes, and each table keeps its log's name in its metadata."""

import os
import shutil
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from groundstation.logbook.folder import evaluate_folder
from groundstation.logbook.summary import log_id
from groundstation.names import PATH_NAME_CHARS, path_name
from tests.crafted_files import dataflash_types, ulog_topics

CLIMBING = "../../escaped"  # from OUT/tables/<topic>: a folder beside OUT
LONG = "t" * 300  # a name no file system takes (errno 36)


@pytest.fixture
def hostile(tmp_path):
    logs = tmp_path / "logs"
    logs.mkdir()
    ulog_topics(logs / "climb.ulg", [CLIMBING, LONG, "Upper"])
    dataflash_types(logs / "root.bin", ["/tmp"])
    return logs


def files_under(folder: Path) -> set[Path]:
    return {Path(root, name) for root, _, names in os.walk(folder) for name in names}


def check_dataset(logs: Path, out: Path, rows: list[dict]) -> None:
    at_root = Path("/tmp") / f"log_id={log_id(logs / 'root.bin', logs)}"  # where the type "/tmp" went
    escaped = at_root.is_dir()
    if escaped:
        shutil.rmtree(at_root)
    assert not escaped, at_root
    assert sorted(p.name for p in out.parent.iterdir()) == sorted([logs.name, out.name])  # nothing beside OUT
    assert {row["path"] for row in rows} == {"climb.ulg", "root.bin"} and not any(row["error"] for row in rows)
    written = files_under(out)
    assert all(out.resolve() in p.resolve().parents for p in written)
    tables = out / "tables"
    for log, name, original in (("climb.ulg", CLIMBING, CLIMBING), ("climb.ulg", LONG, LONG), ("climb.ulg", "upper", "Upper"),
                                ("root.bin", "/tmp", "/tmp")):
        folder = tables / path_name(name)
        assert len(folder.name) <= PATH_NAME_CHARS
        part = folder / f"log_id={log_id(logs / log, logs)}" / "part-0.parquet"
        table = pq.read_table(part)
        assert table.schema.metadata[b"table"] == name.encode()  # the session's name, kept
        assert table.schema.metadata[b"label"].decode().startswith(original)  # and the log's: "Upper (ulog)"
        assert table.num_rows == {"Upper": 30, CLIMBING: 10, LONG: 20, "/tmp": 10}[original]
    assert (tables / "imu").is_dir()  # a plain name is its own folder


def test_a_folder_run_writes_only_under_out(hostile, tmp_path):
    out = tmp_path / "out"
    rows = evaluate_folder(hostile, out, ["ahf2"], workers=1)
    check_dataset(hostile, out, rows)


def test_on_dask_too(hostile, tmp_path):
    distributed = pytest.importorskip("distributed")
    out = tmp_path / "out"
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        rows = evaluate_folder(hostile, out, ["ahf2"], dask_scheduler=cluster.scheduler_address)
    check_dataset(hostile, out, rows)


def test_path_names_are_plain_bounded_and_distinct():
    names = ["imu", "..", ".", "", "/tmp", "a/b", "a_b", "A_b", "con", "ü" * 200, "x" * 101, "x" * 100, "a\x00b", "a\x1b[2Jb"]
    made = [path_name(n) for n in names]
    assert made[0] == "imu" and made[6] == "a_b" and made[11] == "x" * 100
    assert len(set(made)) == len(names)  # no two names one folder
    assert len({m.lower() for m in made}) == len(names)  # nor on a file system blind to case
    for m in made:
        assert m not in (".", "..", "") and len(m.encode()) <= PATH_NAME_CHARS and "/" not in m and not m.startswith(".")
        assert m.isascii() and m.isprintable()
