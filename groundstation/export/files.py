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


@contextlib.contextmanager
def atomic_output(path, overwrite: bool = False):
    """Yields a temporary path in the destination folder; renames it to ``path`` on success."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise UserError(f"{path} exists; choose another name or pass --overwrite")
    if not path.parent.is_dir():
        raise UserError(f"cannot write {path}: the folder {path.parent} does not exist")
    temporary = path.with_name(f".{path.name}.{secrets.token_hex(4)}.part")
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


def describe(error: OSError) -> str:
    if error.errno == errno.ENOSPC:
        return "the disk is full (nothing was left behind)"
    if error.errno in (errno.EACCES, errno.EPERM):
        return "permission denied (is the file open in another program?)"
    return error.strerror or str(error)
