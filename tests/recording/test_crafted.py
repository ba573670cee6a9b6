"""Crafted recordings (valid checksums, hostile content, ``tests/crafted_files.py``): every command
reads each to a result or a one-line message, and what it could not use is said, never a traceback."""

import pytest

from groundstation.cli import main
from groundstation.session_makers.load import load_session
from tests.crafted_files import CRAFTED, write_all

# What the session's warning must name for each crafted header or event it could not use.
LEFT_OUT = {
    "settings_not_a_dict": "estimator_settings",
    "settings_values_text": "hf.beta",
    "settings_of_unknown_estimator": "zz9.beta",
    "settings_event_of_a_newer_version": "hf.warp_drive",
    "settings_event_without_settings": "hf (not a table of settings)",
    "filters_not_a_list": "not a list of names",
    "filters_unknown_names": "'no_such_filter'",
}
REFUSED = {"samples_without_time": "missing columns time_s", "samples_zero_rows": "missing columns"}


@pytest.fixture(scope="module")
def crafted(tmp_path_factory):
    return write_all(tmp_path_factory.mktemp("crafted"))


@pytest.mark.parametrize("name", sorted(CRAFTED))
def test_every_command_reads_a_crafted_recording_without_a_traceback(crafted, name, capsys, tmp_path):
    path = str(crafted[name])
    for argv in (["export", path, "--out", str(tmp_path / "out.csv")], ["evaluate", path], ["replay", path, "--speed", "64"]):
        status = main(argv)
        err = capsys.readouterr().err
        assert "Traceback" not in err
        if name in REFUSED:
            assert status == 2 and REFUSED[name] in err, (argv, err)
        else:
            assert status == 0, (argv, err)


@pytest.mark.parametrize("name", sorted(LEFT_OUT))
def test_what_a_crafted_header_or_event_could_not_set_is_said(crafted, name):
    warnings = [e["message"] for e in load_session(crafted[name]).events if e["kind"] == "warning"]
    assert any(LEFT_OUT[name] in message for message in warnings), warnings


def test_json_nested_beyond_reason_is_damage_not_a_crash(crafted):
    from groundstation.recording import open_recording

    recording = open_recording(crafted["deep_json_event"])
    assert any("is not a JSON object; skipped" in finding for finding in recording.damage)


def test_a_dataset_csv_gz_with_a_corrupt_body_is_one_line(tmp_path, capsys):
    from tests.crafted_files import damaged_csv_gz

    path = str(damaged_csv_gz(tmp_path))
    for argv in (["export", path, "--out", str(tmp_path / "o.csv")], ["evaluate", path],
                 ["import", path, "--out", str(tmp_path / "o.gsrec")]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "not a readable CSV file" in err and "Traceback" not in err, err
