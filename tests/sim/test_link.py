"""The link model: the decoder's counters match what it injected; loss statistics; timing."""

import math

import numpy as np

import firmware_protocol as fp
from groundstation.sim.firmware import SentFrame
from groundstation.sim.link import Link, LinkSettings
from groundstation.sim.stream import Scenario

from sim_helpers import assert_decoder_agrees_with_link, stream_bytes

ALL_IMPAIRMENTS = LinkSettings(loss=0.02, burst_loss=0.03, burst_length_frames=6, ber=2e-4, truncate=0.01,
                               latency_ms=3.0, jitter_ms=2.0, usb_batch_ms=4.0)


def test_decoder_counts_exactly_what_the_link_injected():
    data, stream = stream_bytes(Scenario("flight", 60.0, seed=11, link=ALL_IMPAIRMENTS))
    report = stream.link.report
    assert min(report.lost_random, report.lost_burst, report.truncated, report.corrupted) > 50
    decoder = fp.StreamDecoder()
    frames = []
    for i in range(0, len(data), 64):  # in serial-sized pieces
        frames += decoder.feed(data[i : i + 64])
    assert_decoder_agrees_with_link(decoder, frames, stream)


def test_stepping_in_10_ms_or_in_one_block_gives_identical_bytes():
    scenario = Scenario("hover", 20.0, seed=5, link=ALL_IMPAIRMENTS)
    assert stream_bytes(scenario, step_s=0.01)[0] == stream_bytes(scenario)[0]
    other_seed = Scenario("hover", 20.0, seed=6, link=ALL_IMPAIRMENTS)
    assert stream_bytes(other_seed)[0] != stream_bytes(scenario)[0]


def frames_at(rate_hz, n, size=20):
    return [SentFrame(k / rate_hz, bytes([0xA5]) + bytes(size - 1), k) for k in range(n)]


def test_gilbert_elliott_bursts_have_the_configured_share_and_length():
    link = Link(LinkSettings(burst_loss=0.1, burst_length_frames=8.0), seed=3)
    chunks = link.carry(frames_at(100.0, 200_000))
    arrived = np.zeros(200_000, dtype=bool)
    arrived[[stamp for c in chunks for stamp in c.t_us]] = True
    lost = ~arrived
    assert abs(lost.mean() - 0.1) < 0.01
    starts = np.flatnonzero(lost[1:] & ~lost[:-1])
    assert abs(lost.sum() / len(starts) - 8.0) < 0.5


def test_latency_jitter_and_batching_shape_delivery_times():
    settings = LinkSettings(latency_ms=5.0, jitter_ms=2.0, usb_batch_ms=16.0)
    chunks = Link(settings, seed=1).carry(frames_at(100.0, 5000))
    times = np.array([c.t_s for c in chunks])
    assert np.all(np.diff(times) > 0)
    batches = times / 0.016
    assert np.allclose(batches, np.round(batches), atol=1e-6)
    # Each frame arrives in the first batch after send + latency + jitter.
    sent = np.array([c.t_us[0] / 100.0 for c in chunks])
    assert np.all(times >= sent + 0.005 - 1e-9)
    assert 0.005 + 0.002 < np.mean(times - sent) < 0.005 + 0.002 + 0.016


def test_port_dropouts_lose_what_falls_due_while_away():
    settings = LinkSettings(dropout_every_s=10.0, dropout_s=2.0)
    chunks = Link(settings, seed=1).carry(frames_at(100.0, 4000))
    times = np.array([c.t_s for c in chunks])
    assert not np.any((times >= 10.0) & (times % 10.0 < 2.0))
    assert len(chunks) == 4000 - 3 * 200
    assert not settings.port_is_up(21.0) and settings.port_is_up(19.0) and settings.port_is_up(5.0)
    assert math.isclose(sum(len(c.data) for c in chunks), 20 * len(chunks))
