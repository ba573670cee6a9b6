"""``open_source(spec)``: the one way to turn a string into a Source.

A spec is what the user types in the app's port field or after ``--port``:

    COM3, /dev/ttyUSB0[?baud=N]        a serial port                     -> serial_port.py
    socket://, rfc2217://, loop://...  any other pyserial URL            -> serial_port.py
    udp://HOST:PORT, tcp://HOST:PORT   a UDP or TCP (Wi-Fi) bridge       -> udp.py, tcp.py
    sim:[?scenario=NAME&seed=N...]     the in-process simulated bridge   -> sim.py
    FILE.gsrec[?speed=X]               a recording, replayed             -> replay.py
    mavlink:...                        an autopilot (MAVLink 1/2)        -> mavlink.py

``SCHEMES`` is the registry: a new input is one module with ``open_spec(spec: Spec) -> Source`` and
one entry here; the ``--port`` helps, the app's source box and the error messages list its forms from
here (``source_forms``, ``accepted_forms``). Strings without a scheme are a recording when they name a
file, else a serial port.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import re
import stat
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple
from urllib.parse import parse_qsl, urlsplit

from groundstation import formats
from groundstation.sources.base import Source, SourceError

class SourceScheme(NamedTuple):
    module: str  # providing open_spec(spec) -> Source
    forms: tuple[str, ...]  # what the user types, the commonest first
    what: str  # what it is, one line


# scheme -> its entry. "serial" and "recording" are also what a string without a scheme is taken for.
SCHEMES: dict[str, SourceScheme] = {
    "serial": SourceScheme("groundstation.sources.serial_port",
                           ("COM3", "/dev/ttyUSB0", "socket://HOST:PORT", "rfc2217://HOST:PORT", "loop://"),
                           "a serial port or any pyserial URL (?baud=N, default 115200)"),
    "udp": SourceScheme("groundstation.sources.udp", ("udp://HOST:PORT",),
                        "a UDP bridge: listen on HOST:PORT (0.0.0.0 for every interface), uplink to the last sender"),
    "tcp": SourceScheme("groundstation.sources.tcp", ("tcp://HOST:PORT",),
                        "a TCP bridge: connect to HOST:PORT, reconnect when it drops"),
    "sim": SourceScheme("groundstation.sources.sim", ("sim:[?scenario=NAME&seed=N&...]",),
                        "the built-in simulated bridge (any bridge-sim option as a parameter)"),
    "mavlink": SourceScheme("groundstation.sources.mavlink",
                            ("mavlink:PORT[?baud=N]", "mavlink:udpin:HOST:PORT", "mavlink:udpout:HOST:PORT",
                             "mavlink:tcp:HOST:PORT", "mavlink:FILE.tlog[?speed=X]"),
                            "an autopilot speaking MAVLink (ArduPilot, PX4): a SiK radio (57600 baud unless ?baud=), SITL "
                            "or a Wi-Fi bridge over UDP or TCP, or a .tlog replayed"),
    "recording": SourceScheme("groundstation.sources.replay", ("FILE.gsrec[?speed=X]",),
                              "a recording, replayed at X times real time (0.25-64, default 1; speed=max: as fast as possible)"),
}
URL = re.compile(r"^(?P<scheme>[A-Za-z][A-Za-z0-9+.-]+):(?P<rest>.*)$", re.DOTALL)  # 2+ letters: C:\ is a path
COM_PORT = re.compile(r"^(\\\\\.\\)?COM\d+$", re.IGNORECASE)


def accepted_forms() -> str:
    """One line per scheme, for error messages and the app's source box."""
    return "".join(f"\n  {', '.join(scheme.forms)}  —  {scheme.what}" for scheme in SCHEMES.values())


def source_forms(commonest: bool = False, but: tuple[str, ...] = ()) -> str:
    """Every form the user may type (``commonest``: each scheme's first two) of the schemes not in ``but``, on
    one line, for help texts."""
    forms = [form for name, scheme in SCHEMES.items() if name not in but
             for form in (scheme.forms[:2] if commonest else scheme.forms)]
    return ", ".join(forms[:-1]) + " or " + forms[-1]


@dataclass(frozen=True)
class Spec:
    """A parsed spec: ``scheme`` (a key of SCHEMES), ``target`` (host:port, device or file; the whole
    URL for pyserial URLs) and the query ``options``; ``defaults`` fill options the user left out."""

    text: str
    scheme: str
    target: str
    options: dict[str, str] = field(default_factory=dict)
    defaults: dict[str, object] = field(default_factory=dict)

    def option(self, name: str, convert, default=None):
        """``options[name]`` through ``convert`` (else the caller's default, else ``default``);
        SourceError naming the option when it does not convert."""
        if name not in self.options:
            return self.defaults.get(name, default)
        try:
            return convert(self.options[name])
        except (TypeError, ValueError) as error:
            raise SourceError(f"{self.text}: bad {name}={self.options[name]!r} ({error})") from None

    def check_options(self, known) -> None:
        unknown = sorted(set(self.options) - set(known))
        if unknown:
            accepted = ", ".join(sorted(known)) or "none"
            raise SourceError(f"{self.text}: unknown option {', '.join(unknown)} (accepted here: {accepted})")

    def host_port(self) -> tuple[str, int]:
        """(host, port) of ``scheme://HOST:PORT``; an empty host is every interface (listening) or localhost."""
        try:
            parts = urlsplit(f"//{self.target}")
            host, port = parts.hostname or "", parts.port
        except ValueError as error:
            raise SourceError(f"{self.text}: bad address ({error}); expected {self.scheme}://HOST:PORT") from None
        if port is None or parts.path:
            raise SourceError(f"{self.text}: expected {self.scheme}://HOST:PORT, e.g. {self.scheme}://192.168.4.1:8888")
        return host, port


def parse_spec(text: str, **defaults) -> Spec:
    """Which kind of source ``text`` names, without opening it; SourceError listing the accepted forms."""
    if not isinstance(text, str) or not text.strip():
        raise SourceError(f"no source given; the accepted forms are:{accepted_forms()}")
    text = text.strip()
    match = URL.match(text)
    if match:
        scheme, rest = match["scheme"].lower(), match["rest"]
        if scheme in SCHEMES and scheme not in ("serial", "recording"):
            target, _, query = rest.removeprefix("//").partition("?")
            return Spec(text, scheme, target, _query(text, query), defaults)
        if _is_pyserial_scheme(scheme):
            return Spec(text, "serial", text, {}, defaults)  # pyserial reads its own URL options
        raise SourceError(f"{text}: unknown source scheme '{scheme}:'; the accepted forms are:{accepted_forms()}")
    # A path or a device name, perhaps with a query (unless the whole string names a file).
    target, query = (text, "") if os.path.exists(text) else text.partition("?")[::2]
    if COM_PORT.match(target) or _is_device(target):
        return Spec(text, "serial", target, _query(text, query), defaults)
    if os.path.isfile(target):
        file_format = formats.sniff(target)
        if file_format is not None and file_format.read is not None:
            raise SourceError(f"{target} is an autopilot's flight log, not a link: open it whole (groundstation app FILE, "
                              "the app's File > Open, or replay, export and evaluate FILE)")
        return Spec(text, "recording", target, _query(text, query), defaults)
    if os.path.isdir(target):
        raise SourceError(f"{target} is a folder; give a recording file (.gsrec) or a port")
    raise SourceError(f"{target}: no such file or serial port (groundstation ports lists the ports); "
                      f"the accepted forms are:{accepted_forms()}")


def whole_file(text: str):
    """The file a spec names when it is to be opened whole (a recording, a flight log, ``mavlink:FILE.tlog``),
    as a ``Path``; None for a link (or no file)."""
    text = text.strip() if isinstance(text, str) else ""
    if text.lower().startswith("mavlink:"):
        text = text[len("mavlink:"):]
    path = text if os.path.exists(text) else text.partition("?")[0]
    return Path(path) if path and os.path.isfile(path) else None


def open_source(text: str, **defaults) -> Source:
    """The Source ``text`` names, opened. ``defaults`` are option values the spec may override
    (``baud=`` from the app's baud box, ``speed=`` from ``replay --speed``). SourceError says why not."""
    spec = parse_spec(text, **defaults)
    module = importlib.import_module(SCHEMES[spec.scheme].module)
    return module.open_spec(spec)


def _query(text: str, query: str) -> dict[str, str]:
    pairs = parse_qsl(query, keep_blank_values=True)
    if query and not pairs:
        raise SourceError(f"{text}: cannot read the options after '?' (expected NAME=VALUE&NAME=VALUE)")
    options: dict[str, str] = {}
    for name, value in pairs:
        name = name.strip().lower().replace("-", "_")
        if name in options:
            raise SourceError(f"{text}: option {name} given twice")
        options[name] = value.strip()
    return options


def _is_pyserial_scheme(scheme: str) -> bool:
    """pyserial finds a URL's handler as PACKAGE.protocol_SCHEME (serial.urlhandler and any added)."""
    import serial

    return scheme.isidentifier() and any(
        importlib.util.find_spec(f"{package}.protocol_{scheme}") is not None for package in serial.protocol_handler_packages)


def _is_device(path: str) -> bool:
    """A character device (a tty), or a name under /dev that is not there right now (unplugged)."""
    try:
        return stat.S_ISCHR(os.stat(path).st_mode)
    except OSError:
        return path.startswith("/dev/")
