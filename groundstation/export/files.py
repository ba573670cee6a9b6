"""Writing an export safely: to a temporary file beside the destination, renamed only when complete.

A failure or a cancel leaves nothing at the destination, and an existing file is replaced only
when the user asked for it.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
from pathlib import Path

from groundstation.errors import UserError


class ExportCancelled(Exception):
    """The caller cancelled the export; nothing was written."""


@contextlib.contextmanager
def atomic_output(path, overwrite: bool = False, reserve: bool = True):
    """Yields a temporary path in the destination folder; renames it to ``path`` on success.

    The temporary name ends like ``path`` (``.gs-1a2b3c4d.flight.csv.gz``), so writers that choose
    the compression by the name still do. ``reserve``: create it now (for writers that overwrite);
    False for writers that create it exclusively themselves (``RecordingWriter``).
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise UserError(f"{path} exists; choose another name or pass --overwrite")
    if not path.parent.is_dir():
        raise UserError(f"cannot write {path}: the folder {path.parent} does not exist")
    temporary = path.with_name(f".gs-{secrets.token_hex(4)}.{path.name}")
    if reserve:
        try:
            # os.open with 0o666, not mkstemp (0o600): the export gets the user's usual permissions (umask).
            os.close(os.open(temporary, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
        except OSError as error:
            raise UserError(f"cannot write in {path.parent}: {error.strerror}") from None
    try:
        yield temporary
        os.replace(temporary, path)
    except OSError as error:
        raise UserError(f"cannot write {path}: {describe(error)}") from None
    finally:
        temporary.unlink(missing_ok=True)


@contextlib.contextmanager
def atomic_recording(path, metadata: dict):
    """A whole recording written at once (import, simulate): a ``RecordingWriter`` on a temporary file,
    renamed to ``path`` when complete, so a failure (a full disk) leaves nothing to block a retry."""
    from groundstation.recording import RecordingError, RecordingWriter

    with atomic_output(path, reserve=False) as temporary:
        try:
            with RecordingWriter(temporary, metadata) as writer:
                yield writer
        except RecordingError as error:
            if isinstance(error.__cause__, OSError):
                raise error.__cause__ from None  # said by atomic_output, with the destination's name
            raise


def describe(error: OSError) -> str:
    if error.errno == errno.ENOSPC:
        return "the disk is full (nothing was left behind)"
    if error.errno in (errno.EACCES, errno.EPERM):
        return "permission denied (is the file open in another program?)"
    return error.strerror or str(error)
