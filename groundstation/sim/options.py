"""Command-line options shared by ``bridge-sim`` and ``simulate``: they describe one Scenario."""

from __future__ import annotations

import argparse
import dataclasses

from groundstation.errors import UserError
from groundstation.sim.settings import DEFAULT_DURATION_S, MAX_DURATION_S, MODES, PROFILES, FirmwareSettings, VibrationSettings

# Rates of the optional sensors (Hz); each must divide the output rate.
EXTRA_SENSOR_RATES_HZ = {"mag": 50, "baro": 25, "gps": 5}


def add_scenario_arguments(parser: argparse.ArgumentParser) -> None:
    durations = ", ".join(f"{name} {seconds:g} s" for name, seconds in DEFAULT_DURATION_S.items())
    parser.add_argument("--scenario", choices=PROFILES, default="flight", help="truth profile (default: flight)")
    parser.add_argument("--seed", type=seed_number, default=1, help="random seed; equal seeds give identical bytes (default: 1)")
    parser.add_argument("--mode", choices=tuple(MODES), default="both", help="what the board sends (default: both)")
    parser.add_argument("--rate", type=int, default=100, metavar="HZ", help="output rate (default: 100)")
    parser.add_argument("--accel-fs", type=int, default=4, metavar="G", help="accelerometer full scale: 2, 4, 8, 16 (default: 4)")
    parser.add_argument("--gyro-fs", type=int, default=500, metavar="DPS", help="gyro full scale: 250, 500, 1000, 2000 (default: 500)")
    parser.add_argument("--mounting", type=int, default=FirmwareSettings.mounting, metavar="N",
                        help=f"sensor mounting index 0-23 (default: {FirmwareSettings.mounting}, x forward, z up)")
    parser.add_argument("--sensors", default="", metavar="LIST",
                        help="extra sensors, comma-separated: mag, baro, gps (50, 25, 5 Hz)")
    parser.add_argument("--clock-drift-ppm", type=float, default=FirmwareSettings.clock_drift_ppm, metavar="PPM",
                        help=f"board clock error (default: {FirmwareSettings.clock_drift_ppm:g})")
    parser.add_argument("--sample-jitter-us", type=float, default=FirmwareSettings.sample_jitter_us, metavar="US",
                        help=f"σ of the sampling-time jitter (default: {FirmwareSettings.sample_jitter_us:g})")
    shake = parser.add_argument_group("motor vibration (default: none)")
    shake.add_argument("--vibration", type=float, default=0.0, metavar="HZ",
                       help="rotor frequency at hover thrust; it follows the thrust (f ∝ √thrust), with its 2nd harmonic")
    shake.add_argument("--vibration-accel", type=float, default=VibrationSettings.accel_m_s2, metavar="M_S2",
                       help=f"accelerometer amplitude at hover, strongest axis (default: {VibrationSettings.accel_m_s2:g})")
    shake.add_argument("--vibration-gyro", type=float, default=VibrationSettings.gyro_dps, metavar="DPS",
                       help=f"gyro amplitude at hover, strongest axis (default: {VibrationSettings.gyro_dps:g})")
    board = parser.add_argument_group("board mishaps (default: none)")
    board.add_argument("--reboot-after", type=float, default=0.0, metavar="S",
                       help="the board resets once after S seconds: clock and sequence restart at 0, it boots again")
    board.add_argument("--clock-jump-after", type=float, default=0.0, metavar="S", help="the board's clock jumps ahead once after S seconds")
    board.add_argument("--clock-jump", type=float, default=FirmwareSettings.clock_jump_s, metavar="S",
                       help=f"by this much (default: {FirmwareSettings.clock_jump_s:g})")
    link = parser.add_argument_group("link impairments (default: a clean link)")
    link.add_argument("--loss", type=float, default=0.0, metavar="P", help="independent frame-loss probability")
    link.add_argument("--burst-loss", type=float, default=0.0, metavar="P", help="fraction of frames lost in bursts (Gilbert-Elliott)")
    link.add_argument("--burst-len", type=float, default=10.0, metavar="N", help="mean burst length in frames (default: 10)")
    link.add_argument("--ber", type=float, default=0.0, metavar="P", help="bit-error probability per bit")
    link.add_argument("--truncate", type=float, default=0.0, metavar="P", help="probability that a frame arrives cut short")
    link.add_argument("--latency-ms", type=float, default=0.0, metavar="MS", help="fixed link delay")
    link.add_argument("--jitter-ms", type=float, default=0.0, metavar="MS", help="mean of an exponential extra delay")
    link.add_argument("--usb-batch-ms", type=float, default=0.0, metavar="MS", help="release bytes on this period (USB-serial latency timer)")
    link.add_argument("--dropout-every", type=float, default=None, metavar="S", help="the port disappears every S seconds")
    link.add_argument("--dropout-s", type=float, default=2.0, metavar="S", help="for this long (default: 2)")
    parser.epilog = f"Default durations: {durations}."


def seed_number(text: str) -> int:
    """An argparse type: a seed numpy's generators take (a non-negative integer)."""
    try:
        seed = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if seed < 0:
        raise argparse.ArgumentTypeError(f"a seed is a non-negative integer, not {seed}")
    return seed


def scenario_from_args(args: argparse.Namespace, duration_s: float | None):
    """The ``sim.stream.Scenario`` the options describe (UserError for an impossible one)."""
    from groundstation.sim.imu import MPU6050Settings
    from groundstation.sim.link import LinkSettings
    from groundstation.sim.stream import Scenario

    sensors = [s.strip() for s in args.sensors.split(",") if s.strip()]
    unknown = set(sensors) - EXTRA_SENSOR_RATES_HZ.keys()
    if unknown:
        raise UserError(f"unknown sensor(s) {', '.join(sorted(unknown))}; choose from {', '.join(EXTRA_SENSOR_RATES_HZ)}")
    if args.rate <= 0 or args.rate > 1000:
        raise UserError("--rate must be between 1 and 1000 Hz (the MPU-6050 samples at 1 kHz)")
    if duration_s is not None and not 0 < duration_s <= MAX_DURATION_S:
        # The truth profile is computed ahead for the whole duration: a bound keeps its memory bounded.
        raise UserError(f"--duration must be positive and at most {MAX_DURATION_S:g} s (a day), not {duration_s:g}")
    if args.dropout_every is not None and not args.dropout_every > 0:
        raise UserError("--dropout-every must be positive (leave it out for a port that never drops)")
    rates = {f"{name}_rate_hz": EXTRA_SENSOR_RATES_HZ[name] for name in sensors}
    try:
        firmware = FirmwareSettings(
            rate_hz=args.rate, mode=args.mode, accel_fs_g=args.accel_fs, gyro_fs_dps=args.gyro_fs, mounting=args.mounting,
            clock_drift_ppm=args.clock_drift_ppm, sample_jitter_us=args.sample_jitter_us, reboot_after_s=args.reboot_after,
            clock_jump_after_s=args.clock_jump_after, clock_jump_s=args.clock_jump, **rates,
        )
        link = LinkSettings(
            loss=args.loss, burst_loss=args.burst_loss, burst_length_frames=args.burst_len, ber=args.ber, truncate=args.truncate,
            latency_ms=args.latency_ms, jitter_ms=args.jitter_ms, usb_batch_ms=args.usb_batch_ms,
            dropout_every_s=args.dropout_every or 0.0, dropout_s=args.dropout_s,
        )
        vibration = VibrationSettings(args.vibration, args.vibration_accel, args.vibration_gyro)
    except ValueError as error:
        raise UserError(str(error)) from None
    return dataclasses.replace(Scenario(), profile=args.scenario, duration_s=duration_s, seed=args.seed, firmware=firmware, link=link,
                               imu=MPU6050Settings(vibration=vibration))
