"""Incremental stream decoder: bytes in any chunking -> frames, with link-health counters.

It never raises on input bytes. It resynchronises on the sync byte; a candidate whose length is
impossible for its type (this version's payload, or an older sender's shorter one: ``FrameType.readers``), or whose CRC fails, gives up only its sync byte, so a corrupted or
truncated frame never swallows the intact frame that follows it. Every byte fed ends up in an
CRC-valid frame (``frame_bytes``), in ``bytes_skipped``, or still pending (less than one frame):
``bytes_in == frame_bytes + bytes_skipped + pending_bytes``.

Lost frames. The sender numbers every frame (one 8-bit counter for all types), so a gap in the
sequence counts lost frames modulo 256. A gap is placed against the device timestamps too: the
frames the sender sent in the elapsed device time decide how many whole turns of the counter the gap
hides, so an outage of any length is counted right. The sending rate (frames of every type per µs)
is measured on the stream itself, since ``CONFIG``'s ``rate_hz`` counts samples, not frames (a sample
may send IMU_RAW, ATTITUDE and more); it is measured again after a ``CONFIG`` with another rate or a
restart, keeping the last measurement meanwhile; until a first one (0.5 s of stream), gaps count
modulo 256. When ``feed`` is given the chunk's host arrival time, the elapsed time is never taken
longer than the host waited: a device clock that jumped ahead is not an outage.

Plausibility. CRC-valid noise is rare but real (a CRC-16 passes one random candidate in 65,536), so
a frame moves the sequence and timestamp state only if it fits the stream: an unknown type never
does (counted in ``unknown_types``); a timestamp that steps back more than ``BACK_TOLERANCE_US``, or
ahead by more than the host waited (plus a tolerance), is held back until the next timestamped frame
decides. If that one follows the held frame, the device restarted (a reboot, a clock jump): both are
returned, ``restarts`` counts it, device time restarts from the new timestamps and no loss is counted
across it. Otherwise the held frame was noise: it is dropped and counted in ``implausible``.

These sequence and time rules are one public object, ``SequenceRules``: ``StreamDecoder`` calls it
for every frame its inlined fast path does not take, and the columnar ``batch.decode_batch`` calls
it for every frame its cumulative sums do not place.
"""

from __future__ import annotations

from binascii import crc_hqx
from dataclasses import dataclass, fields

from firmware_protocol.codec import CRC_BYTES, CRC_INIT, HEADER_BYTES, SYNC, Frame
from firmware_protocol.spec import SPEC, Spec

_OVERHEAD = HEADER_BYTES + CRC_BYTES
_CONFIG_ID = SPEC.frame("CONFIG").id
_FINGERPRINT_INDEX = SPEC.frame("CONFIG").field_names.index("schema_fingerprint")
_RATE_INDEX = SPEC.frame("CONFIG").field_names.index("rate_hz")
_new = tuple.__new__  # Frame construction without a Python-level call (see codec.Frame)

DEFAULT_RATE_HZ = 100  # until a CONFIG says otherwise
BACK_TOLERANCE_US = 500_000  # a frame stamped up to this before the last one (a sensor reporting late) fits
FORWARD_TOLERANCE_US = 2_000_000  # device time may run ahead of the host's by this (+5 %): host stalls, buffering
CONFIRM_US = 1_000_000  # a held frame is confirmed by the next one if that follows within this and 32 frames
LEARN_US = 500_000  # device time over which the sending rate is measured before it is trusted
_FAST_PERIODS = 4  # consecutive frames less than 4 sample periods apart need no closer look
_WRAP = 1 << 32


def _lookup(spec: Spec) -> tuple[list, list, list, list, list]:
    """Per type id (0..255): the frame type, its payload size, unpacker, readers of every payload length
    it may have (``FrameType.readers``: older senders' shorter ones too) and whether it is timestamped
    (None/False for ids the spec lacks): lists indexed in the hot loop."""
    by_id = {t.id: t for t in spec.frames}
    types = [by_id.get(i) for i in range(256)]
    return (types, [t.payload_size if t else None for t in types], [t.struct.unpack_from if t else None for t in types],
            [t.readers if t else None for t in types], [bool(t and t.has_timestamp) for t in types])


@dataclass
class DecoderStats:
    """Counters since the decoder was made. All are exact counts, none are rates."""

    bytes_in: int = 0
    frames: int = 0  # known-type frames returned
    crc_errors: int = 0  # candidates with a plausible header whose CRC failed
    bytes_skipped: int = 0  # bytes not part of any CRC-valid frame
    frame_bytes: int = 0  # bytes of CRC-valid frames (duplicates, unknown types and implausible ones included)
    frames_lost: int = 0  # frames the sender's sequence counter and timestamps say were sent and did not arrive
    duplicates: int = 0  # a frame repeated byte for byte (same type, seq and values); dropped
    unknown_types: int = 0  # CRC-valid frames of a type this spec lacks; skipped
    bad_lengths: int = 0  # sync + type whose length byte is impossible for that type
    schema_mismatches: int = 0  # CONFIG frames from firmware whose spec has a frame type of ours otherwise, or is unknown
    implausible: int = 0  # CRC-valid frames whose timestamp did not fit the stream; dropped
    restarts: int = 0  # the sender's sequence and clock started over (reboot, clock jump)

    def as_dict(self) -> dict[str, int]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


class StreamDecoder:
    """Feed chunks of any size and boundary; get back the complete, valid, new frames."""

    def __init__(self, spec: Spec = SPEC) -> None:
        """``spec``: the protocol to decode (the project's own by default; tests decode others)."""
        self.spec = spec
        self._types, self._sizes, self._unpackers, self._readers, self._timestamped = _lookup(spec)
        self.stats = DecoderStats()
        self.rules = SequenceRules(self.stats, spec)  # sequence, device time, plausibility, restarts
        self._pending = b""
        self._last_seq: int | None = None  # duplicate detection: the last frame accepted
        self._last_raw: tuple | bytes = ()

    @property
    def rate_hz(self) -> int:
        """From the last CONFIG seen (``DEFAULT_RATE_HZ`` before)."""
        return self.rules.rate_hz

    @property
    def remote_fingerprint(self) -> int | None:
        """From the last CONFIG seen."""
        return self.rules.remote_fingerprint

    @property
    def schema_matches(self) -> bool | None:
        """Whether the firmware's frame types decode as ours (``Spec.changed_frames``) once a CONFIG frame has
        been seen, None before."""
        return self.rules.schema_matches

    @property
    def schema_warning(self) -> str | None:
        """``Spec.schema_warning`` of the last CONFIG seen; None before one, or when its frame types decode as ours."""
        return self.rules.schema_warning

    @property
    def pending_bytes(self) -> int:
        return len(self._pending)

    def feed(self, data: bytes | bytearray | memoryview, t_host_ns: int | None = None) -> list[Frame]:
        """The frames completed by ``data``; ``t_host_ns`` (when it arrived) bounds the loss a clock jump could fake."""
        data = self._pending + bytes(data)
        n = len(data)
        stats = self.stats
        stats.bytes_in += n - len(self._pending)
        out: list[Frame] = []
        append = out.append
        find = data.find
        # Locals, not globals, in the loop that runs a million times a second.
        sync, header, overhead, max_payload, crc_init = SYNC, HEADER_BYTES, _OVERHEAD, self.spec.max_payload_bytes, CRC_INIT
        sizes, unpackers, readers, types, timestamped = self._sizes, self._unpackers, self._readers, self._types, self._timestamped
        crc, new, frame_class = crc_hqx, _new, Frame
        skipped = crc_errors = bad_lengths = lost = duplicates = unknown = accepted = 0
        last_seq, last_raw = self._last_seq, self._last_raw
        rules = self.rules
        ref_next, ref_t32, ref_t64, fast_us = rules.next_seq, rules.t32, rules.t64, rules.fast_us
        t64_before = ref_t64  # the reference moved in this chunk if its device time did: it arrived at t_host_ns
        pos = 0
        while True:
            start = find(sync, pos)
            if start < 0:
                skipped += n - pos
                pos = n
                break
            skipped += start - pos
            if start + header > n:
                pos = start
                break
            length = data[start + 1]
            type_id = data[start + 2]
            size = sizes[type_id]
            if length != size and (length > max_payload if size is None else length not in readers[type_id]):
                bad_lengths += 1
                skipped += 1
                pos = start + 1
                continue
            end = start + overhead + length
            if end > n:
                pos = start
                break
            # The CRC is sent big-endian, so a CRC over the frame including it is 0 when intact.
            if crc(data[start + 1 : end], crc_init):
                crc_errors += 1
                skipped += 1
                pos = start + 1
                continue
            accepted += end - start
            pos = end
            if size is None:  # noise or a newer spec: it must not move the sequence state
                unknown += 1
                continue
            seq = data[start + 3]
            # Encoding is a function of (type, seq, values): equal values mean equal bytes.
            raw = unpackers[type_id](data, start + header) if length == size else readers[type_id][length](data, start + header)
            if seq == last_seq and raw == last_raw:
                duplicates += 1
                continue
            last_seq, last_raw = seq, raw
            if timestamped[type_id]:
                t32 = raw[0]
                step = (t32 - ref_t32) & 0xFFFFFFFF if fast_us else 0
                if seq == ref_next and step < fast_us:  # the common case: the next frame, soon after
                    ref_t64 += step
                    ref_next, ref_t32 = (seq + 1) & 0xFF, t32
                    append(new(frame_class, (types[type_id], seq, raw, ref_t64)))
                    continue
                rules.ran(ref_next, ref_t32, ref_t64, t_host_ns if ref_t64 != t64_before else rules.host_ns)
                lost += rules.timed(out, types[type_id], seq, raw, t32, t_host_ns, stats.frames + len(out) + stats.frames_lost + lost)
                ref_next, ref_t32, ref_t64, fast_us = rules.next_seq, rules.t32, rules.t64, rules.fast_us
                t64_before = ref_t64
                continue
            rules.ran(ref_next, ref_t32, ref_t64, t_host_ns if ref_t64 != t64_before else rules.host_ns)
            t64_before = ref_t64
            lost += rules.untimed(type_id, seq, raw, stats.frames + len(out) + stats.frames_lost + lost)
            ref_next, fast_us = rules.next_seq, 0
            append(new(frame_class, (types[type_id], seq, raw, None)))
        self._pending = data[pos:]
        self._last_seq, self._last_raw = last_seq, last_raw
        rules.ran(ref_next, ref_t32, ref_t64, t_host_ns if ref_t64 != t64_before else rules.host_ns)
        stats.frames += len(out)
        stats.bytes_skipped += skipped
        stats.frame_bytes += accepted
        stats.crc_errors += crc_errors
        stats.bad_lengths += bad_lengths
        stats.frames_lost += lost
        stats.duplicates += duplicates
        stats.unknown_types += unknown
        return out


class SequenceRules:
    """The sender's sequence counter and device clock as both decoders apply them (the module's
    docstring): lost-frame counting, device-time unwrap, plausibility, held frames and restarts.

    ``StreamDecoder`` takes the common frame (timestamped, the next seq, a step shorter than
    ``fast_us``) on its inlined fast path and ``decode_batch`` takes runs of them by cumulative sums;
    both then report where the run left the reference with ``ran``, and hand every other frame to
    ``timed`` or ``untimed``. The state they read is public: ``next_seq`` (the seq expected next),
    ``t32`` and ``t64`` (the reference frame's device time as sent and unwrapped), ``host_ns`` (when
    the reference arrived), ``fast_us`` (0: every frame comes here) and ``held`` (a frame whose
    timestamp awaits confirmation, or None). The counters it keeps (``implausible``, ``restarts``,
    ``schema_mismatches``) are in ``stats``.
    """

    def __init__(self, stats: DecoderStats, spec: Spec = SPEC) -> None:
        self.stats = stats
        self.spec = spec  # the ground station's: what a CONFIG's schema fingerprint is checked against
        self.remote_fingerprint: int | None = None  # from the last CONFIG seen
        self.rate_hz = DEFAULT_RATE_HZ  # from the last CONFIG seen
        self.next_seq: int | None = None
        self.t32: int | None = None
        self.t64 = 0
        self.host_ns: int | None = None
        self.fast_us = 0
        self.held: tuple | None = None  # (type, seq, raw, t32)
        self._untimed_advance = 0  # seq advance taken by frames without timestamp since the reference
        self._untimed_lost = 0  # of which counted lost (taken back if the sender turns out to have restarted)
        self._learn_from = (0, 0)  # (seq advances, device time) where the rate measurement starts
        self._frames_per_us: float | None = None  # the measured sending rate; None until measured

    @property
    def schema_matches(self) -> bool | None:
        """Whether the firmware's frame types decode as ours once a CONFIG frame has been seen, None before."""
        if self.remote_fingerprint is None:
            return None
        return self.spec.changed_frames(self.remote_fingerprint) == ()

    @property
    def schema_warning(self) -> str | None:
        return None if self.remote_fingerprint is None else self.spec.schema_warning(self.remote_fingerprint)

    def ran(self, next_seq: int | None, t32: int | None, t64: int, host_ns: int | None) -> None:
        """The fast path placed frames up to here: the last one's next seq, device times and arrival."""
        self.next_seq, self.t32, self.t64, self.host_ns = next_seq, t32, t64, host_ns

    def _fast_threshold(self) -> int:
        """Steps below this need no closer look; 0 sends every frame to ``timed`` (no reference yet,
        frames without timestamp since it, or a held frame waiting)."""
        if self.t32 is None or self._untimed_advance or self.held is not None:
            return 0
        return _FAST_PERIODS * 1_000_000 // self.rate_hz

    def timed(self, out: list, frame_type, seq: int, raw: tuple, t32: int, t_host_ns: int | None, advances: int) -> int:
        """Place a timestamped frame that is not simply the next one: appended to ``out`` with its
        unwrapped device time (two frames when it confirms a held one, none when it is held); returns
        the frames lost before it. ``advances``: every frame returned or counted lost so far (the
        sender's sequence, unwrapped)."""
        lost = 0
        if self.t32 is None:  # the first timestamped frame
            if self.next_seq is not None:
                lost = (seq - self.next_seq) & 0xFF
            self._restart(seq, t32, t_host_ns, advances + lost)
            out.append(_new(Frame, (frame_type, seq, raw, t32)))
            return lost
        step = (t32 - self.t32) & 0xFFFFFFFF
        step_us = step if step < _WRAP // 2 else step - _WRAP
        host_us = None if t_host_ns is None or self.host_ns is None else (t_host_ns - self.host_ns) // 1000
        if step_us >= -BACK_TOLERANCE_US and (host_us is None or step_us <= host_us * 1.05 + FORWARD_TOLERANCE_US):
            if self.held is not None:
                self.held = None
                self.stats.implausible += 1
            gap = (seq - self.next_seq) & 0xFF
            sent = self._untimed_advance + gap + 1  # seq advance since the reference, modulo 256
            lost = gap
            # The rate up to the reference frame: untimed frames since (an ACK and a CONFIG answering a
            # reconnection's request) carry losses counted modulo 256 so far, which must not inflate it.
            rate = self._rate(advances - self._untimed_advance)
            if rate is not None:  # whole turns of the counter the gap hides
                elapsed_us = step_us if host_us is None else min(step_us, host_us)
                lost += 256 * max(0, round((elapsed_us * rate - sent) / 256))
            self._untimed_advance = self._untimed_lost = 0
            self._move(seq, t32, self.t64 + step_us, t_host_ns)
            out.append(_new(Frame, (frame_type, seq, raw, self.t64)))
            return lost
        held = self.held
        if held is not None:
            since = (t32 - held[3]) & 0xFFFFFFFF
            if since <= CONFIRM_US and 0 < (seq - held[1]) & 0xFF <= 32:  # it follows the held frame: a restart
                # No loss is counted across a restart: what the sequence said since the reference is taken back.
                self.stats.restarts += 1
                lost = -self._untimed_lost
                self._restart(held[1], held[3], t_host_ns, advances + lost)
                out.append(_new(Frame, (*held[:3], held[3])))
                self._move(seq, t32, held[3] + since, t_host_ns)
                out.append(_new(Frame, (frame_type, seq, raw, self.t64)))
                return lost
            self.stats.implausible += 1  # the held frame was noise, and this one may be too
        self.held = (frame_type, seq, raw, t32)
        self.fast_us = 0
        return 0

    def untimed(self, type_id: int, seq: int, raw: tuple, advances: int) -> int:
        """A frame without timestamp: the sequence goes on (the next timestamped frame checks the time,
        on the slow path); returns the frames lost before it."""
        lost = 0
        if self.next_seq is not None:
            lost = (seq - self.next_seq) & 0xFF
            self._untimed_lost += lost
            self._untimed_advance += lost + 1
        self.next_seq, self.fast_us = (seq + 1) & 0xFF, 0
        if type_id == _CONFIG_ID:
            self._config(raw, advances + lost)
        return lost

    def _move(self, seq: int, t32: int, t64: int, t_host_ns: int | None) -> None:
        self.next_seq, self.t32, self.t64, self.host_ns = (seq + 1) & 0xFF, t32, t64, t_host_ns
        self.fast_us = self._fast_threshold()

    def _restart(self, seq: int, t32: int, t_host_ns: int | None, advances: int) -> None:
        """A new reference with no past: the first frame, or the first after the sender restarted."""
        self.held = None
        self._untimed_advance = self._untimed_lost = 0
        self._move(seq, t32, t32, t_host_ns)
        self._learn_from = (advances + 1, t32)

    def _rate(self, advances: int) -> float | None:
        """Frames per µs of device time the sender has been sending (measured, or the last measurement)."""
        advances0, t0 = self._learn_from
        span_us = self.t64 - t0
        if span_us >= LEARN_US:
            self._frames_per_us = (advances - advances0) / span_us
        return self._frames_per_us

    def _config(self, raw: tuple, advances: int) -> None:
        fingerprint = raw[_FINGERPRINT_INDEX]
        self.remote_fingerprint = fingerprint
        if self.spec.changed_frames(fingerprint) != ():
            self.stats.schema_mismatches += 1
        rate_hz = raw[_RATE_INDEX]
        if 0 < rate_hz != self.rate_hz:  # another rate: measure again
            self.rate_hz = rate_hz
            self._frames_per_us = None
            self._learn_from = (advances + 1, self.t64)
        # The same rate again (the answer to the request a reconnection sends) keeps the measurement going:
        # restarting it here, just before the first sample after the outage, left no rate to count it by.
