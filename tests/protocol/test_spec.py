"""The spec itself: required content, framing limits, and what the fingerprint covers."""

import dataclasses

import pytest

from firmware_protocol import SPEC, load_spec
from firmware_protocol.spec import KNOWN_SPECS, SPEC_PATH, Field, SpecError

REQUIRED = {
    "IMU_RAW": {"t_us", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z", "temperature"},
    "ATTITUDE": {"t_us", "q_w", "q_x", "q_y", "q_z", "lambda_gain", "flags"},
    "CONFIG": {"protocol_version", "schema_fingerprint", "accel_fs_g", "gyro_fs_dps", "rate_hz", "mode", "mounting"},
    "STATUS": {"t_us", "battery", "retransmits", "lost_acks", "cpu_load", "flags"},
    "MAG_RAW": {"t_us", "mag_x", "mag_y", "mag_z"},
    "BARO": {"t_us", "pressure", "temperature"},
    "GPS": {"t_us", "lat", "lon", "alt", "vel_n", "vel_e", "vel_d", "heading", "fix_type", "satellites"},
    "COMMAND": {"command", "param", "value"},
    "ACK": {"command_seq", "command", "result"},
}


@pytest.mark.parametrize("name", REQUIRED)
def test_required_frames_and_fields(name):
    frame_type = SPEC.frame(name)
    assert REQUIRED[name] <= set(frame_type.field_names)
    assert frame_type.payload_size + SPEC.header_bytes + SPEC.crc_bytes <= 32
    for field in frame_type.fields:
        assert field.unit and field.description


def test_gps_position_is_in_1e7_degrees():
    assert SPEC.frame("GPS").fields[1].scale == 1e-7 and SPEC.frame("GPS").fields[1].c_type == "int32_t"


def test_command_enum_covers_the_uplink_actions():
    assert set(SPEC.enums["command"].values) == {"set_mode", "set_filter_param", "request_config", "calibrate_gyro"}
    assert set(SPEC.enums["mode"].values) == {"raw", "estimated", "both"}


def test_fingerprint_tracks_layout_not_wording():
    text = SPEC_PATH.read_text()
    reworded = text.replace('description = "device time of the sample; wraps every 71.6 min"', 'description = "sample time"')
    rescaled = text.replace("scale = 0.15,", "scale = 0.3,")
    assert reworded != text and rescaled != text
    assert load_spec(reworded).fingerprint == SPEC.fingerprint
    assert load_spec(rescaled).fingerprint != SPEC.fingerprint


def test_a_frame_too_big_for_one_radio_payload_is_rejected():
    text = SPEC_PATH.read_text()
    oversized = text.replace(
        '{ name = "satellites", type = "uint8_t"', '{ name = "spare", type = "uint8_t", unit = "1", description = "x" },\n  { name = "satellites", type = "uint8_t"'
    )
    with pytest.raises(SpecError, match="GPS.*exceeds 26"):
        load_spec(oversized)


def test_every_spec_the_project_has_had_is_known_and_ours_decodes_their_frames():
    """known_specs.toml holds this spec (the generator adds it) and the older one of tests/data, which differs
    from ours only by CONFIG's gyro_calibration, appended since: compatible frame for frame."""
    assert KNOWN_SPECS[SPEC.fingerprint] == SPEC.frame_fingerprints
    assert SPEC.changed_frames(0x5B4C2EFE) == ()
    assert SPEC.changed_frames(SPEC.fingerprint ^ 1) is None
    assert "does not know" in SPEC.schema_warning(SPEC.fingerprint ^ 1)


def test_a_frame_fingerprint_covers_base_fields_and_their_enums_not_appended_fields():
    gps = SPEC.frame("GPS")
    grown = dataclasses.replace(gps, fields=gps.fields + (Field("hdop", "uint16_t", "1", "", absent=0xFFFF),))
    assert SPEC.frame_fingerprint(grown) == SPEC.frame_fingerprint(gps)
    renamed = dataclasses.replace(gps, fields=tuple(dataclasses.replace(f, name="sats") if f.name == "satellites" else f
                                                    for f in gps.fields))
    assert SPEC.frame_fingerprint(renamed) != SPEC.frame_fingerprint(gps)
    renumbered = dataclasses.replace(SPEC, enums={**SPEC.enums, "gps_fix": dataclasses.replace(
        SPEC.enums["gps_fix"], values={**SPEC.enums["gps_fix"].values, "rtk": 6})})
    assert renumbered.frame_fingerprint(gps) != SPEC.frame_fingerprint(gps)
    assert renumbered.frame_fingerprint(SPEC.frame("IMU_RAW")) == SPEC.frame_fingerprint(SPEC.frame("IMU_RAW"))
