"""The simulated stream as an in-process, pyserial-like port: the simulator where no pty exists (Windows).

``SimulatedPort`` offers the part of ``serial.Serial`` a reader uses (``read``, ``in_waiting``,
``write``, ``reset_input_buffer``, ``close``, ``is_open``, ``timeout``), paced by the host's monotonic
clock exactly as the pty bridge is, so code written against a serial port runs on it unchanged.
"""

from __future__ import annotations

import time

from groundstation.sim.stream import SimStream


class SimulatedPort:
    def __init__(self, stream: SimStream, timeout: float | None = 1.0):
        self.stream = stream
        self.timeout = timeout
        self.is_open = True
        self._t0 = time.monotonic()
        self._buffer = bytearray()

    def _now_s(self) -> float:
        return time.monotonic() - self._t0

    def _pump(self) -> None:
        now = self._now_s()
        if self.stream.link.settings.port_is_up(now):
            self._buffer += b"".join(chunk.data for chunk in self.stream.advance(now))
        else:
            self.stream.advance(now)  # the device is gone: what falls due now is lost

    @property
    def in_waiting(self) -> int:
        self._pump()
        return len(self._buffer)

    def read(self, size: int = 1) -> bytes:
        """Up to ``size`` bytes; waits (up to ``timeout`` s, None = forever) until at least one is due."""
        if not self.is_open:
            raise OSError("port is closed")
        deadline = None if self.timeout is None else time.monotonic() + self.timeout
        self._pump()
        while not self._buffer:
            wake_s = self.stream.next_event_s() - self._now_s()
            if deadline is not None:
                wake_s = min(wake_s, deadline - time.monotonic())
                if wake_s <= 0:
                    break
            time.sleep(max(wake_s, 0.0))
            self._pump()
        data = bytes(self._buffer[:size])
        del self._buffer[:size]
        return data

    def write(self, data: bytes) -> int:
        if not self.is_open:
            raise OSError("port is closed")
        self.stream.receive(bytes(data))
        return len(data)

    def reset_input_buffer(self) -> None:
        self._pump()
        self._buffer.clear()

    def close(self) -> None:
        self.is_open = False

    def __enter__(self) -> SimulatedPort:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
