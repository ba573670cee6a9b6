"""What a file that is not a recording looks like, so the error message can say so."""

from __future__ import annotations

SIGNATURES = (
    (b"\x89PNG\r\n\x1a\n", "a PNG image"),
    (b"PK\x03\x04", "a ZIP archive (an .xlsx workbook is one)"),
    (b"\x1f\x8b", "a gzip file (for a dataset .csv.gz use 'groundstation import')"),
    (b"%PDF", "a PDF document"),
    (b"PAR1", "a Parquet file"),
    (b"SQLite format 3\x00", "an SQLite database"),
)


def describe(head: bytes) -> str:
    """A short description of a file from its first bytes, e.g. 'a PNG image'."""
    for signature, description in SIGNATURES:
        if head.startswith(signature):
            return description
    # The last few bytes may cut a multi-byte character in half: not a reason to call it binary.
    text = head.decode("utf-8", errors="replace").rstrip("\ufffd")
    if not text or any(c == "\ufffd" or (c < " " and c not in "\t\r\n") for c in text):
        return "binary data of an unknown format"
    if "," in text.splitlines()[0]:
        return "text, CSV-like (for a dataset CSV use 'groundstation import FILE.csv --out FILE.gsrec')"
    return "text"
