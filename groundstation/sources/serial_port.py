"""A serial port (any pyserial port name or URL: COM3, /dev/ttyUSB0, loop://, socket://host:port)."""

from __future__ import annotations

import time

import serial
from serial.tools import list_ports as pyserial_list_ports

from groundstation.sources.base import Chunk, SourceError

READ_TIMEOUT_S = 0.05


class SerialSource:
    """Reads whatever the port has (``in_waiting or 1`` bytes), stamped on arrival.

    ``port`` may also be an already open pyserial-like object (read, write, in_waiting, close),
    which is how the in-process simulated bridge plugs in where no pseudo-terminal exists.
    """

    can_send = True

    def __init__(self, port, baud: int = 115200):
        self.baud = baud
        if isinstance(port, str):
            self.port_name: str | None = port
            self.description = f"{port} @ {baud} baud"
            self._port = self._open()
        else:
            self.port_name = None
            self.description = getattr(port, "name", None) or type(port).__name__
            self._port = port

    def _open(self):
        try:
            return serial.serial_for_url(self.port_name, baudrate=self.baud, timeout=READ_TIMEOUT_S)
        except (serial.SerialException, ValueError, OSError) as error:
            raise SourceError(f"cannot open serial port {self.port_name}: {error}") from None

    def reopen(self) -> None:
        """Open the same port again after it went away (a USB bridge unplugged and plugged back)."""
        if self.port_name is None:
            raise SourceError(f"{self.description} cannot be reopened")
        self.close()
        self._port = self._open()

    def read(self) -> Chunk | None:
        try:
            data = self._port.read(self._port.in_waiting or 1)
        except (serial.SerialException, OSError) as error:
            raise SourceError(f"{self.description}: the port stopped answering ({error}); unplugged?") from None
        if not data:
            return None
        return Chunk(time.monotonic_ns(), bytes(data))

    def write(self, data: bytes) -> None:
        try:
            self._port.write(data)
        except (serial.SerialException, OSError) as error:
            raise SourceError(f"{self.description}: cannot send ({error})") from None

    def close(self) -> None:
        try:
            self._port.close()
        except (serial.SerialException, OSError):
            pass  # already gone; closing must not fail


def list_ports() -> list[dict[str, str]]:
    """Serial ports on this machine: device, description, VID:PID (empty when not USB)."""
    ports = []
    for info in sorted(pyserial_list_ports.comports(), key=lambda p: p.device):
        vid_pid = f"{info.vid:04X}:{info.pid:04X}" if info.vid is not None and info.pid is not None else ""
        ports.append({"device": info.device, "description": info.description or "", "vid_pid": vid_pid})
    return ports
