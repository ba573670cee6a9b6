"""Text from a log or a file name, made safe to write: ``clean``, the one rule every writer calls.

A log's text is anybody's: PX4 colours its messages with ANSI escape sequences
(``[commander] \\x1b[32mReady for takeoff!\\x1b[0m``), a crafted log or file name can carry NUL, BEL,
a sequence that sets a terminal's title or clears its screen, or a newline that forges a line of output.
XML (the workbook) refuses C0 controls, and a lone surrogate (an undecodable byte of a file name,
``os.fsdecode``) cannot be encoded as UTF-8 at all.

- ``clean(text)``: for what a person reads in a file (workbook, CSV, MCAP, report): escape sequences
  removed whole, every other control character removed; tab and newline kept.
- ``clean(text, visible=True)``: for one line of a terminal, and for names: every control character,
  tab and newline too, shown as its escape (``\\x1b``, ``\\n``), so nothing is hidden and nothing acts.
"""

from __future__ import annotations

import re

# ECMA-48 escape sequences: CSI (``ESC [`` or the 8-bit 0x9B, parameters, one final byte), OSC (``ESC ]``
# up to BEL or ``ESC \\``: window titles, hyperlinks) and the two-byte ones (``ESC c``: reset the terminal).
_SEQUENCE = re.compile(r"(?:\x1b\[|\x9b)[0-?]*[ -/]*[@-~]|\x1b\][^\x07\x1b]*(?:\x07|\x1b\\)?|\x1b[ -~]?")
# C0 but tab and newline, DEL, C1, lone surrogates, and the two non-characters XML refuses
_CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\ud800-\udfff\ufffe\uffff]")
_UNSEEN = re.compile("[\x00-\x1f\x7f-\x9f\ud800-\udfff\ufffe\uffff]")  # the same with tab and newline: one line
_SHOWN = {"\t": "\\t", "\n": "\\n", "\r": "\\r"}


def clean(text: str, visible: bool = False) -> str:
    """``text`` without control characters (escape sequences removed whole; tab and newline kept), or
    with ``visible`` every one of them, tab and newline too, shown as its escape (``\\x1b[32m``)."""
    if visible:
        return _UNSEEN.sub(_escape, text) if _UNSEEN.search(text) else text
    if not _CONTROL.search(text):
        return text  # the usual text: no copy
    return _CONTROL.sub("", _SEQUENCE.sub("", text))


def _escape(match: re.Match) -> str:
    char = match.group()
    code = ord(char)
    return _SHOWN.get(char) or (f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}")
