"""Simulated sessions as the chunks a host receives, and recordings of them, for tests."""

from __future__ import annotations

from groundstation.recording import RecordingWriter
from groundstation.sim.firmware import FirmwareSettings
from groundstation.sim.link import LinkSettings
from groundstation.sim.stream import Scenario, SimStream


def simulated_chunks(duration_s: float, seed: int = 7, **options) -> list[tuple[int, bytes]]:
    """``(t_host_ns, bytes)`` chunks of a simulated flight; ``options`` are FirmwareSettings and
    LinkSettings fields (``reboot_after_s``, ``mag_rate_hz``, ``loss``, ``usb_batch_ms`` ...)."""
    firmware = {k: v for k, v in options.items() if k in FirmwareSettings.__dataclass_fields__}
    link = {k: v for k, v in options.items() if k in LinkSettings.__dataclass_fields__}
    unknown = set(options) - set(firmware) - set(link)
    assert not unknown, f"not simulator options: {unknown}"
    stream = SimStream(Scenario(duration_s=duration_s, seed=seed, firmware=FirmwareSettings(**firmware),
                                link=LinkSettings(**link)))
    chunks = stream.advance(duration_s) + stream.flush()
    return [(int(c.t_s * 1e9), c.data) for c in chunks]


def write_recording(path, chunks, metadata: dict | None = None, events=()) -> None:
    """A recording of ``chunks`` with ``events`` (``(t_host_ns, event)``) in its stream."""
    with RecordingWriter(path, {"source": "test", **(metadata or {})}) as writer:
        for t_host_ns, event in events:
            writer.write_event(t_host_ns, event)
        for t_host_ns, data in chunks:
            writer.write_chunk(t_host_ns, data)
