"""Names that come from data (a log's topics and message types, a file's columns) where the project
needs them apart and safe: two rules, each in one place.

- ``kept_apart``: names made distinct. Reading folds names (``caseTopic`` and ``casetopic`` are both
  table ``casetopic``; table ``foo`` column ``bar_baz`` and table ``foo_bar`` column ``baz`` are both
  export column ``foo_bar_baz``); the first keeps the name, each later one gets a suffix (``__2``) no
  other name has, and a warning says so. Nothing is merged, no row is lost.
- ``path_name``: a name as a folder or file name, and ``under``: the path it makes, checked to lie in
  its folder. A name that is already plain (lower-case letters, digits, ``_``; short) is its own path
  name, so ``imu`` stays ``tables/imu``; any other (``../../tmp/x``, ``/tmp``, 300 characters, upper
  case that a case-blind file system would fold) is a slug of it and a hash of the whole name, bounded
  to ``PATH_NAME_CHARS``: the same name gives the same folder in every log, two names never one folder.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Sequence
from pathlib import Path

PATH_NAME_CHARS = 100  # ASCII: as many bytes; every file system takes 255
_HASH_CHARS = 12  # hex digits of SHA-1 (48 bits): two of a few thousand names share it with odds below 1e-7
_PLAIN = re.compile(r"[a-z0-9_]+")
_NOT_PLAIN = re.compile(r"[^a-z0-9_]+")
_DEVICES = re.compile(r"(con|prn|aux|nul|com[0-9]|lpt[0-9])")  # names Windows reserves in every folder


def kept_apart(names: Sequence[str], originals: Sequence[str], what: str) -> tuple[list[str], list[str]]:
    """``names`` made distinct: the first of a name keeps it, each later one gets ``__<n>`` (the
    smallest n from 2 that makes a name no other has); and for each renamed, a warning naming
    ``what`` it is ("ULog topic") by its ``originals`` (what the data calls it)."""
    taken, out, warnings, first = set(names), [], [], {}
    for name, original in zip(names, originals):
        if name not in first:
            first[name] = original
            out.append(name)
            continue
        n = 2
        while f"{name}__{n}" in taken:
            n += 1
        renamed = f"{name}__{n}"
        taken.add(renamed)
        out.append(renamed)
        warnings.append(f"{what} {original!r} would share the name {name!r} with {first[name]!r}: kept apart as {renamed!r}")
    return out, warnings


def path_name(name: str) -> str:
    """``name`` as one folder or file name: itself when plain (lower-case letters, digits, ``_``, at most
    ``PATH_NAME_CHARS``, no name Windows reserves), else ``<slug>-<hash>``: its plain characters and a
    hash of the whole name (a ``-`` no plain name has), at most ``PATH_NAME_CHARS``."""
    if len(name) <= PATH_NAME_CHARS and _PLAIN.fullmatch(name) and not _DEVICES.fullmatch(name):
        return name
    digest = hashlib.sha1(name.encode("utf-8", "surrogatepass")).hexdigest()[:_HASH_CHARS]
    slug = _NOT_PLAIN.sub("_", name.lower()).strip("_")[: PATH_NAME_CHARS - _HASH_CHARS - 1]
    return f"{slug or 'name'}-{digest}"


def under(folder: Path, *parts: str) -> Path:
    """``folder/parts...``, checked to resolve inside ``folder`` (ValueError otherwise): the guard behind
    ``path_name`` for every path a run writes from names."""
    path = Path(folder, *parts)
    root = Path(folder).resolve()
    if root not in path.resolve().parents:
        raise ValueError(f"{path}: outside {folder}")
    return path
