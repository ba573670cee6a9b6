"""A POSIX pseudo-terminal carrying the simulated stream in real time (``groundstation bridge-sim``).

Any serial program opens the slave side at any baud rate (a pty ignores it; the slave is put in raw
mode so no line discipline touches the bytes). The bridge keeps the slave open itself, so the pty
survives readers coming and going; while nobody reads, the kernel buffer fills and further bytes are
dropped, as a real USB-serial adapter drops them (counted in ``bytes_dropped``).

Port drop-outs close the pty (a reader gets an I/O error, as when a USB adapter is pulled) and open a
new one; the stable name is a symlink (``link_path``) re-pointed at each new pty, like udev's
``/dev/serial/by-id`` names.
"""

from __future__ import annotations

import os
import select
import time
import tty

from groundstation.sim.stream import SimStream


# Where the slave side of a pseudo-terminal lives (Linux, macOS): a link pointing there is a bridge's own.
PTY_DIRECTORIES = ("/dev/pts/", "/dev/ttys")


def is_a_bridge_link(path: str) -> bool:
    """Whether ``path`` is a symlink to a pseudo-terminal: the only kind of name the bridge replaces or removes."""
    return os.path.islink(path) and os.readlink(path).startswith(PTY_DIRECTORIES)


class PtyBridge:
    def __init__(self, stream: SimStream, link_path: str | None = None, timing_log=None):
        for name in (link_path, f"{link_path}.new") if link_path else ():
            if os.path.lexists(name) and not is_a_bridge_link(name):
                raise FileExistsError(f"{name} exists and is not a pseudo-terminal link a bridge made: "
                                      "choose a new name for --link")
        self.stream = stream
        self.link_path = link_path
        self.timing_log = timing_log  # a text file: one line per write, "monotonic_ns t_us t_us ..."
        self.bytes_written = 0
        self.bytes_dropped = 0
        self.reconnects = 0
        self._master = self._slave = None
        self.slave_path = ""
        self._open()

    @property
    def path(self) -> str:
        """What a serial program should open."""
        return self.link_path or self.slave_path

    def _open(self) -> None:
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.slave_path = os.ttyname(self._slave)
        if self.link_path:
            temporary = f"{self.link_path}.new"
            if os.path.lexists(temporary):
                os.unlink(temporary)
            os.symlink(self.slave_path, temporary)
            os.replace(temporary, self.link_path)  # atomic: the name never dangles half-made

    def _close(self) -> None:
        if self._master is not None:
            os.close(self._master)
            os.close(self._slave)
            self._master = self._slave = None
            if self.link_path and is_a_bridge_link(self.link_path):
                os.unlink(self.link_path)

    def close(self) -> None:
        self._close()

    def _write(self, data: bytes, stamps: tuple[int, ...]) -> None:
        try:
            n = os.write(self._master, data)
        except BlockingIOError:
            n = 0
        if self.timing_log is not None and n == len(data):
            self.timing_log.write(" ".join(map(str, (time.monotonic_ns(), *stamps))) + "\n")
        self.bytes_written += n
        self.bytes_dropped += len(data) - n

    def run(self, should_stop, duration_s: float | None = None) -> None:
        """Stream in real time until ``should_stop()`` is true or ``duration_s`` (simulated) has passed."""
        stream = self.stream
        link = stream.link.settings
        t0 = time.monotonic()
        while not should_stop():
            now = time.monotonic() - t0
            if duration_s is not None and now >= duration_s:
                break
            up = link.port_is_up(now)
            if up and self._master is None:
                self._open()
                self.reconnects += 1
            elif not up and self._master is not None:
                self._close()
            for chunk in stream.advance(now):
                if self._master is not None:
                    self._write(chunk.data, chunk.t_us)
            timeout = min(max(stream.next_event_s() - (time.monotonic() - t0), 0.0), 0.05)
            if self._master is None:
                time.sleep(timeout)
                continue
            readable, _, _ = select.select([self._master], [], [], timeout)
            if readable:
                try:
                    stream.receive(os.read(self._master, 4096))
                except OSError:
                    pass  # EAGAIN, or EIO while no reader is attached: nothing to read
