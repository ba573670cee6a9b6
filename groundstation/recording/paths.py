"""Where recordings go by default, and their names (the start time)."""

from __future__ import annotations

import os
import sys
from datetime import datetime
from pathlib import Path

from groundstation.recording.format import EXTENSION

ENV_VAR = "GROUNDSTATION_RECORDINGS"


def default_recordings_dir() -> Path:
    """The folder live sessions record to (not created here).

    ``$GROUNDSTATION_RECORDINGS`` if set; otherwise the platform's per-user data folder:
    Linux and other Unix ``$XDG_DATA_HOME/groundstation/recordings`` (``~/.local/share/...``),
    macOS ``~/Library/Application Support/groundstation/recordings``, Windows
    ``%LOCALAPPDATA%\\groundstation\\recordings``.
    """
    override = os.environ.get(ENV_VAR)
    if override:
        return Path(override).expanduser()
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Application Support"
    else:
        xdg = os.environ.get("XDG_DATA_HOME")
        # The XDG spec says a relative path is invalid and must be ignored.
        base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".local" / "share"
    return base / "groundstation" / "recordings"


def new_recording_path(folder, start: datetime) -> Path:
    """``folder/2026-11-21_18-32-53.gsrec`` for ``start`` (an aware time is shown in local time);
    ``_2``, ``_3``, ... appended if that name is taken. Creates ``folder`` if needed.

    The writer still refuses to overwrite, so two processes racing for one name cannot clobber.
    """
    folder = Path(folder).expanduser()
    folder.mkdir(parents=True, exist_ok=True)
    if start.tzinfo is not None:
        start = start.astimezone()
    stem = start.strftime("%Y-%m-%d_%H-%M-%S")
    path = folder / f"{stem}{EXTENSION}"
    suffix = 2
    while path.exists():
        path = folder / f"{stem}_{suffix}{EXTENSION}"
        suffix += 1
    return path
