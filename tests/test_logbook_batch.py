"""A folder run always finishes (issue 37): a log that fails in any way (an exception, a worker that
dies, one that stops and never ends) is its row with the error, the others' work is written; a rerun
replaces the dataset whole; the workers are bounded by the cores and the memory.

The logs are PX4 ULogs written here (``mavlink_helpers.write_ulog``). The faults are put in the
workers' way by a task (``logbook_faults.faulty``) that runs the real ``summarise`` on the other logs."""

import os
from pathlib import Path

import pandas as pd
import pytest

from groundstation.cli import main
from groundstation.logbook import folder as logbook_folder
from groundstation.logbook.folder import evaluate_folder, worker_count
from groundstation.logbook.summary import log_id, summarise
from tests.autopilot.mavlink_helpers import px4_flight, write_ulog
from tests.logbook_faults import faulty

FILTERS = ["ahf"]


def write_logs(folder: Path, *names: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    topics, _ = px4_flight(duration_s=2.0)
    for name in names:
        write_ulog(folder / name, topics, {"sys_name": "PX4"})
    return folder


def rows_by_path(out: Path) -> pd.DataFrame:
    return pd.read_parquet(out / "logs.parquet").drop_duplicates("path").set_index("path")


def test_a_log_that_raises_or_kills_its_worker_is_its_row_and_the_rest_is_written(tmp_path):
    logs = write_logs(tmp_path / "logs", "dies.ulg", "good.ulg", "raises.ulg")
    seen = []
    evaluate_folder(logs, tmp_path / "out", FILTERS, workers=2, task=faulty, progress=lambda *a: seen.append(a[2].name))
    assert sorted(seen) == ["dies.ulg", "good.ulg", "raises.ulg"]
    rows = rows_by_path(tmp_path / "out")
    assert sorted(rows.index) == ["dies.ulg", "good.ulg", "raises.ulg"]
    assert "RuntimeError: a defect met in this log" in rows.loc["raises.ulg", "error"]
    assert "died" in rows.loc["dies.ulg", "error"] and "exit status 3" in rows.loc["dies.ulg", "error"]
    assert pd.isna(rows.loc["good.ulg", "error"]) and rows.loc["good.ulg", "samples"] > 0
    imu = pd.read_parquet(tmp_path / "out" / "tables" / "imu")
    assert set(imu["log_id"]) == {log_id(logs / "good.ulg", logs)}


def test_a_failure_after_the_log_is_read_is_its_row_and_leaves_none_of_its_files(tmp_path):
    """The report page cannot be written (``reports`` is a file): the log's tables, already written, go too."""
    logs = write_logs(tmp_path / "logs", "good.ulg")
    out = tmp_path / "out"
    out.mkdir()
    (out / "reports").write_text("in the way")
    rows = summarise(logs / "good.ulg", logs, out, FILTERS, page=True)
    assert len(rows) == 1 and rows[0]["error"].startswith("internal error (") and "reports" in rows[0]["error"]
    assert rows[0]["samples"] is None  # the row of a log that failed: its fields, none of its figures
    assert (out / "tables").is_dir() and not list((out / "tables").glob("*/log_id=*"))


def test_a_stopped_worker_is_ended_at_the_time_limit_and_its_log_named(tmp_path, capsys):
    """One worker stops (SIGSTOP) on its log: past the per-log limit it is ended, the log's row and its
    progress line say so, and the next log runs in a new worker."""
    logs = write_logs(tmp_path / "logs", "quick_a.ulg", "stops.ulg", "zz_quick.ulg")
    seen = []
    evaluate_folder(logs, tmp_path / "out", FILTERS, workers=1, task=faulty, limit_s=3.0,
                    progress=lambda *a: seen.append((a[2].name, a[3][0]["error"])))
    assert [name for name, _ in seen] == ["quick_a.ulg", "stops.ulg", "zz_quick.ulg"]  # one worker: in order
    rows = rows_by_path(tmp_path / "out")
    assert "stopped after 3 s, the per-log time limit" in rows.loc["stops.ulg", "error"]
    assert rows["error"].isna().sum() == 2
    import multiprocessing
    assert not multiprocessing.active_children()  # the stopped worker was ended, not left behind


def test_the_time_limit_from_the_command_line(tmp_path, capsys):
    logs = write_logs(tmp_path / "logs", "good.ulg")
    assert main(["evaluate", str(logs), "--out", str(tmp_path / "out"), "--time-limit", "0"]) == 2
    assert "--time-limit" in capsys.readouterr().err


def test_a_rerun_replaces_the_dataset_whole(tmp_path, capsys):
    """report DIR into the OUT of an earlier run after a log left DIR: refused without --overwrite (OUT
    untouched); with it the new dataset replaces OUT whole: nothing of the log that left remains."""
    logs = write_logs(tmp_path / "logs", "kept.ulg", "removed.ulg")
    out = tmp_path / "out"
    argv = ["report", str(logs), "--out", str(out), "--filters", "ahf", "--workers", "1"]
    assert main(argv) == 0
    gone = log_id(logs / "removed.ulg", logs)
    assert (out / "reports" / f"{gone}.html").exists() and (out / "tables" / "imu" / f"log_id={gone}").exists()
    (logs / "removed.ulg").unlink()
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--overwrite" in err and len(err.strip().splitlines()) == 1, err
    assert (out / "reports" / f"{gone}.html").exists()  # refused: the earlier dataset as it was
    assert main([*argv, "--overwrite"]) == 0
    assert list(rows_by_path(out).index) == ["kept.ulg"]
    assert not (out / "reports" / f"{gone}.html").exists() and gone not in (out / "index.html").read_text()
    assert set(pd.read_parquet(out / "tables" / "imu")["log_id"]) == {log_id(logs / "kept.ulg", logs)}
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no staging folder left


def test_overwrite_replaces_only_a_dataset(tmp_path, capsys):
    logs = write_logs(tmp_path / "logs", "kept.ulg")
    precious = tmp_path / "notes"
    precious.mkdir()
    (precious / "flight notes.txt").write_text("do not lose")
    assert main(["evaluate", str(logs), "--out", str(precious), "--overwrite"]) == 2
    assert "logs.parquet" in capsys.readouterr().err
    assert (precious / "flight notes.txt").read_text() == "do not lose"
    out = tmp_path / "out"  # a dataset's folder (its logs.parquet), the logs moved into it since
    out.mkdir()
    (out / "logs.parquet").write_bytes(b"")
    (logs / "kept.ulg").rename(out / "kept.ulg")
    assert main(["evaluate", str(out), "--out", str(out), "--overwrite"]) == 2
    assert "holds the logs" in capsys.readouterr().err and (out / "kept.ulg").is_file()


def test_workers_are_bounded_by_cores_and_memory(monkeypatch):
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    count, said = worker_count(30)
    assert count <= cores and count >= 1
    assert said is not None and "--workers 30" in said and f"{cores} cores" in said
    monkeypatch.setattr(logbook_folder, "free_memory_bytes", lambda: int(2.5 * logbook_folder.MEMORY_PER_WORKER_BYTES))
    count, said = worker_count(30)
    assert count == min(cores, 2) and "memory" in said
    assert worker_count(1) == (1, None)
    monkeypatch.setattr(logbook_folder, "free_memory_bytes", lambda: 0)
    assert worker_count(None)[0] == 1  # always one at least


def test_workers_capped_on_the_command_line(tmp_path, capsys):
    logs = write_logs(tmp_path / "logs", "good.ulg")
    assert main(["evaluate", str(logs), "--out", str(tmp_path / "out"), "--workers", "30", "--filters", "ahf"]) == 0
    assert "--workers 30:" in capsys.readouterr().out
