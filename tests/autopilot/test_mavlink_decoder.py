"""The byte-stream decoder against pymavlink's own parse of the same bytes (the oracle), whatever the
chunking, with MAVLink 1 and 2 mixed and junk between packets; sequence gaps counted per sender."""

import random

from hypothesis import given, settings
from hypothesis import strategies as st
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation.autopilot.decoder import MavlinkDecoder

from mavlink_helpers import Sender, ardupilot_heartbeat


def stream(seed: int, n: int = 200):
    """Packets from an autopilot (MAVLink 2), a SiK radio (MAVLink 1) and junk, in a seeded order."""
    rng = random.Random(seed)
    ap, radio = Sender(1, 1), Sender(51, 68, mavlink1=True)
    out = [ardupilot_heartbeat(ap)]
    for i in range(n):
        kind = rng.random()
        if kind < 0.5:
            out.append(ap.raw_imu(i * 20_000, rng.randint(-2000, 2000), 3, -1000, rng.randint(-500, 500), 0, 0, 1, 2, 3))
        elif kind < 0.8:
            out.append(ap.attitude(i * 20, rng.uniform(-1, 1), 0.1, 0.2, 0, 0, 0))
        elif kind < 0.9:
            out.append(radio.radio_status(rng.randint(0, 254), 100, 50, 30, 31, i, 0))
        else:
            out.append(bytes(rng.randrange(256) for _ in range(rng.randint(1, 12))).replace(b"\xfd", b"").replace(b"\xfe", b""))
    return b"".join(out)


def oracle(data: bytes) -> list:
    parser = mavlink.MAVLink(None)
    parser.robust_parsing = True
    return [(m.get_type(), m.get_srcSystem(), m.get_srcComponent(), m.get_seq(), m.to_dict())
            for m in parser.parse_buffer(data) or () if m.get_type() != "BAD_DATA"]


@settings(max_examples=15)
@given(seed=st.integers(0, 10_000), cuts=st.lists(st.integers(1, 5000), max_size=30))
def test_same_messages_as_pymavlink_for_any_chunking(seed, cuts):
    data = stream(seed)
    decoder = MavlinkDecoder()
    got, at = [], 0
    for cut in sorted(set(cuts)) + [len(data)]:
        got += [(m.get_type(), m.get_srcSystem(), m.get_srcComponent(), m.get_seq(), m.to_dict()) for m in decoder.messages(data[at:cut])]
        at = max(at, cut)
    assert got == oracle(data)
    assert decoder.stats.bytes_in == len(data)
    assert decoder.stats.messages == len(got)


def test_records_come_in_arrival_order_and_junk_is_counted():
    data = stream(3)
    decoder = MavlinkDecoder()
    records = decoder.feed(data)
    imu_times = [r.time_us for r in records if type(r).__name__ == "ImuSample"]
    assert imu_times == sorted(imu_times) and len(imu_times) > 50
    assert decoder.stats.bad_bytes > 0 and decoder.stats.bad_runs > 0


def test_lost_packets_are_counted_per_sender_from_sequence_gaps():
    ap, radio = Sender(1, 1), Sender(51, 68, mavlink1=True)
    packets = [(1, ap.attitude(i, 0, 0, 0, 0, 0, 0)) for i in range(600)] + [(51, radio.radio_status(1, 1, 1, 1, 1, 1, 1)) for _ in range(40)]
    rng = random.Random(5)
    dropped = {1: set(rng.sample(range(1, 599), 37)), 51: set(rng.sample(range(1, 39), 4))}
    kept, index = [], {1: 0, 51: 0}
    for system, packet in packets:
        if index[system] not in dropped[system]:
            kept.append(packet)
        index[system] += 1
    decoder = MavlinkDecoder()
    decoder.feed(b"".join(kept))
    assert decoder.senders[(1, 1)].lost == 37 and decoder.senders[(1, 1)].received == 600 - 37
    assert decoder.senders[(51, 68)].lost == 4
    assert abs(decoder.senders[(1, 1)].loss_pct - 100 * 37 / 600) < 1e-9
