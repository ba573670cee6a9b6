"""The reference firmware built for the Cortex-M3 (``arm-none-eabi-gcc``), and the core's AHF run on an
emulated Cortex-M3 (``qemu-system-arm -M lm3s6965evb``, semihosting): what ``bench/bench_firmware.py``
reports and ``tests/firmware/test_fw_cross.py`` checks. Everything is built into a directory the
caller gives (a temporary one), never into the source tree.
"""

from __future__ import annotations

import dataclasses
import math
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np

from firmware_protocol.reference import host

REFERENCE_DIR = Path(__file__).parent
STM32_DIR = REFERENCE_DIR / "stm32"
QEMU_DIR = REFERENCE_DIR / "qemu"
CROSS_CFLAGS = ("-mcpu=cortex-m3", "-mthumb", "-std=c99", "-Wall", "-Wextra", "-Werror", "-ffp-contract=off",
                "-ffunction-sections", "-fdata-sections")
CROSS_LDFLAGS = ("-nostartfiles", "--specs=nano.specs", "--specs=nosys.specs", "-Wl,--gc-sections", "-lm")
STM32F103C8_FLASH_BYTES, STM32F103C8_RAM_BYTES = 64 * 1024, 20 * 1024


def toolchain() -> str | None:
    return shutil.which("arm-none-eabi-gcc")


def emulator() -> str | None:
    return shutil.which("qemu-system-arm")


@dataclasses.dataclass(frozen=True)
class ImageSize:
    text: int
    data: int
    bss: int

    @property
    def flash_bytes(self) -> int:
        return self.text + self.data  # code and constants, plus the initial values of .data

    @property
    def static_ram_bytes(self) -> int:
        return self.data + self.bss  # the stack takes what is left


def _run(command: list[str], **kwargs) -> subprocess.CompletedProcess:
    result = subprocess.run(command, capture_output=True, text=True, **kwargs)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed:\n{result.stdout}\n{result.stderr}")
    return result


def build_images(build_dir: Path) -> dict[str, ImageSize]:
    """flight.elf/.bin and bridge.elf/.bin with the port's Makefile; their sizes (arm-none-eabi-size)."""
    _run(["make", "-s", "-C", str(STM32_DIR), f"BUILD={build_dir}", "all"])
    sizes = {}
    for name in ("flight", "bridge"):
        out = _run(["arm-none-eabi-size", str(build_dir / f"{name}.elf")]).stdout.splitlines()
        text, data, bss = (int(v) for v in out[1].split()[:3])
        sizes[name] = ImageSize(text, data, bss)
    return sizes


def _input_header(settings, gyr_rad_s, acc_g, dt_s) -> str:
    """ahf_input.h: the settings (an ``AhfSettings``; its fields are the C struct's) and the samples as float bits."""
    values = {field.name: getattr(settings, field.name) for field in dataclasses.fields(settings)}
    literals = ", ".join(f".{name} = {'HUGE_VAL' if value == math.inf else float(value).hex()}" for name, value in values.items())
    rows = np.column_stack([np.asarray(gyr_rad_s), np.asarray(acc_g), np.asarray(dt_s)]).astype(np.float32).view(np.uint32)
    lines = ["static const gs_ahf_settings gs_settings = {" + literals + "};",
             f"#define GS_INPUT_SAMPLES {len(rows)}u", "static const uint32_t gs_input[GS_INPUT_SAMPLES][7] = {"]
    lines += ["    {" + ", ".join(f"0x{v:08x}u" for v in row) + "}," for row in rows.tolist()]
    return "\n".join([*lines, "};", ""])


def build_ahf_program(settings, gyr_rad_s, acc_g, dt_s, build_dir: Path) -> Path:
    """The QEMU program (qemu/ahf_qemu.c + core/gs_ahf.c, -Os as the board's) with these settings and samples
    compiled in."""
    build_dir.mkdir(parents=True, exist_ok=True)
    (build_dir / "ahf_input.h").write_text(_input_header(settings, gyr_rad_s, acc_g, dt_s))
    elf = build_dir / "ahf.elf"
    _run(["arm-none-eabi-gcc", *CROSS_CFLAGS, "-Os", "-I", str(build_dir), "-I", str(host.CORE_DIR),
          str(QEMU_DIR / "ahf_qemu.c"), str(host.CORE_DIR / "gs_ahf.c"), "-o", str(elf), f"-T{QEMU_DIR / 'lm3s6965.ld'}", *CROSS_LDFLAGS])
    return elf


def _qemu(elf: Path, *extra: str, timeout_s: float = 300.0) -> str:
    """What the program wrote over semihosting (QEMU puts it on its stderr, beside its own messages)."""
    command = ["qemu-system-arm", "-M", "lm3s6965evb", "-nographic", "-monitor", "none", "-serial", "none",
               "-semihosting-config", "enable=on,target=native", "-kernel", str(elf), *extra]
    return _run(command, timeout=timeout_s, stdin=subprocess.DEVNULL).stderr


_OUTPUT_LINE = re.compile(r"[0-9a-f]{8}( [0-9a-f]{8}){8}")


def row(status: int, *outputs) -> tuple[int, ...]:
    """One sample as ``run_ahf`` gives it, from the outputs as floats: the status, then the float32 bits of
    q_w, q_x, q_y, q_z, lambda, e_a, err and acc_dev (ahf_qemu.c's line)."""
    return (int(status), *np.array(outputs, dtype=np.float32).view(np.uint32).tolist())


def model_rows(model, gyr_rad_s, acc_g, dt_s) -> list[tuple[int, ...]]:
    """The ``row``s of the ground station's float32 model (``Ahf(settings, dtype=np.float32)``, fresh) on these samples."""
    rows = []
    for g, a, d in zip(gyr_rad_s, acc_g, dt_s):
        q, diag = model.step(g, a, d)
        rows.append(row(diag.status, *q, diag.lam, diag.e_a, diag.gravity_error, model._acc_dev))
    return rows


def host_rows(settings, gyr_rad_s, acc_g, dt_s) -> list[tuple[int, ...]]:
    """The ``row``s of the core's AHF built for this machine (``host.Ahf32``) on these samples."""
    core = host.Ahf32(settings)
    rows = []
    for g, a, d in zip(gyr_rad_s, acc_g, dt_s):
        status, q, lam, e_a, err = core.step(g, a, d)
        rows.append(row(status, *q, lam, e_a, err, core.acc_dev_g))
    return rows


def run_ahf(elf: Path) -> list[tuple[int, ...]]:
    """Per sample, the ``row`` the emulated Cortex-M3 computed."""
    return [tuple(int(v, 16) for v in line.split()) for line in _qemu(elf).splitlines() if _OUTPUT_LINE.fullmatch(line)]


def trace_steps(elf: Path, trace: Path) -> list[list[int]]:
    """Per AHF step, the addresses of the instructions executed (between the two mark() calls around it, the
    call included), from a QEMU trace of every instruction (-singlestep -d exec,nochain); ``trace`` is
    written, read and deleted."""
    mark = next(int(line.split()[0], 16) for line in _run(["arm-none-eabi-nm", str(elf)]).stdout.splitlines()
                if line.split()[-1] == "mark")
    _qemu(elf, "-singlestep", "-d", "exec,nochain", "-D", str(trace))
    steps, current = [], None
    with open(trace) as log:
        for line in log:
            if "[" not in line:
                continue
            pc = int(line.split("[", 1)[1].split("/", 2)[1], 16)
            if pc == mark:
                if current is None:
                    current = []
                else:
                    steps.append(current)
                    current = None
            elif current is not None:
                current.append(pc)
    trace.unlink()
    return steps
