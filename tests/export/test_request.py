"""The one export entry point: every choice checked before any decoding, the same for the CLI and the
app, and a failed write (a full disk) leaves nothing at the destination."""

import sys

import pandas as pd
import pytest

from groundstation.cli import main
from groundstation.errors import UserError
from groundstation.export.request import export_request, run_export
from groundstation.session_makers.load import load_session
from groundstation.ui.export_job import ExportJob
from tests.session.full_disk import tiny_tmpfs


@pytest.fixture
def no_decoding(monkeypatch):
    """Decoding is what takes seconds: these mistakes must be found without it."""
    import groundstation.session_makers.load as data

    def decode(*args, **kwargs):
        raise AssertionError("decoded before the mistake was found")

    monkeypatch.setattr(data, "load_session", decode)


@pytest.mark.parametrize("out, expected", [
    ("missing/out.csv", "the folder {tmp}/missing does not exist"),
    ("out.txt", "the name must end in .xlsx, .csv, .parquet"),
    ("exists.csv", "exists; choose another name or pass --overwrite"),
    ("a_folder.csv", "it is a folder"),
])
def test_destination_mistakes_are_found_before_decoding(sim_recording, tmp_path, no_decoding, capsys, out, expected):
    (tmp_path / "exists.csv").write_text("keep me")
    (tmp_path / "a_folder.csv").mkdir()
    assert main(["export", str(sim_recording), "--out", str(tmp_path / out)]) == 2
    assert expected.format(tmp=tmp_path) in capsys.readouterr().err
    assert (tmp_path / "exists.csv").read_text() == "keep me"


def test_a_folder_that_refuses_new_files_is_found_before_decoding(sim_recording, tmp_path, no_decoding):
    """Root ignores permission bits, so the folder is tried, not judged from its mode: /proc takes no files."""
    if not sys.platform.startswith("linux"):
        pytest.skip("/proc is Linux's")
    with pytest.raises(UserError, match="cannot write in /proc"):
        export_request(sim_recording, "/proc/out.csv")


@pytest.mark.parametrize("options, expected", [
    (["--rate", "nan"], "--rate must be a finite number, not nan"),
    (["--rate", "inf"], "--rate must be a finite number, not inf"),
    (["--rate", "0"], "--rate must be positive"),
    (["--from", "nan"], "--from must be a finite number"),
    (["--from", "10", "--to", "5"], "--from (10.0 s) is after --to (5.0 s)"),
])
def test_impossible_ranges_and_rates_are_user_errors(sim_recording, tmp_path, no_decoding, capsys, options, expected):
    assert main(["export", str(sim_recording), "--out", str(tmp_path / "out.csv"), *options]) == 2
    assert expected in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_exporting_a_file_onto_itself_is_refused(tmp_path, no_decoding):
    source = tmp_path / "trial.csv"
    source.write_text("time_s\n0\n")
    with pytest.raises(UserError, match="is the file being exported"):
        export_request(source, tmp_path / "." / "trial.csv", overwrite=True)
    assert source.read_text() == "time_s\n0\n"


def test_the_cli_and_the_app_write_the_same_file(sim_recording, tmp_path):
    assert main(["export", str(sim_recording), "--out", str(tmp_path / "cli.csv"), "--rate", "10"]) == 0
    job = ExportJob(load_session, sim_recording, tmp_path / "app.csv", rate_hz=10).start()
    job.wait(60)
    assert job.error is None and job.fraction == 1.0
    assert (tmp_path / "cli.csv").read_bytes() == (tmp_path / "app.csv").read_bytes()
    time_s = pd.read_csv(tmp_path / "cli.csv").time_s
    # every 10th of the 100 Hz samples; the link of this recording loses 1 % of its frames
    assert len(time_s) == pytest.approx((time_s.iloc[-1] - time_s.iloc[0]) * 10 * 0.99, abs=3)


@pytest.mark.parametrize("suffix", [".csv", ".xlsx"])
def test_a_full_disk_leaves_nothing_and_a_retry_is_not_blocked(sim_recording, tmp_path, capsys, suffix):
    with tiny_tmpfs(tmp_path / "full", size="256k", room_bytes=8_000) as folder:
        out = folder / f"out{suffix}"
        assert main(["export", str(sim_recording), "--out", str(out)]) == 2
        assert f"cannot write {out}: the disk is full (nothing was left behind)" in capsys.readouterr().err
        assert sorted(p.name for p in folder.iterdir()) == ["filler"]
        (folder / "filler").unlink()  # room again: the same command now works
        assert main(["export", str(sim_recording), "--out", str(out), "--rate", "5"]) == 0


def test_run_export_reports_its_stages(sim_recording, tmp_path):
    stages = []
    result = run_export(export_request(sim_recording, tmp_path / "out.xlsx", rate_hz=5), load_session,
                        lambda stage, done, total: stages.append(stage))
    assert result.message.startswith(f"wrote {tmp_path / 'out.xlsx'}: sheets Session, Attitude")
    assert stages[0] == "decoding" and stages[-1] == "writing" and set(stages) == {"decoding", "writing"}
