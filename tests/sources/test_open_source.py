"""open_source(spec): every accepted form opens the right source with the right capabilities, and a
garbled or impossible spec says what is wrong and which forms exist."""

import importlib
import os
import time
from pathlib import Path

import pytest

import firmware_protocol as fp
from groundstation.errors import UserError
from groundstation.recording import open_recording
from groundstation.sim.stream import SimStream
from groundstation.sources import SCHEMES, SourceClosed, SourceError, open_source, parse_spec
from groundstation.sources.sim import parse_scenario

SAMPLE = Path(__file__).resolve().parents[2] / "recordings" / "samples" / "hover-raw.gsrec"


def read_for(source, seconds: float) -> bytes:
    data, end = bytearray(), time.monotonic() + seconds
    while time.monotonic() < end:
        chunk = source.read()
        if chunk is not None:
            data += chunk.data
    return bytes(data)


@pytest.mark.parametrize(("spec", "scheme", "target"), [
    ("COM3", "serial", "COM3"),
    ("com12?baud=57600", "serial", "com12"),
    (r"\\.\COM10", "serial", r"\\.\COM10"),
    ("/dev/ttyUSB0", "serial", "/dev/ttyUSB0"),  # unplugged right now: still a port, not a file
    ("/dev/null", "serial", "/dev/null"),  # a character device
    ("socket://192.168.4.1:23", "serial", "socket://192.168.4.1:23"),
    ("RFC2217://host:2217?logging=debug", "serial", "RFC2217://host:2217?logging=debug"),  # pyserial's own options
    ("udp://0.0.0.0:14550", "udp", "0.0.0.0:14550"),
    ("tcp://192.168.4.1:8888", "tcp", "192.168.4.1:8888"),
    ("sim:", "sim", ""),
    ("SIM:?scenario=hover&seed=3", "sim", ""),
    (f"{SAMPLE}?speed=4", "recording", str(SAMPLE)),
])
def test_each_form_is_recognised_without_opening_it(spec, scheme, target):
    parsed = parse_spec(spec)
    assert (parsed.scheme, parsed.target) == (scheme, target)


def test_every_registered_scheme_has_an_opener_and_is_listed_in_the_error():
    with pytest.raises(SourceError) as error:
        parse_spec("nonsense://x")
    for scheme in SCHEMES.values():
        assert callable(importlib.import_module(scheme.module).open_spec)
        assert ", ".join(scheme.forms) in str(error.value)


@pytest.mark.parametrize(("spec", "message"), [
    ("", "no source given"),
    ("   ", "no source given"),
    ("http://example.com", "unknown source scheme 'http:'"),
    ("no-such-thing", "no such file or serial port"),
    ("missing.gsrec", "no such file or serial port"),
    (".", "is a folder"),
    ("udp://", "expected udp://HOST:PORT"),
    ("udp://127.0.0.1", "expected udp://HOST:PORT"),
    ("udp://127.0.0.1:99999", "bad address"),
    ("udp://127.0.0.1:port", "bad address"),
    ("udp://127.0.0.1:0?remote=nowhere", "expected udp://HOST:PORT"),
    ("udp://127.0.0.1:0?bogus=1", "unknown option bogus"),
    ("udp://no.such.host.invalid:5000", "unknown host"),
    ("tcp://127.0.0.1:1", "cannot open the TCP bridge 127.0.0.1:1"),  # nothing listens on port 1
    ("tcp://127.0.0.1:9?x=1", "unknown option x"),
    ("sim:?scenario=nope", "invalid choice: 'nope'"),
    ("sim:?seed=x", "not an integer: 'x'"),
    ("sim:?seed=1&seed=2", "given twice"),
    ("sim:?duration=-5", "must be positive"),
    ("sim:?sensors=radar", "unknown sensor(s) radar"),
    ("sim:?wings=2", "unknown option wings"),
    ("sim:?scenario", "invalid choice: ''"),
    ("sim:?&&", "cannot read the options"),
    ("/dev/ttyUSB-none", "cannot open serial port /dev/ttyUSB-none"),
    ("/dev/ttyUSB-none?baud=fast", "bad baud='fast'"),
    ("/dev/ttyUSB-none?baud=-9600", "must be positive"),
    ("COM3?parity=odd", "unknown option parity"),
    (f"{SAMPLE}?speed=100", "between 0.25x and 64x"),
    (f"{SAMPLE}?speed=nan", "between 0.25x and 64x"),
    (f"{SAMPLE}?speed=fast", "bad speed='fast'"),
    (f"{SAMPLE}?loop=1", "unknown option loop"),
    (str(Path(__file__)), "is not a groundstation recording"),  # this Python file
])
def test_bad_specs_say_what_is_wrong(spec, message):
    with pytest.raises(UserError) as error:
        open_source(spec).close()
    assert message in str(error.value)


def test_an_imported_dataset_is_not_a_live_source(tmp_path):
    from groundstation.recording import RecordingWriter

    path = tmp_path / "trial.gsrec"
    with RecordingWriter(path, {"source": "dataset"}) as writer:
        writer.write_event(0, {"kind": "note"})
    with pytest.raises(UserError, match="no link data to replay"):
        open_source(str(path))


def test_sim_streams_exactly_the_simulators_bytes_and_answers_uplink():
    spec = "sim:?scenario=hover&seed=4&sensors=&loss=0.02"
    scenario = parse_scenario(parse_spec(spec))
    assert (scenario.profile, scenario.seed, scenario.link.loss, scenario.firmware.gps_rate_hz) == ("hover", 4, 0.02, 0)
    source = open_source(spec)
    assert (source.is_replay, source.can_reopen, source.can_send) == (False, False, True)
    with pytest.raises(SourceError, match="cannot be reopened"):
        source.reopen()
    received = read_for(source, 1.5)
    offline = SimStream(scenario)
    expected = b"".join(c.data for c in offline.advance(60.0))
    assert len(received) > 1000 and expected.startswith(received)  # same seed, same bytes, in real time
    source.write(fp.encode(fp.make_frame("COMMAND", 9, command=fp.SPEC.enums["command"].values["request_config"],
                                         param=0, value=0.0)))
    frames = fp.StreamDecoder().feed(read_for(source, 0.3))
    source.close()
    assert [f["command_seq"] for f in frames if f.name == "ACK"] == [9]
    assert any(f.name == "CONFIG" for f in frames)


def test_sim_defaults_carry_every_aiding_sensor():
    scenario = parse_scenario(parse_spec("sim:"))
    assert scenario.profile == "flight" and scenario.duration_s == 3600.0
    assert all(rate > 0 for rate in (scenario.firmware.mag_rate_hz, scenario.firmware.baro_rate_hz, scenario.firmware.gps_rate_hz))


def test_a_recording_replays_at_its_speed_and_refuses_uplink():
    recording = open_recording(SAMPLE)
    fast = open_source(f"{SAMPLE}?speed=max")
    assert (fast.is_replay, fast.can_reopen, fast.can_send) == (True, False, False)
    chunks = []
    while True:
        try:
            chunk = fast.read()
        except SourceClosed:
            break
        chunks.append(chunk)
    assert [c.t_host_ns for c in chunks] == recording.chunk_t_host_ns.tolist()
    with pytest.raises(SourceError, match="has no uplink"):
        fast.write(b"\xa5")
    assert open_source(str(SAMPLE)).speed == 1.0  # real time unless told
    assert open_source(f"{SAMPLE}?speed=8").speed == 8.0
    assert open_source(str(SAMPLE), speed=None).speed is None  # a caller's default (replay --speed) ...
    assert open_source(f"{SAMPLE}?speed=2", speed=None).speed == 2.0  # ... that the spec overrides


def test_a_pyserial_url_is_a_serial_port_that_sends():
    source = open_source("loop://")
    assert (source.is_replay, source.can_reopen, source.can_send) == (False, True, True)
    source.write(b"\xa5\x01hello")
    assert read_for(source, 0.3) == b"\xa5\x01hello"  # pyserial's loop-back: what is written comes back
    source.reopen()
    source.close()


def test_udp_listens_where_asked():
    source = open_source("udp://127.0.0.1:0")
    try:
        host, port = source.local_address
        assert host == "127.0.0.1" and port > 0
        with pytest.raises(SourceError, match="cannot listen"):
            open_source(f"udp://127.0.0.1:{port}")  # taken
    finally:
        source.close()


def test_a_mavlink_serial_port_takes_the_apps_baud_rate_unless_the_spec_names_one():
    """A SiK radio's 57600 when nothing says otherwise; the app's baud box (or --baud) when set; ?baud= over both."""
    import pty

    from groundstation.sources.mavlink import SIK_BAUD

    master, slave = pty.openpty()
    path = os.ttyname(slave)
    try:
        for spec, defaults, expected in ((f"mavlink:{path}", {}, SIK_BAUD),
                                         (f"mavlink:{path}", {"baud": 921600}, 921600),
                                         (f"mavlink:{path}?baud=115200", {"baud": 921600}, 115200)):
            source = open_source(spec, **defaults)
            try:
                assert source.description.endswith(f"@ {expected} baud"), source.description
            finally:
                source.close()
    finally:
        os.close(master)
        os.close(slave)
