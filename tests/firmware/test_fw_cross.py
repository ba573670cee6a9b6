"""The board and bridge images for the Cortex-M3 (where arm-none-eabi-gcc is installed), and the core's
AHF on an emulated Cortex-M3 (where qemu-system-arm is) against the host build."""

import struct
import subprocess

import numpy as np
import pytest

from firmware_protocol.reference import cross, host
from groundstation.estimation.ahf import Ahf, AhfSettings
from groundstation.sim.offline import simulate

pytestmark = pytest.mark.skipif(cross.toolchain() is None, reason="arm-none-eabi-gcc not installed (Debian: gcc-arm-none-eabi, "
                                                                  "libnewlib-arm-none-eabi): the STM32 images are not built")
needs_qemu = pytest.mark.skipif(cross.emulator() is None, reason="qemu-system-arm not installed: the Cortex-M3 run is not checked")


def vector(elf, index: int) -> int:
    table = subprocess.run(["arm-none-eabi-objcopy", "-O", "binary", "-j", ".isr_vector", str(elf), "/dev/stdout"],
                           capture_output=True, check=True).stdout
    return struct.unpack_from("<I", table, 4 * index)[0]


def symbol(elf, name: str) -> int:
    lines = subprocess.run(["arm-none-eabi-nm", str(elf)], capture_output=True, text=True, check=True).stdout.splitlines()
    return next(int(line.split()[0], 16) for line in lines if line.split()[-1] == name)


def test_both_images_build_fit_the_blue_pill_and_route_their_interrupts(tmp_path):
    sizes = cross.build_images(tmp_path)
    for name, size in sizes.items():
        assert size.flash_bytes <= cross.STM32F103C8_FLASH_BYTES, name
        assert size.static_ram_bytes + 2048 <= cross.STM32F103C8_RAM_BYTES, name  # 2 KB of stack left at least
    for name in ("flight", "bridge"):
        elf = tmp_path / f"{name}.elf"
        assert vector(elf, 1) == symbol(elf, "Reset_Handler") | 1
        assert vector(elf, 16 + 28) == symbol(elf, "TIM2_IRQHandler") | 1  # the microsecond clock
    bridge = tmp_path / "bridge.elf"
    assert vector(bridge, 16 + 37) == symbol(bridge, "USART1_IRQHandler") | 1 != symbol(bridge, "Default_Handler") | 1
    assert (tmp_path / "flight.bin").stat().st_size == sizes["flight"].flash_bytes


def flight(seconds: float = 60.0):
    run = simulate("flight", seconds, seed=5, accel_fs_g=4, gyro_fs_dps=500)
    return run.gyr_rad_s, run.acc_g, np.full(len(run), run.dt_s)


def rows(status, q, lam) -> tuple:
    return (status, *np.array([*q, lam], dtype=np.float32).view(np.uint32).tolist())


@needs_qemu
def test_on_a_cortex_m3_the_core_computes_what_the_host_build_computes(c_core, tmp_path):
    """Soft-float, newlib's double functions and GCC for ARM change nothing when x^-0.5 is the portable
    expression: 60 s of flight, every output bit equal."""
    defines = ("GS_AHF_PORTABLE_RSQRT",)
    gyr, acc, dt = flight()
    board = cross.run_ahf(cross.build_ahf_program(gyr, acc, dt, tmp_path, defines))
    ahf = host.Ahf32(AhfSettings(), defines=defines)
    expected = []
    for g, a, d in zip(gyr.tolist(), acc.tolist(), dt.tolist()):
        status, q, lam, _, _ = ahf.step(g, a, d)
        expected.append(rows(status, q, lam))
    assert len(board) == len(expected) == 6000
    assert board == expected


@needs_qemu
@pytest.mark.xfail(strict=True, reason="newlib's powf(x, -0.5) rounds differently from glibc's (NumPy's) in 9 % of inputs, and "
                                       "the filter amplifies it to degrees: the ground station's float32 model and the core need "
                                       "one exactly specified x^-0.5 (docs/firmware.md)")
def test_the_stm32_build_agrees_with_the_ground_stations_float32_model(tmp_path):
    gyr, acc, dt = flight(10.0)
    board = cross.run_ahf(cross.build_ahf_program(gyr, acc, dt, tmp_path))
    model = Ahf(AhfSettings(), dtype=np.float32)
    expected = [rows(diag.status, q, diag.lam) for q, diag in (model.step(g, a, d) for g, a, d in zip(gyr.tolist(), acc.tolist(), dt.tolist()))]
    assert board == expected
