"""The protocol spec (``spec.toml``) loaded and checked: frame types, fields, enums, fingerprints.

Everything else in the package (codec, decoder, C and document generators) reads the spec through
this module, so a field added to ``spec.toml`` reaches every output at once.

Compatibility is checked per frame type, as MAVLink checks each message against its ``crc_extra``: a
frame type's fingerprint covers its name, id and base fields (the fields every version sends), not the
fields appended later (``absent``), so adding a frame type or growing one at its end leaves every other
frame type's fingerprint, and so every older firmware and recording, compatible. The firmware sends one
number, the whole spec's ``fingerprint`` (``CONFIG.schema_fingerprint``); ``known_specs.toml`` (generated,
only ever added to) says which frame fingerprints each spec this project has had is made of, so the
ground station names the frame types that differ (``Spec.changed_frames``).
"""

from __future__ import annotations

import struct
import tomllib
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

# C type -> (struct format character, size in bytes, smallest raw value, largest raw value)
C_TYPES: dict[str, tuple[str, int, float, float]] = {
    "uint8_t": ("B", 1, 0, 2**8 - 1),
    "int8_t": ("b", 1, -(2**7), 2**7 - 1),
    "uint16_t": ("H", 2, 0, 2**16 - 1),
    "int16_t": ("h", 2, -(2**15), 2**15 - 1),
    "uint32_t": ("I", 4, 0, 2**32 - 1),
    "int32_t": ("i", 4, -(2**31), 2**31 - 1),
    "float": ("f", 4, -3.4028234663852886e38, 3.4028234663852886e38),
}

TIMESTAMP_FIELD = "t_us"
ABSENT_KEY = "absent"  # spec.toml: the field was appended later, and reads as this where an older sender left it out
ABSENT_NAME = "unknown"  # what an absent enum field is called
SPEC_PATH = Path(__file__).with_name("spec.toml")
KNOWN_SPECS_PATH = Path(__file__).with_name("known_specs.toml")


class SpecError(ValueError):
    """The spec file contradicts itself or the framing limits."""


@dataclass(frozen=True)
class Field:
    name: str
    c_type: str
    unit: str
    description: str
    scale: float = 1.0
    enum: str | None = None
    absent: int | float | None = None  # raw value read where an older sender's payload ends before the field; None: always sent

    @property
    def size(self) -> int:
        return C_TYPES[self.c_type][1]

    @property
    def raw_range(self) -> tuple[float, float]:
        return C_TYPES[self.c_type][2], C_TYPES[self.c_type][3]


@dataclass(frozen=True)
class FrameType:
    name: str
    id: int
    direction: str  # "down": aircraft -> ground; "up": ground -> aircraft
    description: str
    fields: tuple[Field, ...]

    @property
    def field_names(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.fields)

    @cached_property  # made once: the encoder packs with it a hundred times a second
    def struct(self) -> struct.Struct:
        return struct.Struct("<" + "".join(C_TYPES[f.c_type][0] for f in self.fields))

    @property
    def payload_size(self) -> int:
        return sum(f.size for f in self.fields)

    @property
    def has_timestamp(self) -> bool:
        return bool(self.fields) and self.fields[0].name == TIMESTAMP_FIELD

    def field(self, name: str) -> Field:
        return self.fields[self.field_names.index(name)]

    @cached_property
    def readers(self) -> dict[int, Callable[[bytes, int], tuple]]:
        """Payload length -> ``read(data, offset)``: the raw values in field order. A frame type grows
        only at its end, so besides this version's payload every older one is read: a payload that ends
        at a field boundary after the last field every version sends, the fields it lacks read as their
        ``absent`` value. Both decoders read payloads through this table (one rule)."""
        readers = {self.payload_size: self.struct.unpack_from}
        size = self.payload_size
        for count in range(len(self.fields) - 1, -1, -1):
            if self.fields[count].absent is None:
                break
            size -= self.fields[count].size
            readers[size] = _older_reader(self.fields[:count], tuple(f.absent for f in self.fields[count:]))
        return readers


def _older_reader(sent: tuple[Field, ...], absent: tuple) -> Callable[[bytes, int], tuple]:
    unpack_from = struct.Struct("<" + "".join(C_TYPES[f.c_type][0] for f in sent)).unpack_from
    return lambda data, offset: unpack_from(data, offset) + absent


@dataclass(frozen=True)
class Enum:
    name: str
    description: str
    values: dict[str, int]

    def name_of(self, value: int, absent: int | None = None) -> str:
        """The member name of a raw value; ``unknown`` for the field's ``absent`` value (an older sender
        left the field out); a value the spec lacks: the number, said so."""
        if absent is not None and value == absent:
            return ABSENT_NAME
        for name, member in self.values.items():
            if member == value:
                return name
        return f"{value} (not in the spec)"


@dataclass(frozen=True)
class Spec:
    protocol_version: int
    sync: int
    max_frame_bytes: int
    header_bytes: int
    crc_bytes: int
    enums: dict[str, Enum]
    frames: tuple[FrameType, ...]

    @property
    def max_payload_bytes(self) -> int:
        return self.max_frame_bytes - self.header_bytes - self.crc_bytes

    def enum_name(self, field: Field, raw: int) -> str:
        """An enum field's raw value by name (``unknown`` where an older sender left the field out)."""
        return self.enums[field.enum].name_of(raw, field.absent)

    def frame(self, name: str) -> FrameType:
        for frame_type in self.frames:
            if frame_type.name == name:
                return frame_type
        raise KeyError(f"no frame type {name!r} in the protocol spec")

    @property
    def fingerprint(self) -> int:
        """CRC-32 of everything that decides how bytes decode: the spec as a whole, what the firmware sends
        in ``CONFIG`` and the key of ``known_specs.toml`` (compatibility is per frame type: ``changed_frames``).

        Names, ids, types, scales and enum values count; units and descriptions do not, so
        a documentation change does not make old firmware incompatible. Nor does ``absent``: what an older
        sender's shorter payload reads as changes nothing a sender built from this spec sends.
        """
        parts = [f"v{self.protocol_version} sync{self.sync}"]
        for enum in self.enums.values():
            parts.append(_enum_line(enum))
        for frame_type in self.frames:
            parts.append(f"frame {frame_type.name} {frame_type.id}")
            parts += [_field_line(f) for f in frame_type.fields]
        return zlib.crc32("\n".join(parts).encode())

    def frame_fingerprint(self, frame_type: FrameType) -> int:
        """CRC-32 of what decides how one frame type's bytes decode, as MAVLink's ``crc_extra``: its name, id
        and base fields (types, names, scales, the values of their enums); fields appended later (``absent``)
        are left out, so a frame type grown at its end stays compatible with its older senders."""
        base = [f for f in frame_type.fields if f.absent is None]
        parts = [f"frame {frame_type.name} {frame_type.id}", *map(_field_line, base)]
        parts += [_enum_line(self.enums[name]) for name in dict.fromkeys(f.enum for f in base if f.enum)]
        return zlib.crc32("\n".join(parts).encode())

    @cached_property
    def frame_fingerprints(self) -> dict[str, tuple[int, int]]:
        """Frame type name -> (id, ``frame_fingerprint``): this spec's entry in ``known_specs.toml``."""
        return {t.name: (t.id, self.frame_fingerprint(t)) for t in self.frames}

    def changed_frames(self, remote: int) -> tuple[str, ...] | None:
        """The names of this spec's frame types that firmware built from the spec whose ``fingerprint`` is
        ``remote`` sends otherwise: () when none (frame types added since, or grown at their end, are
        compatible), None when ``remote`` is no spec this project has had (``known_specs.toml``: newer
        firmware, or another project's)."""
        if remote == self.fingerprint:
            return ()
        if remote not in KNOWN_SPECS:
            return None
        theirs = dict(KNOWN_SPECS[remote].values())  # id -> frame fingerprint
        return tuple(name for name, (type_id, frame) in self.frame_fingerprints.items()
                     if type_id in theirs and theirs[type_id] != frame)

    def schema_warning(self, remote: int) -> str | None:
        """What a ground station built from this spec says of a CONFIG whose firmware was built from the
        spec ``remote``; None when every frame type they share decodes alike (the one wording everywhere)."""
        changed = self.changed_frames(remote)
        if changed == ():
            return None
        built = f"the firmware was built from another protocol spec (schema fingerprint 0x{remote:08X})"
        if changed is None:
            return f"{built}, one this ground station does not know (newer, or another project's): its frames may be mis-decoded"
        return f"{built} whose {', '.join(changed)} differ from this ground station's: those frames may be mis-decoded"


def _enum_line(enum: Enum) -> str:
    return f"enum {enum.name} " + " ".join(f"{k}={v}" for k, v in enum.values.items())


def _field_line(field: Field) -> str:
    return f"  {field.c_type} {field.name} {field.scale!r} {field.enum}"


def known_specs_text(known: dict[int, dict[str, tuple[int, int]]]) -> str:
    """``known_specs.toml``: each spec's fingerprint -> its frame types' (id, fingerprint) by name, oldest first."""
    lines = ["# Generated by `python -m firmware_protocol.generate`, which adds the current spec and never removes one:",
             "# every spec this project has had, by its schema fingerprint (what CONFIG carries), with each of its frame",
             "# types' [id, fingerprint] (firmware_protocol/spec.py, Spec.frame_fingerprint). A ground station compares",
             "# a firmware's frame types with its own through this table (Spec.changed_frames). An entry of a spec that",
             "# was never committed (generated between two edits) may be deleted by hand; any other must stay."]
    for fingerprint, frames in known.items():
        lines += ["", f'["0x{fingerprint:08X}"]']
        lines += [f"{name} = [0x{type_id:02X}, 0x{frame:08X}]" for name, (type_id, frame) in frames.items()]
    return "\n".join(lines) + "\n"


def load_known_specs(path: Path = KNOWN_SPECS_PATH) -> dict[int, dict[str, tuple[int, int]]]:
    document = tomllib.loads(path.read_text(encoding="utf-8")) if path.exists() else {}
    return {int(key, 16): {name: tuple(entry) for name, entry in frames.items()} for key, frames in document.items()}


def _parse(document: dict) -> Spec:
    framing = document["framing"]
    enums = {
        name: Enum(name, table.get("description", ""), {k: v for k, v in table.items() if k != "description"})
        for name, table in document.get("enums", {}).items()
    }
    frames = tuple(
        FrameType(
            name=entry["name"],
            id=entry["id"],
            direction=entry["direction"],
            description=entry["description"],
            fields=tuple(
                Field(f["name"], f["type"], f["unit"], f["description"], float(f.get("scale", 1.0)), f.get("enum"), f.get(ABSENT_KEY))
                for f in entry["fields"]
            ),
        )
        for entry in document["frames"]
    )
    spec = Spec(
        protocol_version=framing["protocol_version"],
        sync=framing["sync"],
        max_frame_bytes=framing["max_frame_bytes"],
        header_bytes=framing["header_bytes"],
        crc_bytes=framing["crc_bytes"],
        enums=enums,
        frames=frames,
    )
    _check(spec)
    return spec


def _check(spec: Spec) -> None:
    seen_ids: set[int] = set()
    seen_names: set[str] = set()
    for frame_type in spec.frames:
        if frame_type.id in seen_ids or frame_type.name in seen_names:
            raise SpecError(f"frame {frame_type.name}: duplicate name or id {frame_type.id}")
        if not 0 <= frame_type.id <= 255:
            raise SpecError(f"frame {frame_type.name}: id {frame_type.id} does not fit one byte")
        if frame_type.direction not in ("up", "down"):
            raise SpecError(f"frame {frame_type.name}: direction must be 'up' or 'down'")
        seen_ids.add(frame_type.id)
        seen_names.add(frame_type.name)
        if frame_type.payload_size > spec.max_payload_bytes:
            raise SpecError(
                f"frame {frame_type.name}: payload of {frame_type.payload_size} bytes exceeds "
                f"{spec.max_payload_bytes} (a {spec.max_frame_bytes}-byte radio payload)"
            )
        for field in frame_type.fields:
            if field.c_type not in C_TYPES:
                raise SpecError(f"{frame_type.name}.{field.name}: unknown C type {field.c_type}")
            if field.enum is not None and field.enum not in spec.enums:
                raise SpecError(f"{frame_type.name}.{field.name}: unknown enum {field.enum}")
            if field.absent is not None and field.c_type != "float" and not (
                    isinstance(field.absent, int) and field.raw_range[0] <= field.absent <= field.raw_range[1]):
                raise SpecError(f"{frame_type.name}.{field.name}: absent = {field.absent!r} is not a {field.c_type}")
            if field.absent is not None and field.enum is not None and field.absent in spec.enums[field.enum].values.values():
                raise SpecError(f"{frame_type.name}.{field.name}: absent = {field.absent} is a member of its enum, "
                                "so a field left out would read as one")
        appended = [field.absent is not None for field in frame_type.fields]
        if any(appended) and (appended[0] or appended != sorted(appended)):
            raise SpecError(f"frame {frame_type.name}: a field with '{ABSENT_KEY}' (appended later) must come after "
                            "every field that is always sent, and the first field is always sent")


def load_spec(text: str | None = None) -> Spec:
    """Parse the packaged ``spec.toml`` (or ``text``, for tests of the checks)."""
    if text is None:
        text = SPEC_PATH.read_text(encoding="utf-8")
    return _parse(tomllib.loads(text))


SPEC = load_spec()
KNOWN_SPECS = load_known_specs()
