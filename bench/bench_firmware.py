"""The reference firmware on the Cortex-M3: image sizes, the AHF step's instruction count, and how far
the board's float arithmetic is from the host's and from the ground station's float32 model.

    python bench/bench_firmware.py [--seconds S] [--traced-steps N]

Needs arm-none-eabi-gcc and qemu-system-arm (Debian: gcc-arm-none-eabi, libnewlib-arm-none-eabi,
qemu-system-arm). Builds into a temporary directory. Instructions are counted exactly from a QEMU trace
of every executed instruction (-singlestep -d exec) between the marks around each step, call included;
the baseline is the same step with x^-0.5 computed through double (GS_AHF_PORTABLE_RSQRT).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from firmware_protocol.reference import cross, host
from groundstation.estimation.ahf import Ahf, AhfSettings
from groundstation.sim.offline import simulate

PORTABLE = ("GS_AHF_PORTABLE_RSQRT",)


def angle_deg(q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
    """The rotation between two attitudes; arcsin of the chord, exact near zero where arccos of the dot is not."""
    chord = np.minimum(np.linalg.norm(q_a - q_b, axis=1), np.linalg.norm(q_a + q_b, axis=1))
    return np.degrees(4.0 * np.arcsin(np.clip(chord / 2.0, 0.0, 1.0)))


def outputs(rows) -> tuple[np.ndarray, np.ndarray]:
    """(status, q as float64) from rows of (status, q bits, lambda bits)."""
    table = np.array(rows, dtype=np.uint32)
    return table[:, 0], table[:, 1:5].view(np.float32).astype(float)


def host_rows(step, gyr, acc, dt) -> list[tuple]:
    rows = []
    for g, a, d in zip(gyr.tolist(), acc.tolist(), dt.tolist()):
        status, q, lam = step(g, a, d)
        rows.append((status, *np.array([*q, lam], dtype=np.float32).view(np.uint32).tolist()))
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="simulated flight compared (at most 60: the samples go in flash)")
    parser.add_argument("--traced-steps", type=int, default=200, help="steps whose instructions are counted")
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

        print(f"\n## AHF step on a Cortex-M3 (qemu lm3s6965evb, -Os, soft float), {args.traced_steps} steps of the flight\n")
        print("| x^-0.5 | first step (init from gravity) | median | min | max | vs baseline |")
        print("|---|---|---|---|---|---|")
        n = args.traced_steps
        medians = {}
        for label, defines in (("double (baseline)", PORTABLE), ("powf (default)", ())):
            elf = cross.build_ahf_program(gyr[:n], acc[:n], dt[:n], work / f"trace{len(defines)}", defines)
            counts = cross.count_step_instructions(elf, work / f"trace{len(defines)}.log")
            (work / f"trace{len(defines)}.log").unlink()
            medians[label] = median = float(np.median(counts[1:]))
            ratio = median / medians["double (baseline)"]
            print(f"| {label} | {counts[0]} | {median:.0f} | {min(counts[1:])} | {max(counts[1:])} | {ratio:.2f}x |")

        print(f"\n## The board's numbers against the host's ({len(gyr)} samples, {args.seconds:g} s of flight)\n")
        print("| build | rows bit-identical | status equal | max angle between estimates |")
        print("|---|---|---|---|")
        model = Ahf(AhfSettings(), dtype=np.float32)

        def model_step(g, a, d):
            q, diag = model.step(g, a, d)
            return diag.status, q, diag.lam

        def core_step(defines):
            core = host.Ahf32(AhfSettings(), defines=defines)
            return lambda g, a, d: core.step(g, a, d)[:3]

        for label, defines, reference, step in (
            ("powf: board vs ground-station float32 model", (), "model", model_step),
            ("double: board vs host build", PORTABLE, "host", core_step(PORTABLE)),
        ):
            board = cross.run_ahf(cross.build_ahf_program(gyr, acc, dt, work / "compare", defines))
            expected = host_rows(step, gyr, acc, dt)
            (s_b, q_b), (s_e, q_e) = outputs(board), outputs(expected)
            same = np.mean([b == e for b, e in zip(board, expected)])
            print(f"| {label} | {100 * same:.1f} % | {bool(np.all(s_b == s_e))} | {angle_deg(q_b, q_e).max():.3g} deg |")
        # For scale: the same filter in double precision against the float32 model (rounding alone).
        q64, _ = Ahf(AhfSettings()).run(gyr, acc, dt)
        q32, _ = Ahf(AhfSettings(), dtype=np.float32).run(gyr, acc, dt)
        print(f"| (for scale) host float64 AHF vs float32 model | - | - | {angle_deg(q64, q32).max():.3g} deg |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
