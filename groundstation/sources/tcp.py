"""``tcp://HOST:PORT``: a TCP bridge (an ESP32 or other Wi-Fi serial bridge serving the radio's bytes).

The ground station connects to HOST:PORT; uplink goes back on the same connection. When the bridge
drops the connection (it rebooted, Wi-Fi faded) the session reconnects as it does for an unplugged
USB adapter. The socket is pyserial's ``socket://`` handler, so it behaves as every serial port does.
"""

from __future__ import annotations

from groundstation.sources.serial_port import SerialSource


def open_spec(spec) -> SerialSource:
    spec.check_options(())
    host, port = spec.host_port()
    host = host or "localhost"
    address = f"[{host}]:{port}" if ":" in host else f"{host}:{port}"  # an IPv6 address keeps its brackets
    return SerialSource(f"socket://{address}", description=f"TCP bridge {address}")
