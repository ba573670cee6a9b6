"""Generate everything that derives from ``spec.toml``: the C header, the golden vectors, docs/protocol.md, and
the current spec's entry in ``known_specs.toml`` (whose older entries it keeps).

    python -m firmware_protocol.generate [--root REPO]

The outputs are committed; ``tests/protocol/test_generated.py`` fails while any is stale.
"""

from __future__ import annotations

import argparse
import json
import random
import struct
from pathlib import Path

from firmware_protocol.codec import encode, make_frame
from firmware_protocol.spec import KNOWN_SPECS_PATH, SPEC, Field, FrameType, Spec, known_specs_text, load_known_specs

PACKAGE_DIR = Path(__file__).parent
HEADER_NAME = "gs_protocol.h"
GENERATED_NOTE = "Generated from firmware_protocol/spec.toml by `python -m firmware_protocol.generate`. Do not edit."


# --- golden vectors -------------------------------------------------------------------------------


def golden_frames(spec: Spec = SPEC) -> dict[str, tuple[bytes, dict]]:
    """One frame per type with values spread over each field's range (deterministic)."""
    vectors = {}
    for frame_type in spec.frames:
        rng = random.Random(frame_type.id)
        values = {field.name: _golden_value(field, rng) for field in frame_type.fields}
        seq = (frame_type.id * 37) & 0xFF
        frame = make_frame(frame_type.name, seq, **values)
        description = {
            "name": frame_type.name,
            "id": frame_type.id,
            "seq": seq,
            "values": values,
            "scaled": frame.scaled(),
            "hex": encode(frame).hex(),
        }
        vectors[frame_type.name] = (encode(frame), description)
    return vectors


def _golden_value(field: Field, rng: random.Random) -> int | float:
    if field.c_type == "float":
        # A float32-exact value, so C and Python agree to the bit.
        return struct.unpack("<f", struct.pack("<f", rng.uniform(-100.0, 100.0)))[0]
    low, high = field.raw_range
    return rng.randint(int(low), int(high))


def golden_files(spec: Spec = SPEC) -> dict[str, bytes]:
    files = {}
    for name, (data, description) in golden_frames(spec).items():
        files[f"{name.lower()}.bin"] = data
        files[f"{name.lower()}.json"] = (json.dumps(description, indent=2) + "\n").encode()
    return files


# --- C header ---------------------------------------------------------------------------------------

_C_PUT = {1: "", 2: "gs_put_u16", 4: "gs_put_u32"}
_C_GET = {1: "", 2: "gs_get_u16", 4: "gs_get_u32"}
_C_UNSIGNED = {1: "uint8_t", 2: "uint16_t", 4: "uint32_t"}

_C_HELPERS = """\
/* CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, no final xor. */
static inline uint16_t gs_crc16(const uint8_t *data, size_t len)
{
    uint16_t crc = 0xFFFFu;
    for (size_t i = 0; i < len; i++) {
        crc ^= (uint16_t)((uint16_t)data[i] << 8);
        for (int bit = 0; bit < 8; bit++) {
            crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
        }
    }
    return crc;
}

/* Little-endian field access, independent of the CPU's byte order. */
static inline void gs_put_u16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }
static inline void gs_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static inline uint16_t gs_get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline uint32_t gs_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline uint32_t gs_float_bits(float f) { uint32_t u; memcpy(&u, &f, sizeof u); return u; }
static inline float gs_bits_float(uint32_t u) { float f; memcpy(&f, &u, sizeof f); return f; }

/* Writes sync, length, type, seq and the CRC (big-endian) around a payload already at
 * out + GS_HEADER_BYTES. Returns the frame's length in bytes. */
static inline size_t gs_finish_frame(uint8_t *out, uint8_t type, uint8_t seq, uint8_t payload_len)
{
    out[0] = GS_SYNC;
    out[1] = payload_len;
    out[2] = type;
    out[3] = seq;
    uint16_t crc = gs_crc16(out + 1, (size_t)GS_HEADER_BYTES - 1u + payload_len);
    out[GS_HEADER_BYTES + payload_len] = (uint8_t)(crc >> 8);
    out[GS_HEADER_BYTES + payload_len + 1] = (uint8_t)crc;
    return (size_t)GS_HEADER_BYTES + payload_len + GS_CRC_BYTES;
}
"""


def _c_name(frame_type: FrameType) -> str:
    return frame_type.name.lower()


def _c_pack_statement(field: Field, offset: int) -> str:
    size = field.size
    value = f"m->{field.name}"
    if field.c_type == "float":
        return f"    gs_put_u32(p + {offset}, gs_float_bits({value}));"
    if size == 1:
        return f"    p[{offset}] = (uint8_t){value};"
    return f"    {_C_PUT[size]}(p + {offset}, ({_C_UNSIGNED[size]}){value});"


def _c_unpack_statement(field: Field, offset: int) -> str:
    size = field.size
    if field.c_type == "float":
        return f"    m->{field.name} = gs_bits_float(gs_get_u32(p + {offset}));"
    if size == 1:
        return f"    m->{field.name} = ({field.c_type})p[{offset}];"
    return f"    m->{field.name} = ({field.c_type}){_C_GET[size]}(p + {offset});"


def c_header(spec: Spec = SPEC) -> str:
    lines = [
        f"/* {GENERATED_NOTE} */",
        "/* Telemetry frames for the nRF24L01 link: sync | length | type | seq | payload | crc16 (see docs/protocol.md). */",
        "#ifndef GS_PROTOCOL_H",
        "#define GS_PROTOCOL_H",
        "",
        "#include <stddef.h>",
        "#include <stdint.h>",
        "#include <string.h>",
        "",
        f"#define GS_PROTOCOL_VERSION {spec.protocol_version}u",
        f"#define GS_SCHEMA_FINGERPRINT 0x{spec.fingerprint:08X}u",
        f"#define GS_SYNC 0x{spec.sync:02X}u",
        f"#define GS_MAX_FRAME_BYTES {spec.max_frame_bytes}u",
        f"#define GS_HEADER_BYTES {spec.header_bytes}u",
        f"#define GS_CRC_BYTES {spec.crc_bytes}u",
        "",
    ]
    for enum in spec.enums.values():
        lines.append(f"/* {enum.name}: {enum.description} */")
        lines += [f"#define GS_{enum.name.upper()}_{key.upper()} {value}u" for key, value in enum.values.items()]
        lines.append("")
    for frame_type in spec.frames:
        upper = frame_type.name
        lines.append(f"#define GS_ID_{upper} 0x{frame_type.id:02X}u")
        lines.append(f"#define GS_PAYLOAD_{upper} {frame_type.payload_size}u")
        # physical value = raw * scale, in the field's unit
        lines += [f"#define GS_SCALE_{upper}_{f.name.upper()} {f.scale!r}" for f in frame_type.fields if f.scale != 1.0]
    lines += ["", _C_HELPERS]
    for frame_type in spec.frames:
        lines += _c_frame_block(spec, frame_type)
    lines += _c_payload_size_function(spec)
    lines += ["#endif /* GS_PROTOCOL_H */", ""]
    return "\n".join(lines)


def _c_frame_block(spec: Spec, frame_type: FrameType) -> list[str]:
    name = _c_name(frame_type)
    lines = [f"/* {frame_type.name} (0x{frame_type.id:02X}, {frame_type.direction}, frame fingerprint "
             f"0x{spec.frame_fingerprint(frame_type):08X}): {frame_type.description} */", "typedef struct {"]
    for field in frame_type.fields:
        scale = "" if field.scale == 1.0 else f" x {field.scale!r}"
        lines.append(f"    {field.c_type} {field.name}; /* {field.unit}{scale}: {field.description} */")
    lines.append(f"}} gs_{name}_t;")
    lines.append("")
    lines.append("/* Packs m into out (room for GS_MAX_FRAME_BYTES); returns the frame's length. */")
    lines.append(f"static inline size_t gs_pack_{name}(uint8_t *out, uint8_t seq, const gs_{name}_t *m)")
    lines.append("{")
    lines.append("    uint8_t *p = out + GS_HEADER_BYTES;")
    offset = 0
    for field in frame_type.fields:
        lines.append(_c_pack_statement(field, offset))
        offset += field.size
    lines.append(f"    return gs_finish_frame(out, GS_ID_{frame_type.name}, seq, GS_PAYLOAD_{frame_type.name});")
    lines.append("}")
    lines.append("")
    lines.append("/* Reads the payload (out + GS_HEADER_BYTES of a checked frame) into m. */")
    lines.append(f"static inline void gs_unpack_{name}(const uint8_t *p, gs_{name}_t *m)")
    lines.append("{")
    offset = 0
    for field in frame_type.fields:
        lines.append(_c_unpack_statement(field, offset))
        offset += field.size
    lines += ["}", ""]
    return lines


def _c_payload_size_function(spec: Spec) -> list[str]:
    lines = [
        "/* The payload length of a known frame type, or -1 for a type this spec lacks. */",
        "static inline int gs_payload_size(uint8_t type)",
        "{",
        "    switch (type) {",
    ]
    lines += [f"    case GS_ID_{t.name}: return (int)GS_PAYLOAD_{t.name};" for t in spec.frames]
    lines += [
        "    default: return -1;",
        "    }",
        "}",
        "",
        "/* Checks a complete frame of len bytes: sync, length, known type, CRC. Returns its payload",
        " * length, or -1 when it is not an intact frame of a known type. */",
        "static inline int gs_check_frame(const uint8_t *frame, size_t len)",
        "{",
        "    if (len < GS_HEADER_BYTES + GS_CRC_BYTES || frame[0] != GS_SYNC) return -1;",
        "    int size = gs_payload_size(frame[2]);",
        "    if (size < 0 || frame[1] != (uint8_t)size || len != (size_t)size + GS_HEADER_BYTES + GS_CRC_BYTES) return -1;",
        "    uint16_t crc = gs_crc16(frame + 1, (size_t)GS_HEADER_BYTES - 1u + (size_t)size);",
        "    if (frame[len - 2] != (uint8_t)(crc >> 8) || frame[len - 1] != (uint8_t)crc) return -1;",
        "    return size;",
        "}",
        "",
    ]
    return lines


# --- docs/protocol.md -------------------------------------------------------------------------------


def _absent_note(spec: Spec, field: Field) -> str:
    if field.absent is None:
        return ""
    name = f" (`{spec.enum_name(field, field.absent)}`)" if field.enum else ""
    return f"; appended later: reads as {field.absent!r}{name} from an older sender"


def protocol_markdown(spec: Spec = SPEC) -> str:
    golden = golden_frames(spec)
    out = [
        "# Telemetry wire protocol",
        "",
        f"<!-- {GENERATED_NOTE} -->",
        "",
        f"Protocol version {spec.protocol_version}; schema fingerprint `0x{spec.fingerprint:08X}` "
        "(CRC-32 of the spec's names, ids, types, scales and enums, carried in `CONFIG` so that a firmware built "
        "from another spec is reported instead of silently mis-decoded).",
        "",
        "Compatibility is checked per frame type, as MAVLink checks each message against its `crc_extra`: a frame "
        "type's fingerprint (in its section below) covers its name, id and base fields, not the fields appended "
        "later, so adding a frame type or growing one at its end leaves older firmware and recordings compatible. "
        "`firmware_protocol/known_specs.toml` (generated, only ever added to) holds the frame fingerprints of every "
        "schema fingerprint this project has had; a ground station warns only of the frame types a firmware's spec "
        "has otherwise, by name, or of a spec it does not know (newer, or another project's).",
        "",
        "## Framing",
        "",
        f"Every frame fits one nRF24L01+ payload ({spec.max_frame_bytes} bytes):",
        "",
        "| offset | size | content |",
        "|---|---|---|",
        f"| 0 | 1 | sync `0x{spec.sync:02X}` |",
        "| 1 | 1 | payload length in bytes (per type: this version's, or an older sender's shorter one) |",
        "| 2 | 1 | frame type id |",
        "| 3 | 1 | sequence counter, +1 per frame sent, wraps at 256 (one counter per direction) |",
        f"| 4 | n | payload (at most {spec.max_payload_bytes} bytes), fields little-endian |",
        "| 4 + n | 2 | CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF) of bytes 1 .. 3 + n, high byte first |",
        "",
        "Because the CRC is sent high byte first, the CRC of bytes 1 .. 5 + n of an intact frame is zero. "
        "A field's physical value is `raw * scale` in the field's unit. Device timestamps `t_us` are 32-bit "
        "microseconds that wrap every 71.6 minutes; the decoder unwraps them into a 64-bit monotonic time.",
        "",
        "The decoder resynchronises on the sync byte. A candidate with an impossible length for its type, or a "
        "failed CRC, gives up only its sync byte, so a damaged frame never hides the intact frame after it. "
        "A frame repeated byte for byte is dropped as a duplicate; gaps in the sequence counter count as lost frames.",
        "",
        "A frame type grows only at its end. A field appended after the type was first sent has an *absent* "
        "value: a payload from an older sender that ends before the field (at a field boundary) is still read, "
        "and the field reads as that value (for an enum, one that is none of its members: unknown). The frame table "
        "lists every payload length a type may have.",
        "",
        "## Frames",
        "",
        "| id | frame | direction | payload bytes | frame bytes |",
        "|---|---|---|---|---|",
    ]
    for t in spec.frames:
        direction = "aircraft → ground" if t.direction == "down" else "ground → aircraft"
        sizes = sorted(t.readers)
        payload = ", ".join(map(str, sizes))
        frame_bytes = ", ".join(str(size + spec.header_bytes + spec.crc_bytes) for size in sizes)
        out.append(f"| 0x{t.id:02X} | [`{t.name}`](#{t.name.lower()}) | {direction} | {payload} | {frame_bytes} |")
    for t in spec.frames:
        out += ["", f"### {t.name}", "", t.description, "", f"Frame fingerprint `0x{spec.frame_fingerprint(t):08X}`.", "",
                "| offset | field | C type | scale | unit | description |", "|---|---|---|---|---|---|"]
        offset = spec.header_bytes
        for f in t.fields:
            description = f.description + (f" (enum `{f.enum}`)" if f.enum else "") + _absent_note(spec, f)
            out.append(f"| {offset} | `{f.name}` | `{f.c_type}` | {f.scale!r} | {f.unit} | {description} |")
            offset += f.size
        out += ["", f"Golden vector (`firmware_protocol/golden/{t.name.lower()}.bin`): `{golden[t.name][1]['hex']}`"]
    out += ["", "## Enums", ""]
    for enum in spec.enums.values():
        out += [f"### {enum.name}", "", enum.description, "", "| name | value |", "|---|---|"]
        out += [f"| `{k}` | {v} |" for k, v in enum.values.items()]
        out.append("")
    out += [
        "## C",
        "",
        f"`firmware_protocol/c/{HEADER_NAME}` is header-only C99: a struct per frame, `gs_pack_<frame>()` writing a "
        "whole frame, `gs_unpack_<frame>()` reading a payload, `gs_check_frame()` and `gs_crc16()`, and "
        "`GS_SCALE_<FRAME>_<FIELD>` for every field with a scale. "
        "It does not depend on the CPU's byte order or struct packing.",
        "",
    ]
    return "\n".join(out)


# --- writing -------------------------------------------------------------------------------------


def generated_files(root: Path, spec: Spec = SPEC) -> dict[Path, bytes]:
    """Every generated file, by its path under the repository root ``root``."""
    files = {root / "firmware_protocol" / "c" / HEADER_NAME: c_header(spec).encode()}
    files.update({root / "firmware_protocol" / "golden" / name: data for name, data in golden_files(spec).items()})
    files[root / "docs" / "protocol.md"] = protocol_markdown(spec).encode()
    known_path = root / "firmware_protocol" / KNOWN_SPECS_PATH.name
    known = load_known_specs(known_path)
    known[spec.fingerprint] = spec.frame_fingerprints  # replaced: fields marked absent later keep the spec's fingerprint
    files[known_path] = known_specs_text(known).encode()
    return files


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=PACKAGE_DIR.parent, help="repository root (default: this checkout)")
    args = parser.parse_args(argv)
    if not (args.root / "pyproject.toml").exists():
        parser.error(f"{args.root} is not the repository root (no pyproject.toml); pass --root")
    for path, data in generated_files(args.root).items():
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.exists() or path.read_bytes() != data:
            path.write_bytes(data)
            print(f"wrote {path.relative_to(args.root)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
