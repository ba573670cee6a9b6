"""The radio + USB link between the board and the host's serial port, with exact bookkeeping.

Per frame, in order (each decision from the link's own seeded stream, one fixed set of draws per
frame, so the result does not depend on how frames are batched into calls):

1. loss on the radio: a Gilbert–Elliott channel. In the good state a frame is lost with probability
   ``loss``; the bad state loses every frame. ``burst_loss`` is the long-run fraction of time in the
   bad state and ``burst_length_frames`` its mean length (``p(bad→good) = 1/length``);
2. truncation (probability ``truncate``): only a random non-empty prefix arrives;
3. bit errors: each bit of what arrives flips with probability ``ber``;
4. timing: delivery = send + ``latency_ms`` + an exponential jitter of mean ``jitter_ms``, never
   before the previous byte (a serial line keeps order), then held to the next multiple of
   ``usb_batch_ms`` (a USB-serial bridge flushes its buffer on a timer);
5. port drop-outs: every ``dropout_every_s`` the port disappears for ``dropout_s`` (the USB device
   re-enumerating); frames due while it is gone are lost.

``LinkReport`` counts what was done; a stream decoder reading the output must agree with it.
"""

from __future__ import annotations

import dataclasses
import math


from groundstation.sim.firmware import SentFrame
from groundstation.sim.seeds import stream

HEADER_BYTES = 3  # sync, length, type: what a decoder needs intact to try a frame


@dataclasses.dataclass(frozen=True)
class LinkSettings:
    loss: float = 0.0  # independent frame-loss probability
    burst_loss: float = 0.0  # fraction of time the channel is in its all-lost bad state
    burst_length_frames: float = 10.0  # mean length of a bad-state burst
    ber: float = 0.0  # bit-error probability per bit
    truncate: float = 0.0  # probability that a frame arrives cut short
    latency_ms: float = 0.0  # fixed delay
    jitter_ms: float = 0.0  # mean of an exponential extra delay
    usb_batch_ms: float = 0.0  # 0: bytes pass as soon as due; else released on this period
    dropout_every_s: float = 0.0  # 0: the port never disappears
    dropout_s: float = 2.0  # how long it stays away

    def __post_init__(self):
        for name in ("loss", "burst_loss", "ber", "truncate"):
            if not 0.0 <= getattr(self, name) < 1.0:
                raise ValueError(f"{name} must be a probability in [0, 1), not {getattr(self, name)!r}")
        for name in ("latency_ms", "jitter_ms", "usb_batch_ms", "dropout_every_s", "dropout_s"):
            if not 0.0 <= getattr(self, name) < math.inf:
                raise ValueError(f"{name} must be finite and >= 0, not {getattr(self, name)!r}")
        if self.burst_length_frames < 1.0:
            raise ValueError("burst_length_frames must be >= 1")
        if self.dropout_every_s and self.dropout_s >= self.dropout_every_s:
            raise ValueError("dropout_s must be shorter than dropout_every_s")

    def port_is_up(self, t_s: float) -> bool:
        return not (self.dropout_every_s and t_s >= self.dropout_every_s and t_s % self.dropout_every_s < self.dropout_s)


@dataclasses.dataclass
class LinkReport:
    """Exact counts of what the link did to the frames it was given."""

    frames_in: int = 0
    delivered_intact: int = 0
    lost_random: int = 0  # good-state loss
    lost_burst: int = 0  # bad-state loss
    lost_dropout: int = 0  # due while the port was gone
    truncated: int = 0  # delivered cut short (bit errors in them are not counted again)
    corrupted: int = 0  # delivered whole with at least one bit flipped
    damaged_with_header: int = 0  # truncated or corrupted with sync, length and type intact
    bytes_delivered: int = 0
    damaged_bytes: int = 0  # bytes of truncated or corrupted frames

    @property
    def lost(self) -> int:
        return self.lost_random + self.lost_burst + self.lost_dropout

    def as_dict(self) -> dict[str, int]:
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class Chunk:
    """Bytes that reach the host's serial port at simulated time ``t_s``."""

    t_s: float
    data: bytes
    t_us: tuple[int, ...]  # device timestamps of the intact frames in ``data`` (for latency)


class InFlight:
    """Chunks the link has carried that have not reached the host's port yet, in arrival order."""

    def __init__(self) -> None:
        self._chunks: list[Chunk] = []

    def add(self, chunks: list[Chunk]) -> None:
        self._chunks += chunks

    def due(self, t_s: float) -> list[Chunk]:
        """The chunks at the host's port by simulated time ``t_s``, in order."""
        n = 0
        while n < len(self._chunks) and self._chunks[n].t_s <= t_s:
            n += 1
        due, self._chunks = self._chunks[:n], self._chunks[n:]
        return due

    def flush(self) -> list[Chunk]:
        """Every chunk still in flight (for the end of a recording: everything sent arrives)."""
        due, self._chunks = self._chunks, []
        return due

    def next_arrival_s(self, otherwise_s: float) -> float:
        """When the next chunk arrives, or ``otherwise_s`` if sooner (or none is in flight)."""
        return min(otherwise_s, self._chunks[0].t_s) if self._chunks else otherwise_s


class Link:
    def __init__(self, settings: LinkSettings = LinkSettings(), seed: int = 0):
        self.settings = s = settings
        self.report = LinkReport()
        self._rng = stream(seed, "link")
        self._bits = stream(seed, "link_bits")
        self._bad = False
        self._p_bad_to_good = 1.0 / s.burst_length_frames
        self._p_good_to_bad = s.burst_loss * self._p_bad_to_good / (1.0 - s.burst_loss)
        self._last_delivery_s = 0.0

    def carry(self, frames: list[SentFrame]) -> list[Chunk]:
        """The chunks these frames become, in delivery order (frames in send order)."""
        s, report = self.settings, self.report
        draws = self._rng.random((len(frames), 5)).tolist()
        chunks: list[Chunk] = []
        for frame, (u_loss, u_state, u_cut, u_cut_at, u_jitter) in zip(frames, draws):
            report.frames_in += 1
            # Gilbert–Elliott: decide this frame in the current state, then move.
            lost_burst, lost_random = self._bad, not self._bad and u_loss < s.loss
            self._bad = (u_state >= self._p_bad_to_good) if self._bad else (u_state < self._p_good_to_bad)
            data = frame.data
            truncated = u_cut < s.truncate
            if truncated:
                data = data[: 1 + int(u_cut_at * (len(data) - 1))]
            if s.ber:
                data = self._flip_bits(data)
            due = frame.t_s + (s.latency_ms - s.jitter_ms * math.log1p(-u_jitter)) * 1e-3
            due = max(due, self._last_delivery_s)
            if s.usb_batch_ms:
                batch_s = s.usb_batch_ms * 1e-3
                due = math.ceil(due / batch_s - 1e-9) * batch_s
            if lost_burst or lost_random:
                report.lost_burst += lost_burst
                report.lost_random += lost_random
                continue
            if not s.port_is_up(due):
                report.lost_dropout += 1
                continue
            self._last_delivery_s = due
            intact = data == frame.data
            if intact:
                report.delivered_intact += 1
            else:
                report.truncated += truncated
                report.corrupted += not truncated
                report.damaged_bytes += len(data)
                report.damaged_with_header += data[:HEADER_BYTES] == frame.data[:HEADER_BYTES] and len(data) >= HEADER_BYTES
            report.bytes_delivered += len(data)
            stamps = (frame.t_us,) if intact and frame.t_us is not None else ()
            if chunks and chunks[-1].t_s == due:
                last = chunks[-1]
                chunks[-1] = Chunk(due, last.data + data, last.t_us + stamps)
            else:
                chunks.append(Chunk(due, data, stamps))
        return chunks

    def _flip_bits(self, data: bytes) -> bytes:
        flips = self._bits.binomial(8 * len(data), self.settings.ber)
        if not flips:
            return data
        out = bytearray(data)
        for bit in self._bits.choice(8 * len(data), size=flips, replace=False).tolist():
            out[bit >> 3] ^= 1 << (bit & 7)
        return bytes(out)
