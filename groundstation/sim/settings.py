"""What a simulated flight is asked to be, without the simulator: the board's and the vibration's settings
and the truth profiles' names and default lengths. The commands' help (``sim.options``) reads these
without importing the simulator, whose onboard filter imports numba (bench/bench_help.py)."""

from __future__ import annotations

import dataclasses

import firmware_protocol as fp
from groundstation import mounting as mountings
from groundstation import units

MODES = {name: value for name, value in fp.SPEC.enums["mode"].values.items()}

DEFAULT_DURATION_S = {"static": 300.0, "hover": 120.0, "flight": 120.0, "aggressive": 600.0, "slide": 120.0, "fast": 120.0, "car": 120.0, "turntable": 765.0}
PROFILES = tuple(DEFAULT_DURATION_S)
MAX_DURATION_S = 86_400.0  # a day: profiles are computed ahead, so their length is bounded


# What a board can be: an STM32's internal RC oscillator is off by up to about 1 % untrimmed (10,000 ppm);
# 5 % is beyond any clock that still runs a 1 kHz sensor loop. Jitter beyond one sample period at the
# MPU-6050's 1 kHz would reorder samples.
MAX_CLOCK_DRIFT_PPM = 50_000.0
MAX_SAMPLE_JITTER_US = 1_000.0


@dataclasses.dataclass(frozen=True)
class FirmwareSettings:
    rate_hz: int = 100  # output rate of IMU_RAW / ATTITUDE
    mode: str = "both"  # raw | estimated | both
    accel_fs_g: int = 4  # ±2/4/8/16 g
    gyro_fs_dps: int = 500  # ±250/500/1000/2000 °/s
    mounting: int = mountings.DEFAULT_MOUNTING
    clock_drift_ppm: float = 20.0  # device crystal error (an STM32 HSE crystal: ±20-50 ppm)
    sample_jitter_us: float = 20.0  # σ of the sample-read latency after the timer tick
    boot_calibration_s: float = 1.0  # gyro averaging at power-up, before streaming; 0 = none
    accel_calibrated: bool = True  # stored bench calibration cancels the turn-on zero-g bias
    mag_rate_hz: int = 0  # 0 = no magnetometer
    baro_rate_hz: int = 0  # 0 = no barometer
    gps_rate_hz: int = 0  # 0 = no GPS
    reboot_after_s: float = 0.0  # 0 = never; else the board resets once at this true time
    clock_jump_after_s: float = 0.0  # 0 = never; else the clock jumps ahead once at this true time
    clock_jump_s: float = 3600.0  # by this much

    def __post_init__(self):
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {', '.join(MODES)}, not {self.mode!r}")
        if self.accel_fs_g not in units.ACCEL_LSB_PER_G or self.gyro_fs_dps not in units.GYRO_LSB_PER_DPS:
            raise ValueError(f"full scales must be in {sorted(units.ACCEL_LSB_PER_G)} g and {sorted(units.GYRO_LSB_PER_DPS)} °/s")
        mountings.matrix(self.mounting)
        for name in ("mag_rate_hz", "baro_rate_hz", "gps_rate_hz"):
            rate = getattr(self, name)
            if rate and (rate < 0 or self.rate_hz % rate):
                raise ValueError(f"{name} must divide the output rate {self.rate_hz} Hz")
        if not (self.reboot_after_s >= 0.0 and self.clock_jump_after_s >= 0.0 and self.clock_jump_s >= 0.0):
            raise ValueError("reboot and clock-jump times must be >= 0")
        if not abs(self.clock_drift_ppm) <= MAX_CLOCK_DRIFT_PPM:
            raise ValueError(f"clock drift must be within ±{MAX_CLOCK_DRIFT_PPM:g} ppm (an uncalibrated RC oscillator), "
                             f"not {self.clock_drift_ppm!r}")
        if not 0.0 <= self.sample_jitter_us <= MAX_SAMPLE_JITTER_US:
            raise ValueError(f"sample jitter must be between 0 and {MAX_SAMPLE_JITTER_US:g} µs (the sample period at 1 kHz), "
                             f"not {self.sample_jitter_us!r}")


@dataclasses.dataclass(frozen=True)
class VibrationSettings:
    """``hover_hz`` 0: no vibration. Amplitudes of the fundamental at hover thrust, on the strongest axis."""

    hover_hz: float = 0.0
    accel_m_s2: float = 3.0
    gyro_dps: float = 3.0

    def __post_init__(self):
        if not (0.0 <= self.hover_hz <= 1000.0 and self.accel_m_s2 >= 0.0 and self.gyro_dps >= 0.0):
            raise ValueError(f"vibration: frequency 0-1000 Hz and amplitudes >= 0, not {self.hover_hz!r} Hz, "
                             f"{self.accel_m_s2!r} m/s², {self.gyro_dps!r} °/s")
