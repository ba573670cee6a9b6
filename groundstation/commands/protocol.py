"""``groundstation protocol``: the frame types of the wire protocol, or the frames in a raw byte capture."""

from __future__ import annotations

import argparse
from pathlib import Path

from groundstation.errors import UserError

CHUNK_BYTES = 1 << 16


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--decode", metavar="FILE", type=Path, help="decode a raw byte capture (e.g. from a serial terminal)")
    parser.add_argument("--limit", type=int, default=50, help="frames to print with --decode (default 50; 0: none, just the counts)")


def run(args: argparse.Namespace) -> int:
    if args.decode is None:
        print_spec()
    else:
        decode_file(args.decode, args.limit)
    return 0


def print_spec() -> None:
    from firmware_protocol import SPEC  # here: parsing the spec is most of what the help would cost

    print(f"protocol version {SPEC.protocol_version}, schema fingerprint 0x{SPEC.fingerprint:08X}, sync 0x{SPEC.sync:02X}")
    for frame_type in SPEC.frames:
        arrow = "aircraft->ground" if frame_type.direction == "down" else "ground->aircraft"
        size = frame_type.payload_size + SPEC.header_bytes + SPEC.crc_bytes
        print(f"  0x{frame_type.id:02X} {frame_type.name:<9} {size:2d} bytes  {arrow}  {', '.join(frame_type.field_names)}")
    print("Full layout: docs/protocol.md")


def decode_file(path: Path, limit: int) -> None:
    from firmware_protocol import StreamDecoder

    decoder = StreamDecoder()
    shown = 0
    for chunk in link_bytes(path):
        for frame in decoder.feed(chunk):
            if shown < limit:
                print(f"{frame.seq:3d} {frame.name:<9} " + " ".join(f"{k}={v:g}" for k, v in frame.scaled().items()))
                shown += 1
    counts = ", ".join(f"{k} {v}" for k, v in decoder.stats.as_dict().items())
    print(f"{path}: {counts}; {decoder.pending_bytes} bytes of an incomplete frame at the end")
    if decoder.schema_warning is not None:
        print(f"warning: {decoder.schema_warning}")


def link_bytes(path: Path):
    """The link bytes in ``path``: a raw capture as it is, a recording's chunks (not its record framing)."""
    from groundstation.recording import open_recording
    from groundstation.recording.format import MAGIC

    if not path.is_file():
        # A device (/dev/zero, a serial port) never ends: capture it to a file first.
        raise UserError(f"{path} is not a file: --decode reads a saved capture or recording")
    try:
        handle = path.open("rb")
    except OSError as error:
        raise UserError(f"cannot read {path}: {error.strerror}") from None
    with handle:
        if handle.read(len(MAGIC)) == MAGIC:
            recording = open_recording(path)
            print(f"{path} is a groundstation recording: decoding the link bytes of its {recording.chunk_count} chunks")
            for finding in recording.damage:
                print(f"warning: {finding}")
            yield from (data for _, data in recording.chunks())
            return
        handle.seek(0)
        while chunk := handle.read(CHUNK_BYTES):
            yield chunk
