"""The reference firmware on the Cortex-M3: image sizes, the AHF step's instructions and cycles, and
whether the board's float arithmetic is the ground station's float32 model's.

    python bench/bench_firmware.py [--seconds S] [--traced-steps N]

Needs arm-none-eabi-gcc and qemu-system-arm (Debian: gcc-arm-none-eabi, libnewlib-arm-none-eabi,
qemu-system-arm). Builds into a temporary directory. Instructions are counted exactly from a QEMU trace
of every executed instruction (-singlestep -d exec) between the marks around each step, call included;
cycles are estimated from the same trace with the Cortex-M3 TRM's instruction timings
(firmware_protocol/reference/cycles.py: QEMU does not count cycles). The baseline, run alongside, is the
same step with the accelerometer unusable (NaN after the first sample): the gyro integration alone
(eq. 6, 19), so the ratio is what the gravity correction (eq. 8-20) costs on top.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

from firmware_protocol.reference import cross, cycles
from groundstation.estimation.ahf import Ahf, AhfSettings
from groundstation.sim.offline import simulate

CLOCK_HZ, RATE_HZ = 72e6, 100.0  # the board's core clock and sample rate


def angle_deg(q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
    """The rotation between two attitudes; arcsin of the chord, exact near zero where arccos of the dot is not."""
    chord = np.minimum(np.linalg.norm(q_a - q_b, axis=1), np.linalg.norm(q_a + q_b, axis=1))
    return np.degrees(4.0 * np.arcsin(np.clip(chord / 2.0, 0.0, 1.0)))


def attitudes(rows) -> np.ndarray:
    """q as float64 from ``cross.row``s."""
    return np.array(rows, dtype=np.uint32)[:, 1:5].view(np.float32).astype(float)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="simulated flight compared (at most 60: the samples go in flash)")
    parser.add_argument("--traced-steps", type=int, default=200, help="steps whose instructions and cycles are counted")
    args = parser.parse_args()
    if cross.toolchain() is None or cross.emulator() is None:
        print("needs arm-none-eabi-gcc and qemu-system-arm", file=sys.stderr)
        return 1
    run = simulate("flight", args.seconds, seed=5, accel_fs_g=4, gyro_fs_dps=500)
    gyr, acc, dt = run.gyr_rad_s, run.acc_g, np.full(len(run), run.dt_s)
    with tempfile.TemporaryDirectory() as work:
        work = Path(work)
        sizes = cross.build_images(work / "stm32")
        print("## Images (arm-none-eabi-gcc -Os, newlib-nano; STM32F103C8: 64 KB flash, 20 KB RAM)\n")
        print("| image | text | data | bss | flash | static RAM |")
        print("|---|---|---|---|---|---|")
        for name, s in sizes.items():
            print(f"| {name} | {s.text} | {s.data} | {s.bss} | {s.flash_bytes} B ({100 * s.flash_bytes / cross.STM32F103C8_FLASH_BYTES:.1f} %) "
                  f"| {s.static_ram_bytes} B ({100 * s.static_ram_bytes / cross.STM32F103C8_RAM_BYTES:.1f} %) |")

        n = args.traced_steps
        print(f"\n## AHF step on a Cortex-M3 (qemu lm3s6965evb, -Os, soft float), {n} steps of the flight\n")
        print("Instructions exact (QEMU trace); cycles estimated (TRM timings, `cycles.py`): with no flash wait state, and")
        print(f"at 72 MHz with the STM32F103's {cycles.STM32F103_72MHZ_WAIT_STATES} (each taken branch and flash literal waits). "
              f"Median over steps 2-{n}; the first (attitude from gravity, in double) apart.\n")
        print("| step | instructions, first step | instructions | cycles, 0 wait states | cycles, 72 MHz | µs at 72 MHz "
              "| CPU at 100 Hz | vs baseline |")
        print("|---|---|---|---|---|---|---|---|")
        gyro_only = acc[:n].copy()
        gyro_only[1:] = math.nan
        medians = {}
        for label, acc_used in (("gyro only: accelerometer NaN (baseline)", gyro_only), ("AHF (eq. 6-20)", acc[:n])):
            elf = cross.build_ahf_program(AhfSettings(), gyr[:n], acc_used, dt[:n], work / "trace")
            program = cycles.disassemble(elf)
            steps = cross.trace_steps(elf, work / "trace.log")
            counts = [len(pcs) for pcs in steps]
            idle = float(np.median([cycles.cycles(program, pcs) for pcs in steps[1:]]))
            busy = float(np.median([cycles.cycles(program, pcs, cycles.STM32F103_72MHZ_WAIT_STATES) for pcs in steps[1:]]))
            medians[label] = median = float(np.median(counts[1:]))
            ratio = median / medians["gyro only: accelerometer NaN (baseline)"]
            print(f"| {label} | {counts[0]} | {median:.0f} (min {min(counts[1:])}, max {max(counts[1:])}) | {idle:.0f} | {busy:.0f} "
                  f"| {1e6 * busy / CLOCK_HZ:.0f} | {100 * busy * RATE_HZ / CLOCK_HZ:.1f} % | {ratio:.2f}x |")

        print(f"\n## The board's numbers against the ground station's ({len(gyr)} samples, {args.seconds:g} s of flight)\n")
        print("Every output of every sample: status, q, lambda, e_a, err, the gate's deviation.\n")
        print("| comparison | rows bit-identical | max angle between estimates |")
        print("|---|---|---|")
        board = cross.run_ahf(cross.build_ahf_program(AhfSettings(), gyr, acc, dt, work / "compare"))
        samples = (gyr.tolist(), acc.tolist(), dt.tolist())
        for label, expected in (("board (newlib, soft float) vs ground-station float32 model",
                                 cross.model_rows(Ahf(AhfSettings(), dtype=np.float32), *samples)),
                                ("board vs host build (glibc, x86-64)", cross.host_rows(AhfSettings(), *samples))):
            same = np.mean([b == e for b, e in zip(board, expected)]) if len(board) == len(expected) else 0.0
            print(f"| {label} | {100 * same:.1f} % | {angle_deg(attitudes(board), attitudes(expected)).max():.3g} deg |")
        # For scale: the same filter in double precision against the float32 model (rounding alone).
        q64, _ = Ahf(AhfSettings()).run(gyr, acc, dt)
        q32, _ = Ahf(AhfSettings(), dtype=np.float32).run(gyr, acc, dt)
        print(f"| (for scale) host float64 AHF vs float32 model | - | {angle_deg(q64, q32).max():.3g} deg |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
