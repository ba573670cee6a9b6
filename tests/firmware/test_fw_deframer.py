"""The bridge's deframer (gs_deframer.c) finds in a damaged byte stream exactly the frames the Python
StreamDecoder finds, whatever the chunking."""

import random

import firmware_protocol as fp
from firmware_protocol.reference import host


def damaged_stream(rng: random.Random, n_frames: int) -> bytes:
    """Commands and downlink frames back to back, with noise, stray sync bytes, cut and flipped frames."""
    out = bytearray()
    for seq in range(n_frames):
        frame = bytearray(fp.encode(fp.make_frame("COMMAND", seq=seq & 0xFF, command=rng.randint(1, 4), param=rng.randint(0, 4),
                                                  value=rng.uniform(-5, 5))
                                    if rng.random() < 0.6 else
                                    fp.make_frame("ACK", seq=seq & 0xFF, command_seq=rng.randint(0, 255), command=1, result=0)))
        damage = rng.random()
        if damage < 0.1:
            frame[rng.randrange(1, len(frame))] ^= 1 << rng.randrange(8)
        elif damage < 0.2:
            frame = frame[: rng.randrange(1, len(frame))]
        elif damage < 0.3:
            out += bytes([fp.SPEC.sync, rng.randrange(256)])
        elif damage < 0.4:
            out += bytes(rng.randrange(256) for _ in range(rng.randrange(1, 40)))
        out += frame
    return bytes(out)


def test_the_deframer_finds_the_decoders_frames(c_core):
    rng = random.Random(16)
    data = damaged_stream(rng, 3000)
    expected = [fp.encode(f) for f in fp.StreamDecoder().feed(data)]
    deframer, found, i = host.Deframer(), [], 0
    while i < len(data):
        n = rng.randint(1, 64)
        found += host.split_frames(deframer.feed(data[i : i + n]))
        i += n
    assert found == expected
    assert 2000 < len(found) < 3000  # the damage did remove frames, and only some
