"""Where numba keeps the compiled estimators: a per-user cache folder, not ``__pycache__`` beside the sources.

numba's default cache sits in ``__pycache__`` next to each module, so re-installing the package (what
a test command that installs it does) deletes it and the next start compiles every kernel again
(about 30 CPU s). In the user's cache folder it survives a re-install. numba checks
each cached kernel against its own source file (a hash of the file's bytes, numba 0.68) but not the
modules it calls into ("Cache invalidation fails to recognize changes in symbols defined in a
different file", numba's notes on caching): the folder is therefore named by a hash of every estimation
source, so a change to any of them (``base.py``'s guard, a helper) starts a fresh folder.

``NUMBA_CACHE_DIR`` set by the user wins. Set just before numba is imported (numba reads it at import;
``use_user_cache_for_numba``: hashing the sources costs as much as a command's ``--help`` may in all,
bench/bench_help.py) and also on ``numba.config`` in case something imported numba first.

The first start on a machine fills it in another process (``estimation.warm_up``), never making a session wait.
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

ENV_VAR = "NUMBA_CACHE_DIR"
SOURCES = Path(__file__).resolve().parent  # the estimation package: every module a kernel can call into


def user_cache_root() -> Path:
    """The platform's per-user cache folder for the app: ``$XDG_CACHE_HOME/groundstation`` (``~/.cache``),
    ``~/Library/Caches/groundstation`` on macOS, ``%LOCALAPPDATA%\\groundstation\\cache`` on Windows."""
    if sys.platform == "win32":
        return Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local") / "groundstation" / "cache"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "groundstation"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".cache"  # a relative XDG path is invalid
    return base / "groundstation"


def sources_hash() -> str:
    """A hash of every estimation module's bytes, in name order (16 hex digits)."""
    digest = hashlib.sha256()
    for path in sorted(SOURCES.glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def use_user_cache() -> str:
    """Point numba's cache at the user's cache folder (unless ``NUMBA_CACHE_DIR`` says otherwise); returns it."""
    folder = os.environ.get(ENV_VAR) or str(user_cache_root() / "numba" / sources_hash())
    os.environ[ENV_VAR] = folder
    numba = sys.modules.get("numba")
    if numba is not None:  # imported before us: its config has read the environment already
        numba.config.CACHE_DIR = folder
    return folder


class _BeforeNumba:
    """An import hook (``sys.meta_path``) that points numba's cache at the user's folder when numba is
    first imported, then steps aside: it finds no module itself."""

    def find_spec(self, name, path=None, target=None):
        if name == "numba":
            sys.meta_path.remove(self)
            use_user_cache()
        return None


def use_user_cache_for_numba() -> None:
    """``use_user_cache`` now if numba is imported already, else just before it is."""
    if "numba" in sys.modules:
        use_user_cache()
    elif not any(isinstance(finder, _BeforeNumba) for finder in sys.meta_path):
        sys.meta_path.insert(0, _BeforeNumba())

