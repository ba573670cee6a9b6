"""Shared by the simulator tests: run a scenario offline, and what a decoder must count."""

import time

import firmware_protocol as fp
from groundstation.sim.stream import Scenario, SimStream


def stream_bytes(scenario: Scenario, step_s: float | None = None) -> tuple[bytes, SimStream]:
    """Everything the stream delivers for the scenario's duration (then flushed)."""
    stream = SimStream(scenario)
    if step_s is None:
        chunks = stream.advance(stream.end_s)
    else:
        chunks, t = [], 0.0
        while t < stream.end_s:
            t = min(t + step_s, stream.end_s)
            chunks += stream.advance(t)
    chunks += stream.flush()
    return b"".join(c.data for c in chunks), stream


def assert_decoder_agrees_with_link(decoder: fp.StreamDecoder, frames: list, stream: SimStream) -> None:
    """The decoder's counters equal what the link says it injected."""
    report, stats = stream.link.report, decoder.stats
    assert stats.frames == report.delivered_intact
    # Frames the link lost after the last frame that arrived are invisible to any decoder.
    trailing = (stream.firmware.last_seq - frames[-1].seq) & 0xFF
    assert stats.frames_lost == report.lost + report.truncated + report.corrupted - trailing
    assert stats.bytes_in == report.bytes_delivered
    assert stats.bytes_skipped + decoder.pending_bytes == report.damaged_bytes
    # Each damaged frame with its header intact fails its CRC; stray sync bytes inside damaged
    # frames can add candidates, never remove one.
    assert stats.crc_errors >= report.damaged_with_header
    assert stats.duplicates == 0


ENUM = {name: enum.values for name, enum in fp.SPEC.enums.items()}  # the spec's enums: name -> value


def read_for(port, decoder: fp.StreamDecoder, seconds: float) -> list:
    """The frames a pyserial ``port`` delivers in ``seconds``."""
    frames, end = [], time.monotonic() + seconds
    while time.monotonic() < end:
        frames += decoder.feed(port.read(port.in_waiting or 1))
    return frames
