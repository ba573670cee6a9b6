"""The committed C header, golden vectors and protocol document agree with the spec, and C agrees with Python."""

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from firmware_protocol import SPEC, encode, make_frame
from firmware_protocol.generate import HEADER_NAME, generated_files

ROOT = Path(__file__).resolve().parents[2]
HEADER = ROOT / "firmware_protocol" / "c" / HEADER_NAME
GOLDEN = ROOT / "firmware_protocol" / "golden"


def test_committed_outputs_are_not_stale():
    stale = [str(p.relative_to(ROOT)) for p, data in generated_files(ROOT).items() if not p.exists() or p.read_bytes() != data]
    assert not stale, f"regenerate with `python -m firmware_protocol.generate`: {stale}"


def c_literal(field, value) -> str:
    if field.c_type == "float":
        return f"{value!r}f"
    suffix = "u" if field.c_type.startswith("uint") else ""
    if value == -(2**31):
        return "INT32_MIN"
    return f"{value}{suffix}"


def c_program(vectors: dict[str, dict]) -> str:
    lines = ['#include <stdio.h>', '#include <inttypes.h>', f'#include "{HEADER_NAME}"', "", "int main(void) {", "    uint8_t buf[GS_MAX_FRAME_BYTES];", "    size_t n;"]
    for name, vector in vectors.items():
        frame_type = SPEC.frame(name)
        c = name.lower()
        inits = ", ".join(f".{f.name} = {c_literal(f, vector['values'][f.name])}" for f in frame_type.fields)
        golden = ", ".join(f"0x{b:02x}" for b in bytes.fromhex(vector["hex"]))
        lines += [
            "    {",
            f"        gs_{c}_t m = {{ {inits} }}, u;",
            f"        const uint8_t golden[] = {{ {golden} }};",
            f"        n = gs_pack_{c}(buf, {vector['seq']}u, &m);",
            f'        printf("pack {name} ");',
            '        for (size_t i = 0; i < n; i++) printf("%02x", buf[i]);',
            '        printf("\\n");',
            f"        gs_unpack_{c}(golden + GS_HEADER_BYTES, &u);",
            f'        printf("unpack {name}");',
        ]
        for f in frame_type.fields:
            if f.c_type == "float":
                lines.append(f'        printf(" %.17g", (double)u.{f.name});')
            else:
                lines.append(f'        printf(" %lld", (long long)u.{f.name});')
        lines += [
            '        printf("\\n");',
            f'        printf("check {name} %d ", gs_check_frame(golden, sizeof golden));',
            "        uint8_t bad[sizeof golden];",
            "        memcpy(bad, golden, sizeof golden);",
            "        bad[sizeof golden / 2] ^= 0x10;",
            '        printf("%d\\n", gs_check_frame(bad, sizeof bad));',
            "    }",
        ]
    lines += ["    return 0;", "}", ""]
    return "\n".join(lines)


@pytest.fixture(scope="module")
def c_output(tmp_path_factory):
    compiler = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if compiler is None:
        pytest.skip("no C compiler on this machine (cc, gcc or clang): the C header is not checked")
    vectors = {t.name: json.loads((GOLDEN / f"{t.name.lower()}.json").read_text()) for t in SPEC.frames}
    work = tmp_path_factory.mktemp("c")
    (work / "check.c").write_text(c_program(vectors))
    exe = work / "check"
    build = subprocess.run(
        [compiler, "-std=c99", "-Wall", "-Wextra", "-Wconversion", "-Werror", "-I", str(HEADER.parent), str(work / "check.c"), "-o", str(exe)],
        capture_output=True, text=True,
    )
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, check=True)
    return vectors, {tuple(line.split(" ", 2)[:2]): line.split(" ", 2)[2] for line in run.stdout.splitlines()}


@pytest.mark.parametrize("name", [t.name for t in SPEC.frames])
def test_c_packs_the_same_bytes_as_python(c_output, name):
    vectors, out = c_output
    vector = vectors[name]
    python_bytes = encode(make_frame(name, vector["seq"], **vector["values"]))
    assert out[("pack", name)] == python_bytes.hex() == vector["hex"]


@pytest.mark.parametrize("name", [t.name for t in SPEC.frames])
def test_c_unpacks_the_golden_values(c_output, name):
    vectors, out = c_output
    printed = out[("unpack", name)].split()
    for field, text in zip(SPEC.frame(name).fields, printed):
        expected = vectors[name]["values"][field.name]
        assert (float(text) if field.c_type == "float" else int(text)) == expected, field.name


@pytest.mark.parametrize("name", [t.name for t in SPEC.frames])
def test_c_checks_frames(c_output, name):
    _, out = c_output
    good, corrupted = out[("check", name)].split()
    assert int(good) == SPEC.frame(name).payload_size
    assert int(corrupted) == -1
