"""Writing an export safely: to a temporary file beside the destination, renamed only when complete.

A failure or a cancel leaves nothing at the destination, and an existing file is replaced only
when the user asked for it.
"""

from __future__ import annotations

import contextlib
import errno
import os
import tempfile
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
    try:
        handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
        os.close(handle)
    except OSError as error:
        raise UserError(f"cannot write in {path.parent}: {error.strerror}") from None
    temporary = Path(temporary)
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
