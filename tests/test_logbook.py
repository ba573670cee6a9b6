"""A folder of logs at once (``evaluate DIR --out OUT``): a row per log and estimator equal to what the
same log gives alone, each log's tables partitioned by log and read back by pandas (pyarrow's dataset),
a damaged or foreign file reported and skipped, and the same dataset from a Dask cluster of two workers."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groundstation.errors import UserError
from groundstation.logbook.folder import evaluate_folder
from groundstation.logbook.summary import LOG_COLUMNS, log_id
from groundstation.session_makers.load import load_session

LOGS = Path(__file__).resolve().parents[1].parent / "shared" / "datasets" / "flightlogs"
CHOSEN = ("px4_fmuv5_quad_hop.ulg", "arduplane_omnibusf4_ground_pilot_0004.bin", "px4_sitl_quad_groundtruth.ulg")
FILTERS = ["ahf", "hf"]


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    if not LOGS.exists():
        pytest.skip(f"flight logs not found at {LOGS}")
    root = tmp_path_factory.mktemp("logs")
    (root / "px4").mkdir()
    shutil.copy(LOGS / CHOSEN[0], root / "px4" / CHOSEN[0])
    shutil.copy(LOGS / CHOSEN[1], root / CHOSEN[1])
    shutil.copy(LOGS / CHOSEN[2], root / CHOSEN[2])
    (root / "cut.bin").write_bytes((LOGS / CHOSEN[1]).read_bytes()[:200])  # a log cut in its header
    (root / "notes.txt").write_text("not a log")  # not a log: not listed at all
    (root / ".hidden.ulg").write_text("hidden")
    return root


@pytest.fixture(scope="module")
def local(folder, tmp_path_factory):
    out = tmp_path_factory.mktemp("out") / "dataset"
    seen = []
    rows = evaluate_folder(folder, out, FILTERS, workers=2, progress=lambda *a: seen.append(a))
    return out, rows, seen


def test_a_row_per_log_and_estimator_as_each_log_alone(folder, local):
    out, rows, seen = local
    logs = pd.read_parquet(out / "logs.parquet")
    assert list(logs.columns) == list(LOG_COLUMNS)
    assert sorted(logs["path"].unique()) == sorted(["px4/" + CHOSEN[0], CHOSEN[1], CHOSEN[2], "cut.bin"])
    assert [s[0] for s in seen] == [1, 2, 3, 4] and all(s[1] == 4 for s in seen)  # progress after each log
    hop = load_session(folder / "px4" / CHOSEN[0], FILTERS, exact=True)  # as the logbook loads it
    from groundstation.autopilot.agreement import onboard_agreement
    alone = onboard_agreement(hop)
    mine = logs[logs["path"] == "px4/" + CHOSEN[0]].set_index("estimator")
    assert set(mine.index) == set(alone)
    for name, figures in alone.items():
        assert mine.loc[name, "reference"] == "onboard"
        assert mine.loc[name, "pitch_rms_deg"] == figures["pitch_rms_deg"]
        assert mine.loc[name, "roll_max_deg"] == figures["roll_max_deg"]
    truth = load_session(folder / CHOSEN[2], FILTERS, exact=True).evaluate()
    scored = logs[logs["path"] == CHOSEN[2]].set_index("estimator")
    assert set(scored.index) == set(truth) and (scored["reference"] == "truth").all()
    for name, figures in truth.items():
        assert scored.loc[name, "incl_rmse_deg"] == figures["incl_rmse_deg"]
    assert mine["duration_s"].iloc[0] == pytest.approx(hop.time_s[-1] - hop.time_s[0])
    from groundstation.analysis.vibration import vibration_summary
    vibration = vibration_summary(hop)
    assert mine["vibration_accel_m_s2"].iloc[0] == max(vibration.levels["accel"].values())
    assert mine["vibration_source"].iloc[0] == vibration.source
    no_imu = logs[logs["path"] == CHOSEN[1]]
    assert len(no_imu) == 1 and no_imu["estimator"].isna().all() and no_imu["error"].isna().all()
    cut = logs[logs["path"] == "cut.bin"]
    assert len(cut) == 1 and cut["error"].iloc[0] and "cut.bin" in cut["error"].iloc[0]


def test_tables_partitioned_by_log(folder, local):
    out, _, _ = local
    imu = pd.read_parquet(out / "tables" / "imu")
    hop = load_session(folder / "px4" / CHOSEN[0], FILTERS, exact=True)  # as the logbook loads it
    identifier = log_id(folder / "px4" / CHOSEN[0], folder)
    mine = imu[imu["log_id"] == identifier]
    np.testing.assert_array_equal(mine["time_s"].to_numpy(), hop.tables["imu"]["time_s"])
    np.testing.assert_array_equal(mine["ahf_qw"].to_numpy(), hop.tables["imu"]["ahf_qw"])
    one = pd.read_parquet(out / "tables" / "onboard" / f"log_id={identifier}")  # one log without the others
    assert len(one) == len(hop.tables["onboard"]["time_s"])


def test_the_same_dataset_from_a_dask_cluster(folder, local, tmp_path):
    distributed = pytest.importorskip("distributed")
    out, rows, _ = local
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        dask_rows = evaluate_folder(folder, tmp_path / "dask", FILTERS, dask_scheduler=cluster.scheduler_address)
    pd.testing.assert_frame_equal(pd.read_parquet(out / "logs.parquet"), pd.read_parquet(tmp_path / "dask" / "logs.parquet"))
    for table in ("imu", "onboard"):
        pd.testing.assert_frame_equal(pd.read_parquet(out / "tables" / table), pd.read_parquet(tmp_path / "dask" / "tables" / table))
    assert len(dask_rows) == len(rows)


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "groundstation", "evaluate", *map(str, args)], capture_output=True,
                          text=True, timeout=300)


def test_the_command_line(folder, tmp_path):
    small = tmp_path / "small"
    small.mkdir()
    shutil.copy(folder / "px4" / CHOSEN[0], small)
    shutil.copy(folder / "cut.bin", small)
    done = run_cli(small, "--out", tmp_path / "out", "--filters", "ahf", "--workers", "2")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert sum(line.startswith("[") for line in lines) == 2 and "cut.bin: error:" in done.stdout
    assert "1 estimators against the onboard" in done.stdout
    assert lines[-1].startswith(f"wrote {tmp_path / 'out'}") and "2 logs, 1 failed" in lines[-1]


def test_wrong_inputs_are_said_in_one_line(folder, tmp_path, capsys):
    from groundstation.cli import main

    (tmp_path / "empty").mkdir()
    for args, said in (((folder,), "--out OUT"), ((folder, "--out", tmp_path / "o", "--workers", "0"), "at least 1"),
                       ((tmp_path / "empty", "--out", tmp_path / "o"), "no recordings or flight logs"),
                       ((folder / CHOSEN[1], "--out", tmp_path / "o"), "for a folder of logs"),
                       ((folder, "--out", tmp_path / "o", "--set", "ahf.lambda_max=1"), "applies to one file"),
                       ((folder, "--out", tmp_path / "o", "--dask", "tcp://127.0.0.1:9"), "cannot reach the scheduler")):
        assert main(["evaluate", *map(str, args)]) == 2
        err = capsys.readouterr().err
        assert said in err and len(err.strip().splitlines()) == 1, (args, err)


def test_a_killed_worker_costs_no_log(folder, local, tmp_path):
    """The memory killer takes a worker mid-batch: the pool is made anew and every log still has its rows."""
    import multiprocessing
    import os
    import signal

    killed = []

    def progress(done, total, path, rows, seconds):
        if not killed:
            for child in multiprocessing.active_children():
                os.kill(child.pid, signal.SIGKILL)
                killed.append(child.pid)

    rows = evaluate_folder(folder, tmp_path / "again", FILTERS, workers=2, progress=progress)
    assert killed
    out, expected, _ = local
    pd.testing.assert_frame_equal(pd.read_parquet(out / "logs.parquet"), pd.read_parquet(tmp_path / "again" / "logs.parquet"))
    assert len(rows) == len(expected)


def test_report_dir_writes_a_page_per_log_and_an_index_worst_first(folder, tmp_path):
    from groundstation.cli import main

    small = tmp_path / "small"
    small.mkdir()
    shutil.copy(folder / "px4" / CHOSEN[0], small)
    shutil.copy(folder / CHOSEN[2], small)
    shutil.copy(folder / "cut.bin", small)
    out = tmp_path / "reports"
    assert main(["report", str(small), "--out", str(out), "--filters", "ahf", "--workers", "2"]) == 0
    logs = pd.read_parquet(out / "logs.parquet").drop_duplicates("log_id").set_index("path")
    index = (out / "index.html").read_text()
    order = [index.index(name) for name in ("cut.bin", CHOSEN[0], CHOSEN[2])]
    assert order == sorted(order)  # unreadable first, then the hop's high finding, then the SITL flight's medium one
    assert logs.loc[CHOSEN[0], "worst_severity"] == "high" and logs.loc[CHOSEN[2], "worst_severity"] == "medium"
    for name in (CHOSEN[0], CHOSEN[2]):
        page = out / "reports" / f"{logs.loc[name, 'log_id']}.html"
        assert f'href="reports/{page.name}"' in index and "Flight report" in page.read_text()
    assert not (out / "reports" / f"{logs.loc['cut.bin', 'log_id']}.html").exists()
