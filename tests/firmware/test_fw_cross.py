"""The board and bridge images for the Cortex-M3 (where arm-none-eabi-gcc is installed), and the core's
AHF built with newlib on an emulated Cortex-M3 (where qemu-system-arm is) against the ground station's
float32 model."""

import struct
import subprocess

import numpy as np
import pytest

from firmware_protocol.reference import cross
from groundstation.estimation.ahf import Ahf, AhfSettings
from groundstation.sim.offline import simulate
from tests.firmware.test_fw_ahf import GATE_ON, guard_case

pytestmark = pytest.mark.skipif(cross.toolchain() is None, reason="arm-none-eabi-gcc not installed (Debian: gcc-arm-none-eabi, "
                                                                  "libnewlib-arm-none-eabi): the STM32 images are not built and the "
                                                                  "core's AHF is not checked on a Cortex-M3")
needs_qemu = pytest.mark.skipif(cross.emulator() is None, reason="qemu-system-arm not installed (Debian: qemu-system-arm): the core's AHF "
                                                                 "is not checked bit for bit on an emulated Cortex-M3")


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


def flight_case() -> tuple:
    """(settings, gyr, acc, dt): 60 s of the simulated flight, the paper's settings."""
    run = simulate("flight", 60.0, seed=5, accel_fs_g=4, gyro_fs_dps=500)
    return AhfSettings(), run.gyr_rad_s.tolist(), run.acc_g.tolist(), [run.dt_s] * len(run)


@needs_qemu
@pytest.mark.parametrize("case", [flight_case, lambda: guard_case(GATE_ON)], ids=["flight-60s", "guards-gate-on"])
def test_on_a_cortex_m3_with_newlib_the_core_computes_the_ground_stations_float32_model_bit_for_bit(case, tmp_path):
    """Soft float, newlib's sqrtf and double functions and GCC for ARM: every output bit of every sample (status,
    q, lambda, e_a, err, the gate's deviation) equals the float32 model, over a minute of flight and through
    every guard with the deviation gate (its square root) on."""
    settings, gyr, acc, dt = case()
    board = cross.run_ahf(cross.build_ahf_program(settings, gyr, acc, dt, tmp_path))
    expected = cross.model_rows(Ahf(settings, dtype=np.float32), gyr, acc, dt)
    assert len(board) == len(expected) == len(dt)
    mismatched = [k for k, (b, e) in enumerate(zip(board, expected)) if b != e]
    assert not mismatched, f"{len(mismatched)} of {len(dt)} rows differ, first at sample {mismatched[0]}: board {board[mismatched[0]]} != model {expected[mismatched[0]]}"
