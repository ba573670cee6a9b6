"""Default folder per platform (and its override) and file names from the start time."""

from __future__ import annotations

from datetime import datetime, timedelta, timezone
from pathlib import Path

import pytest

from groundstation.recording import default_recordings_dir, new_recording_path


@pytest.fixture
def home(tmp_path, monkeypatch):
    for name in ("GROUNDSTATION_RECORDINGS", "XDG_DATA_HOME", "LOCALAPPDATA"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(Path, "home", lambda: tmp_path / "home")
    return tmp_path / "home"


def test_environment_variable_overrides_the_default(home, monkeypatch, tmp_path):
    monkeypatch.setenv("GROUNDSTATION_RECORDINGS", str(tmp_path / "flights"))
    assert default_recordings_dir() == tmp_path / "flights"


@pytest.mark.parametrize("platform, env, expected", [
    ("linux", {}, ".local/share/groundstation/recordings"),
    ("linux", {"XDG_DATA_HOME": "/data"}, "/data/groundstation/recordings"),
    ("linux", {"XDG_DATA_HOME": "relative"}, ".local/share/groundstation/recordings"),
    ("darwin", {}, "Library/Application Support/groundstation/recordings"),
    ("win32", {"LOCALAPPDATA": "/appdata"}, "/appdata/groundstation/recordings"),
    ("win32", {}, "AppData/Local/groundstation/recordings"),
])
def test_platform_defaults(home, monkeypatch, platform, env, expected):
    monkeypatch.setattr("sys.platform", platform)
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    assert default_recordings_dir() == home / expected


def test_names_come_from_the_start_time_and_never_collide(tmp_path):
    start = datetime(2026, 11, 21, 18, 32, 53, 700_000)
    folder = tmp_path / "new" / "folder"
    first = new_recording_path(folder, start)
    assert first == folder / "2026-11-21_18-32-53.gsrec"
    first.touch()
    second = new_recording_path(folder, start)
    assert second.name == "2026-11-21_18-32-53_2.gsrec"
    second.touch()
    assert new_recording_path(folder, start).name == "2026-11-21_18-32-53_3.gsrec"


def test_an_aware_start_time_names_the_file_in_local_time(tmp_path):
    start = datetime(2026, 11, 21, 18, 32, 53, tzinfo=timezone(timedelta(hours=5)))
    expected = start.astimezone().strftime("%Y-%m-%d_%H-%M-%S") + ".gsrec"
    assert new_recording_path(tmp_path, start).name == expected
