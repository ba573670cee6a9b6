"""SessionClock: a monotonic session time, continuous in wall-clock terms, whatever the device clock does.

The streams are built from what really happened (host time of each frame, the device clock's raw
32-bit value, the discontinuities put in); the clock sees only the two clocks and must find them.
"""

import math

import numpy as np

from hypothesis import given, settings
from hypothesis import strategies as st

from groundstation.session_parts.clock import SessionClock

PERIOD_US = 10_000
WRAP = 2**32

# What happens between two stretches of ordinary frames:
#   ("outage", host_gap_s): nothing arrives for a while, the device clock runs on (wraps included);
#   ("ahead", host_gap_s, jump_s): the device clock jumps ahead of the host's by jump_s;
#   ("back", host_gap_s, back_s): the device clock restarts: the next frame is stamped back_s before
#   the last one (a 32-bit clock can show no more than one wrap; a reset during an outage longer than
#   the uptime before it looks like an outage, see clock.py).
outage = st.tuples(st.just("outage"), st.floats(0.0, 3 * 3600.0))
ahead = st.tuples(st.just("ahead"), st.floats(0.0, 5.0), st.floats(1.0, 3600.0))
back = st.tuples(st.just("back"), st.floats(0.0, 5.0), st.floats(1.0, 4000.0))
histories = st.lists(st.tuples(st.integers(1, 40), st.one_of(outage, ahead, back)), min_size=1, max_size=12)


def stream(t0_us: int, history, latency=None):
    """[(host ns, raw 32-bit device µs, host send s)] and the number of discontinuities put in."""
    frames, t_dev, t_host, jumps = [], t0_us, 0.0, 0
    for n, (kind, host_gap_s, *jump) in history:
        for _ in range(n):
            frames.append((t_host, t_dev & 0xFFFFFFFF))
            t_dev += PERIOD_US
            t_host += PERIOD_US * 1e-6
        t_host += host_gap_s
        if kind == "back":
            t_dev -= PERIOD_US + round(jump[0] * 1e6)
        else:
            t_dev += round(host_gap_s * 1e6) + (round(jump[0] * 1e6) if kind == "ahead" else 0)
        jumps += kind != "outage"
    frames.append((t_host, t_dev & 0xFFFFFFFF))
    return frames, jumps


@settings(max_examples=200)
@given(st.integers(0, WRAP - 1), histories)
def test_time_is_monotonic_follows_the_host_clock_and_every_jump_is_one_event(t0_us, history):
    """No delivery delay: the session time must equal the host's elapsed time at every frame."""
    frames, jumps = stream(t0_us, history)
    clock, times, events = SessionClock(), [], []
    for t_send_s, t32 in frames:
        times.append(clock.place(round(t_send_s * 1e9) + 10**12, t32))
        if clock.event is not None:
            events.append(clock.event)
    assert all(b > a for a, b in zip(times, times[1:]))
    for (t_send_s, _), time_s in zip(frames, times):
        assert math.isclose(time_s, t_send_s, abs_tol=2e-6)
    assert len(events) == jumps == clock.segment


@settings(max_examples=150)
@given(st.integers(0, WRAP - 1), histories, st.randoms(use_true_random=False))
def test_late_and_bunched_arrivals_never_fake_a_jump_nor_hide_one(t0_us, history, rng):
    """Each frame up to 0.2 s late; a USB bridge or a busy host hands several over in one chunk."""
    frames, jumps = stream(t0_us, history)
    clock, times, events, arrived = SessionClock(), [], [], 0.0
    for t_send_s, t32 in frames:
        arrived = max(arrived, t_send_s + rng.uniform(0.0, 0.2))
        if rng.random() < 0.3:  # the next frames come in the same chunk
            arrived = max(arrived, t_send_s + 0.2)
        times.append(clock.place(round(arrived * 1e9), t32))
        events += [clock.event] if clock.event else []
        # Never ahead of the host clock by more than one delivery delay, plus one per discontinuity:
        # the first frame after one is placed at the least delay seen, but its own delay is unknown.
        assert times[-1] <= arrived - frames[0][0] + 0.2 * (1 + len(events)) + 1e-6
    assert all(b >= a for a, b in zip(times, times[1:]))
    assert len(events) == jumps


def test_the_32_bit_wrap_is_not_a_discontinuity():
    clock, t_host_ns = SessionClock(), 0
    times = []
    for k in range(1000):
        times.append(clock.place(t_host_ns, (WRAP - 3_000_000 + k * PERIOD_US) & 0xFFFFFFFF))
        t_host_ns += PERIOD_US * 1000
    assert clock.segment == 0 and math.isclose(times[-1], 9.99, abs_tol=1e-9)
    assert clock.device_us == WRAP - 3_000_000 + 999 * PERIOD_US  # unwrapped


def test_a_reboot_is_reported_with_both_clocks():
    clock = SessionClock()
    for k in range(3000):  # 30 s of uptime, from 1 s after power-up
        clock.place(5 * 10**9 + k * PERIOD_US * 1000, 1_000_000 + k * PERIOD_US)
    last_host_ns = 5 * 10**9 + 2999 * PERIOD_US * 1000
    time_s = clock.place(last_host_ns + 1_500_000_000, 1_000_000)  # up again 1.5 s later, clock from 0 (+1 s boot)
    assert clock.event == {
        "kind": "device_reset", "t_host_ns": last_host_ns + 1_500_000_000,
        "device_time_us_before": 1_000_000 + 2999 * PERIOD_US, "device_time_us_after": 1_000_000,
        "session_time_before_s": 29.99, "session_time_s": time_s, "host_elapsed_s": 1.5,
    }
    assert math.isclose(time_s, 29.99 + 1.5, abs_tol=1e-9)
    assert math.isclose(clock.place(last_host_ns + 1_510_000_000, 1_010_000) - time_s, 0.01, abs_tol=1e-9)  # the new boot's clock


def test_a_frame_stamped_a_little_before_the_last_gets_the_last_time():
    clock = SessionClock()
    clock.place(0, 5_000_000)
    assert clock.place(10_000_000, 5_010_000) == 0.01
    assert clock.place(10_000_000, 4_900_000) == 0.01 and clock.device_us == 4_900_000 and clock.event is None
    assert clock.place(20_000_000, 5_020_000) == 0.02


@settings(max_examples=150)
@given(st.integers(0, WRAP - 1), histories, st.randoms(use_true_random=False), st.floats(-200.0, 200.0))
def test_place_many_is_place_frame_by_frame(t0_us, history, rng, drift_ppm):
    """The batch path's columns: the same times, device times and events bit for bit, with late,
    bunched and early frames, a drifting device clock (the lead rises frame after frame), sensors
    reporting a little late, outages, jumps and restarts."""
    frames, _ = stream(t0_us, history)
    hosts, stamps, arrived = [], [], 0.0
    for t_send_s, t32 in frames:
        arrived = max(arrived, t_send_s * (1 + drift_ppm * 1e-6) + rng.choice([0.0, rng.uniform(0.0, 0.2)]))
        hosts.append(round(arrived * 1e9))
        stamps.append(t32 if rng.random() > 0.05 else (t32 - rng.randrange(400_000)) & 0xFFFFFFFF)  # a late sensor
    one, expected, expected_device, expected_events = SessionClock(), [], [], []
    for i, (t_host_ns, t32) in enumerate(zip(hosts, stamps)):
        expected.append(one.place(t_host_ns, t32))
        expected_device.append(one.device_us)
        expected_events += [(i, one.event)] if one.event else []
    times, device, events = SessionClock().place_many(np.array(hosts, dtype=np.int64), np.array(stamps, dtype=np.int64))
    assert times.tolist() == expected and device.tolist() == expected_device and events == expected_events
