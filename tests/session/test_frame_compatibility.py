"""Compatibility per frame type (MAVLink's crc_extra): a recording made before the spec gained a frame type,
or before a frame type grew at its end, opens silent; one whose frame type's base fields changed since
warns, naming that frame type."""

import dataclasses
from pathlib import Path

from firmware_protocol import SPEC
from firmware_protocol.spec import Field, FrameType
from groundstation.recording import open_recording
from groundstation.session_makers.pipeline import Pipeline

OLDER = Path(__file__).resolve().parents[2] / "recordings" / "samples" / "flight-both-lossy.gsrec"
SCHEMA_WORDS = "protocol spec"


def replaced(spec, name: str, **changes):
    return dataclasses.replace(spec, frames=tuple(dataclasses.replace(t, **changes) if t.name == name else t
                                                  for t in spec.frames))


def grown_spec():
    """This spec with a frame type more and STATUS grown at its end (a field older senders leave out)."""
    free_id = min(set(range(1, 256)) - {t.id for t in SPEC.frames})
    esc = FrameType("ESC", free_id, "down", "motor telemetry", (
        Field("t_us", "uint32_t", "us", "device time"), Field("rpm", "uint16_t", "rpm", "motor speed")))
    grown = replaced(SPEC, "STATUS", fields=SPEC.frame("STATUS").fields + (
        Field("esc_count", "uint8_t", "1", "motor controllers seen", absent=255),))
    return dataclasses.replace(grown, frames=grown.frames + (esc,))


def schema_warnings(spec) -> list[str]:
    """The schema warnings of the older recording's first seconds, opened by a ground station built from ``spec``."""
    pipeline = Pipeline(("ahf",), spec=spec)
    for k, (t_host_ns, data) in enumerate(open_recording(OLDER).chunks()):
        if k == 300:
            break
        pipeline.feed(t_host_ns, data)
    assert pipeline.config is not None
    return [e["message"] for e in pipeline.events if e["kind"] == "warning" and SCHEMA_WORDS in e["message"]]


def test_a_frame_type_added_or_grown_at_its_end_leaves_an_older_recording_silent():
    spec = grown_spec()
    assert spec.fingerprint != SPEC.fingerprint  # the spec as a whole did change
    assert schema_warnings(spec) == []


def test_a_frame_type_whose_base_fields_changed_warns_naming_it():
    baro = SPEC.frame("BARO")
    rescaled = tuple(dataclasses.replace(f, scale=0.1) if f.name == "pressure" else f for f in baro.fields)
    spec = replaced(grown_spec(), "BARO", fields=rescaled)
    (warning,) = schema_warnings(spec)
    assert "BARO" in warning and "STATUS" not in warning and "ESC" not in warning
