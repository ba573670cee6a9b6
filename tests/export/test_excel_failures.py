"""Bad destinations, a full disk, a locked file, a cancel, a failure: a clear message, and nothing left
behind, neither at the destination nor among openpyxl's temporary files."""

import errno
import os
import subprocess
import sys
import tempfile
import textwrap
import threading
from pathlib import Path

import numpy as np
import pytest
from openpyxl import load_workbook

from groundstation.errors import UserError
from groundstation.export import files
from groundstation.export.excel import ExportCancelled, write_workbook
from tests.cli_in_process import run_in_process

posix_only = pytest.mark.skipif(os.name != "posix", reason="POSIX permissions and resource limits")


@pytest.fixture
def no_leftovers(tmp_path_factory, monkeypatch):
    """openpyxl's temporary sheet files go to a folder of this test's own (other processes share
    the system's), which must be empty afterwards."""
    folder = tmp_path_factory.mktemp("openpyxl_temporaries")
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    yield
    assert list(folder.iterdir()) == []


def test_an_existing_file_is_kept_unless_overwrite(sim_session, tmp_path):
    path = tmp_path / "out.xlsx"
    path.write_bytes(b"the user's own file")
    with pytest.raises(UserError, match="exists; choose another name or pass --overwrite"):
        write_workbook(sim_session, path)
    assert path.read_bytes() == b"the user's own file"
    write_workbook(sim_session, path, overwrite=True)
    assert load_workbook(path).sheetnames[0] == "Session"


def test_a_missing_folder_is_named(sim_session, tmp_path):
    with pytest.raises(UserError, match="does not exist"):
        write_workbook(sim_session, tmp_path / "no such folder" / "out.xlsx")
    assert list(tmp_path.iterdir()) == []


@pytest.fixture
def unwritable_folder(tmp_path):
    """A folder nobody may write in: its mode for users, an immutable attribute for root (who ignores modes)."""
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o555)
    immutable = os.geteuid() == 0 and subprocess.run(["chattr", "+i", folder], capture_output=True).returncode == 0
    try:
        (folder / "probe").touch()
    except PermissionError:
        yield folder
    else:
        pytest.skip("cannot make a folder unwritable here (root without chattr)")
    finally:
        if immutable:
            subprocess.run(["chattr", "-i", folder], check=True)
        folder.chmod(0o755)


@posix_only
def test_an_unwritable_folder_gets_a_message(sim_session, unwritable_folder, no_leftovers):
    with pytest.raises(UserError, match="cannot write in .*(Permission denied|Operation not permitted)"):
        write_workbook(sim_session, unwritable_folder / "out.xlsx")
    assert list(unwritable_folder.iterdir()) == []


@pytest.fixture
def tiny_filesystem(tmp_path):
    """A 64 KiB tmpfs (needs root); the workbook of the test session is about 600 KB."""
    mount_point = tmp_path / "tiny"
    mount_point.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", mount_point], capture_output=True).returncode:
        pytest.skip("mounting a small tmpfs needs root; test_a_file_size_limit covers the full disk instead")
    yield mount_point
    subprocess.run(["umount", mount_point], check=True)


@posix_only
def test_a_full_disk_gets_a_message_and_leaves_nothing(sim_session, tiny_filesystem, no_leftovers):
    with pytest.raises(UserError, match="the disk is full"):
        write_workbook(sim_session, tiny_filesystem / "out.xlsx")
    assert list(tiny_filesystem.iterdir()) == []


@posix_only
def test_a_file_size_limit_gets_a_message_and_leaves_nothing(sim_recording, tmp_path):
    """Without root: RLIMIT_FSIZE in a child process stands in for a full disk (the write fails with
    EFBIG, "File too large", where a full disk gives ENOSPC; the path through the code is the same)."""
    out = tmp_path / "out" / "out.xlsx"
    out.parent.mkdir()
    temporaries = tmp_path / "temporaries"  # openpyxl's sheet files: the limit hits them first
    temporaries.mkdir()
    script = textwrap.dedent(f"""
        import os, resource, signal, tempfile
        from groundstation.errors import UserError
        from groundstation.export.excel import write_workbook
        from groundstation.session_makers.load import load_session
        data = load_session({str(sim_recording)!r}, exact=True)
        tempfile.tempdir = {str(temporaries)!r}
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a failing write, not a killed process
        resource.setrlimit(resource.RLIMIT_FSIZE, (64 * 1024, 64 * 1024))
        try:
            write_workbook(data, {str(out)!r})
        except UserError as error:
            print("UserError:", error)
        print("leftovers:", os.listdir(tempfile.tempdir))  # before exiting: openpyxl removes its files at exit
    """)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert f"UserError: cannot write {out}: File too large" in result.stdout
    assert "leftovers: []" in result.stdout
    assert list(out.parent.iterdir()) == []


def test_a_file_locked_by_another_program(sim_session, tmp_path, monkeypatch, no_leftovers):
    """Windows refuses to replace a file Excel has open; the rename is where that shows."""
    path = tmp_path / "out.xlsx"
    path.write_bytes(b"open in Excel")

    def locked(source, destination):
        raise PermissionError(errno.EACCES, "Permission denied", str(destination))

    monkeypatch.setattr(files.os, "replace", locked)
    with pytest.raises(UserError, match="is the file open in another program"):
        write_workbook(sim_session, path, overwrite=True)
    assert path.read_bytes() == b"open in Excel"
    assert [p.name for p in tmp_path.iterdir()] == ["out.xlsx"]


@pytest.mark.parametrize("how", ["event", "callable"])
def test_a_cancel_leaves_nothing(sim_session, tmp_path, how, no_leftovers):
    path = tmp_path / "out.xlsx"
    event = threading.Event()
    reports = []

    def progress(done, total):
        reports.append((done, total))
        event.set()  # the user presses Cancel after the first report

    cancel = event if how == "event" else event.is_set
    with pytest.raises(ExportCancelled):
        write_workbook(sim_session, path, progress=progress, cancel=cancel, max_rows=1000)
    assert len(reports) == 1 and 0 < reports[0][0] < reports[0][1]
    assert list(tmp_path.iterdir()) == []


def test_a_failure_midway_leaves_nothing(sim_session, tmp_path, no_leftovers):
    def failing(done, total):
        if done > total / 2:
            raise RuntimeError("the worker died")

    with pytest.raises(RuntimeError, match="the worker died"):
        write_workbook(sim_session, tmp_path / "out.xlsx", progress=failing)
    assert list(tmp_path.iterdir()) == []


def test_progress_counts_every_row_up_to_the_total(sim_session, tmp_path):
    reports = []
    write_workbook(sim_session, tmp_path / "out.xlsx", progress=lambda done, total: reports.append((done, total)))
    done = [d for d, _ in reports]
    assert done == sorted(done) and reports[-1][0] == reports[-1][1]
    link = max(len(sim_session.link.per_second["t_s"]), len(sim_session.tables["status"]["time_s"]))  # side by side
    assert reports[-1][1] == len(sim_session) * 3 + link  # Attitude, Sensors, chart points, Link


@pytest.fixture
def gs(capsys):
    return lambda *args: run_in_process(capsys, *args)


def test_the_export_command_writes_a_workbook(sim_recording, tmp_path, gs):
    out = tmp_path / "flight.xlsx"
    result = gs("export", sim_recording, "--out", out, "--from", "2", "--to", "12")
    assert result.returncode == 0, result.stderr
    assert f"wrote {out}: sheets Session, Attitude, Sensors, Link, Chart" in result.stdout
    times = [r[0] for r in load_workbook(out)["Attitude"].iter_rows(min_row=2, values_only=True)]
    assert 2 <= min(times) < 2.02 and 11.98 < max(times) <= 12
    again = gs("export", sim_recording, "--out", out)
    assert again.returncode == 2 and "exists" in again.stderr and "Traceback" not in again.stderr
    assert Path(out).stat().st_size > 0


def test_more_columns_than_excel_holds_is_said_before_anything_is_written(sim_session, tmp_path):
    """A session with 70 message tables of 250 fields (a MAVLink link full of senders, before tables were
    bounded): its Sensors sheet would need 17,600 columns; Excel holds 16,384 (openpyxl raised
    ``Invalid column index 18279`` mid-write)."""
    import dataclasses

    from groundstation.session_parts.catalogue import Catalogue, message_table

    fields = [f"payload_{i}" for i in range(250)]
    infos = [message_table(f"wide_{k}", f"wide {k}", fields, {}) for k in range(70)]
    rows = {"time_s": sim_session.time_s[:3], **{f: np.zeros(3) for f in fields}}
    wide = dataclasses.replace(sim_session, catalogue=Catalogue({**sim_session.catalogue.tables, **{i.name: i for i in infos}}),
                               tables={**sim_session.tables, **{i.name: rows for i in infos}})
    with pytest.raises(UserError, match=r"Sensors.*17,\d{3} columns.*16,384.*CSV"):
        write_workbook(wide, tmp_path / "wide.xlsx")
    assert list(tmp_path.iterdir()) == []
