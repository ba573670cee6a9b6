"""Lost frames counted over outages of any length; noise and restarts never faking losses.

The streams are a sender's: one sequence counter for IMU_RAW + ATTITUDE at 100 Hz and a STATUS
every second (2.01 frames per sample, so the counter turns every 1.27 s), each frame stamped with
its sample's device time. What was dropped is known exactly.
"""

import functools
import random

import pytest

from firmware_protocol import SPEC, StreamDecoder, crc16, encode, make_frame

PERIOD_US = 10_000
KNOWN_IDS = {t.id for t in SPEC.frames}


@functools.cache
def sender(n_samples: int, t0_us: int = 1_000_000, seq0: int = 0, config: bool = True):
    """[(device time µs, unwrapped; frame bytes)] in send order; a CONFIG first, as at power-up."""
    frames, seq = [], seq0  # a tuple (cached): callers slice it
    if config:
        frames.append((t0_us, encode(make_frame(
            "CONFIG", seq, protocol_version=1, schema_fingerprint=SPEC.fingerprint, fw_major=0, fw_minor=1, fw_patch=0,
            accel_fs_g=4, gyro_fs_dps=500, rate_hz=100, mode=2, mounting=0, gyro_calibration=1))))
        seq += 1
    for k in range(n_samples):
        t_sent = t0_us + k * PERIOD_US
        t_us = t_sent & 0xFFFFFFFF
        if k % 100 == 0:
            frames.append((t_sent, encode(make_frame("STATUS", seq & 0xFF, t_us=t_us, battery=12000, retransmits=0,
                                                   lost_acks=0, cpu_load=50, flags=0))))
            seq += 1
        frames.append((t_sent, encode(make_frame("IMU_RAW", seq & 0xFF, t_us=t_us, acc_x=k & 0x7FFF, acc_y=2, acc_z=3,
                                               gyr_x=4, gyr_y=5, gyr_z=6, temperature=7))))
        frames.append((t_sent, encode(make_frame("ATTITUDE", seq + 1 & 0xFF, t_us=t_us, q_w=16384, q_x=0, q_y=0, q_z=0,
                                               lambda_gain=k & 0xFFFF, flags=0))))
        seq += 2
    return tuple(frames)


def feed_per_frame(decoder: StreamDecoder, frames, host_offset_ns: int | None = 5_000_000) -> list:
    """Each frame in its own chunk, arriving (when host times are given) 5 ms after its device time."""
    out = []
    for t_us, data in frames:
        out += decoder.feed(data, None if host_offset_ns is None else t_us * 1000 + host_offset_ns)
    return out


@pytest.mark.parametrize("host_times", [True, False], ids=["with host times", "device times only"])
@pytest.mark.parametrize("outage", [1, 255, 256, 257, 1000, 20_000])
def test_an_outage_of_any_length_counts_every_frame_lost(outage, host_times):
    frames = sender(12_000)
    start = 400  # after 2 s of stream: the sending rate is measured
    kept = frames[:start] + frames[start + outage :]
    decoder = StreamDecoder()
    decoded = feed_per_frame(decoder, kept, 5_000_000 if host_times else None)
    assert len(decoded) == len(kept)
    assert decoder.stats.frames_lost == outage
    assert (decoder.stats.implausible, decoder.stats.restarts) == (0, 0)


@pytest.mark.parametrize("outage", [255, 400, 1000])
def test_a_port_that_vanished_and_came_back_counts_every_frame_lost(outage):
    """After a reconnection the session asks for CONFIG again: the answer (untimed, the same rate) arrives
    before the first sample after the outage, and must not make the decoder forget the rate it measured
    (before: the outage was counted modulo 256, 148 of about 406 frames per 2 s dropout)."""
    frames = sender(3_000)
    start = 400
    config_again = frames[0][1][:3] + bytes([frames[start + outage][1][3] - 1 & 0xFF]) + frames[0][1][4:-2]
    config_again = (frames[start + outage][0], config_again + crc16(config_again[1:]).to_bytes(2, "big"))
    kept = [*frames[:start], config_again, *frames[start + outage:]]
    decoder = StreamDecoder()
    assert len(feed_per_frame(decoder, kept)) == len(kept)
    assert decoder.stats.frames_lost == outage - 1  # the CONFIG took one number of the sequence


def test_many_outages_and_a_32_bit_wrap_of_the_device_clock():
    frames = sender(30_000, t0_us=2**32 - 30_000_000)  # the device clock wraps 30 s in
    rng = random.Random(7)
    kept, lost, i = [], 0, 0
    while i < len(frames):
        if rng.random() < 0.002:
            n = rng.choice([3, 256, 512, 700, 2000])
            lost += len(frames[i : i + n])
            i += n
            continue
        kept.append(frames[i])
        i += 1
    decoder = StreamDecoder()
    decoded = feed_per_frame(decoder, kept)
    assert lost > 3000 and decoder.stats.frames_lost == lost
    times = [f.device_time_us for f in decoded if f.device_time_us is not None]
    assert all(b >= a for a, b in zip(times, times[1:])) and times[-1] > 2**32  # unwrapped, monotonic


def test_a_device_clock_jump_ahead_is_not_counted_as_an_outage():
    """The host waited 10 ms while the device clock moved on 10 minutes: nothing was lost."""
    frames = sender(1000) + sender(1000, t0_us=601_000_000 + 1000 * PERIOD_US, seq0=2011, config=False)
    decoder = StreamDecoder()
    for i, (t_us, data) in enumerate(frames):
        decoder.feed(data, 1_000_000_000 + i * 5_000_000)  # the host clock: 5 ms per frame, whatever the device says
    assert decoder.stats.frames_lost == 0 and decoder.stats.restarts == 1


def forged_unknown(rng: random.Random) -> bytes:
    """A CRC-valid frame of a type the spec lacks, random in every other byte, as noise makes them."""
    type_id = rng.choice([i for i in range(256) if i not in KNOWN_IDS])
    payload = rng.randbytes(rng.randrange(0, SPEC.max_payload_bytes + 1))
    body = bytes([len(payload), type_id, rng.randrange(256)]) + payload
    return bytes([SPEC.sync]) + body + crc16(body).to_bytes(2, "big")


def forged_imu(rng: random.Random) -> bytes:
    """A CRC-valid IMU_RAW with a random seq and timestamp (the rare noise that hits a known type and length)."""
    values = {name: rng.randrange(-2**15, 2**15) for name in SPEC.frame("IMU_RAW").field_names}
    values["t_us"] = rng.randrange(2**32)
    return encode(make_frame("IMU_RAW", rng.randrange(256), **values))


@pytest.mark.parametrize("host_times", [True, False], ids=["with host times", "device times only"])
def test_crc_valid_noise_between_real_frames_fakes_no_lost_frame(host_times):
    """Random bytes with forged CRC-valid frames of unknown type between the frames of a clean stream:
    before, each forged frame moved the sequence state and faked ~2 x 128 lost frames."""
    rng = random.Random(2024)
    frames = sender(3000)
    stream, forged = [], 0
    for t_us, data in frames:
        if rng.random() < 0.05:
            noise = rng.randbytes(rng.randrange(1, 60)) + forged_unknown(rng) + rng.randbytes(rng.randrange(1, 60))
            stream.append((t_us, noise))
            forged += 1
        stream.append((t_us, data))
    decoder = StreamDecoder()
    decoded = feed_per_frame(decoder, stream, 5_000_000 if host_times else None)
    assert [encode(f) for f in decoded] == [d for _, d in frames]
    assert forged > 100 and decoder.stats.unknown_types == forged
    assert decoder.stats.frames_lost == 0 and decoder.stats.restarts == 0


def test_a_forged_frame_of_known_type_with_an_implausible_timestamp_is_dropped():
    rng = random.Random(99)
    frames = sender(3000)
    stream, forged = [], 0
    for t_us, data in frames:
        if rng.random() < 0.01:
            stream.append((t_us, forged_imu(rng)))
            forged += 1
        stream.append((t_us, data))
    decoder = StreamDecoder()
    decoded = feed_per_frame(decoder, stream)
    assert [encode(f) for f in decoded] == [d for _, d in frames]
    assert forged > 20 and decoder.stats.implausible == forged
    assert decoder.stats.frames_lost == 0 and decoder.stats.restarts == 0


@pytest.mark.parametrize("uptime_s", [30, 40 * 60, 80 * 60])
def test_a_reboot_restarts_device_time_and_counts_no_loss_across_it(uptime_s):
    """The board browns out after ``uptime_s`` (its clock and counter start over, CONFIG first)."""
    before = sender(500, t0_us=(1 + uptime_s) * 1_000_000 - 500 * PERIOD_US, seq0=uptime_s * 201, config=False)  # its last 5 s
    after = sender(500, t0_us=1_000_000, seq0=0)
    decoder = StreamDecoder()
    decoded = feed_per_frame(decoder, before + after)
    assert len(decoded) == len(before) + len(after)
    assert decoder.stats.frames_lost == 0 and decoder.stats.restarts == 1 and decoder.stats.implausible == 0
    times = [f.device_time_us for f in decoded[len(before) :] if f.device_time_us is not None]
    assert times[0] == 1_000_000 and times[-1] == 1_000_000 + 499 * PERIOD_US  # the new boot's own clock
