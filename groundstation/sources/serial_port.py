"""A serial port (any pyserial port name or URL: COM3, /dev/ttyUSB0, loop://, socket://host:port).

A USB adapter that is unplugged and plugged back may return under another name (Windows gives it
another COM number; Linux another ttyUSBn when the old one is still held). ``SerialSource`` remembers
the adapter's USB VID:PID and serial number at open and, when its name is gone from the port list,
reopens the port that has the same identity.
"""

from __future__ import annotations

import os
import sys
import time

import serial
from serial.tools import list_ports as pyserial_list_ports

from groundstation.sources.base import Chunk, SourceError, refuse_reopen

READ_TIMEOUT_S = 0.05  # the reader's longest wait: it notices a stop request this quickly
DEFAULT_BAUD = 115200
DIALOUT_HINT = ("on Linux, add yourself to the 'dialout' group (sudo usermod -aG dialout $USER), "
                "then log out and back in")


class PortSource:
    """Reads whatever an open pyserial-like port has (``in_waiting or 1`` bytes), stamped on arrival.

    The port may be any object with read, write, in_waiting and close: the in-process simulated
    bridge plugs in here. It cannot be reopened (``SerialSource`` can).
    """

    is_replay = False
    can_reopen = False
    can_send = True

    def __init__(self, port, description: str):
        self._port = port
        self.description = description

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

    def reopen(self) -> None:
        refuse_reopen(self)

    def close(self) -> None:
        try:
            self._port.close()
        except (serial.SerialException, OSError):
            pass  # already gone; closing must not fail


class SerialSource(PortSource):
    """A port opened by name or pyserial URL; ``reopen`` opens it again, under another name if the
    same USB adapter came back as one.

    ``list_ports`` is how the machine's ports are enumerated (``serial.tools.list_ports.comports``);
    the tests pass their own where no USB adapter can exist.
    """

    can_reopen = True

    def __init__(self, name: str, baud: int = DEFAULT_BAUD, description: str | None = None,
                 list_ports=pyserial_list_ports.comports):
        self.port_name = name
        self.baud = baud
        self._named = description
        self._list_ports = list_ports
        super().__init__(self._open(name), self._describe())
        self.usb_identity = self._identity_of(name)  # (vid, pid, serial number) or None when not USB

    def _describe(self) -> str:
        return self._named or f"{self.port_name} @ {self.baud} baud"

    def _open(self, name: str):
        try:
            return serial.serial_for_url(name, baudrate=self.baud, timeout=READ_TIMEOUT_S)
        except (serial.SerialException, ValueError, OSError) as error:
            what = f"the {self._named}" if self._named else f"serial port {name}"
            # pyserial's text already quotes the OS error with its [Errno N]; say the system's reason once
            reason = f"[Errno {error.errno}] {os.strerror(error.errno)}" if getattr(error, "errno", None) else error
            raise SourceError(explain_port_error(f"cannot open {what}: {reason}")) from None

    def _ports(self) -> list:
        try:
            return list(self._list_ports())
        except OSError:
            return []  # enumeration failing must not stop a reconnection by name

    def _identity_of(self, name: str) -> tuple[int, int, str | None] | None:
        if "://" in name:
            return None  # a URL is not a USB device
        for info in self._ports():
            if _same_device(info.device, name) and info.vid is not None and info.pid is not None:
                return info.vid, info.pid, info.serial_number
        return None

    def current_name(self) -> str:
        """The name to reopen: ours while it is listed (or unknown to the list); otherwise the one
        port with our USB VID:PID and serial number. Without a serial number (cheap adapters) a
        VID:PID match counts only when exactly one port has it: never guess between two."""
        if self.usb_identity is None:
            return self.port_name
        ports = self._ports()
        if any(_same_device(info.device, self.port_name) for info in ports):
            return self.port_name
        same = [info.device for info in ports if (info.vid, info.pid, info.serial_number) == self.usb_identity]
        return same[0] if len(same) == 1 else self.port_name

    def reopen(self) -> None:
        """Open the port again after it went away (a USB bridge unplugged and plugged back)."""
        self.close()
        name = self.current_name()
        self._port = self._open(name)
        self.port_name = name
        self.description = self._describe()


def _same_device(listed: str, name: str) -> bool:
    """``listed`` (from the port list) is ``name``, also through a symlink (/dev/serial/by-id/...)."""
    return listed == name or os.path.realpath(listed) == os.path.realpath(name)


def explain_port_error(message: str) -> str:
    """The open error with what to do about it: a missing permission, a port in use."""
    lowered = message.lower()
    if "permission denied" in lowered or "errno 13" in lowered:
        return f"{message}. Permission denied: " + (DIALOUT_HINT if sys.platform.startswith("linux") else
                                                     "another user or program may own the port")
    if "busy" in lowered or "errno 16" in lowered or "access is denied" in lowered:
        return f"{message}. The port is in use by another program (a serial terminal, another ground station?)"
    return message


def open_spec(spec) -> SerialSource:
    if "://" in spec.target:
        return SerialSource(spec.target, spec.defaults.get("baud", DEFAULT_BAUD))  # a pyserial URL keeps its own options
    spec.check_options({"baud"})
    baud = spec.option("baud", int, DEFAULT_BAUD)
    if baud <= 0:
        raise SourceError(f"{spec.text}: the baud rate must be positive, not {baud}")
    return SerialSource(spec.target, baud)


def list_ports() -> list[dict[str, str]]:
    """Serial ports on this machine: device, description, VID:PID (empty when not USB)."""
    ports = []
    for info in sorted(pyserial_list_ports.comports(), key=lambda p: p.device):
        vid_pid = f"{info.vid:04X}:{info.pid:04X}" if info.vid is not None and info.pid is not None else ""
        ports.append({"device": info.device, "description": info.description or "", "vid_pid": vid_pid})
    return ports
