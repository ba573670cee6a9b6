"""The simulated flight board: sampling clock, MPU-6050, onboard AHF in float32, frames, commands.

Timing. The board's crystal runs ``clock_drift_ppm`` fast: device time = true time × (1 + drift).
Sample k is read at device time ``k / rate_hz`` plus an interrupt-latency jitter (normal, σ
``sample_jitter_us``) and stamped with that device time in µs (``t_us`` wraps at 2³²). The truth is
taken at the true instant of each read, so the host sees real clock drift and jitter.

Boot. At power-up the board averages the gyro for ``boot_calibration_s`` (every profile starts at
rest) and writes the result into the chip's offset registers, as flight firmwares do; it writes the
stored accelerometer offsets too (``accel_calibrated``: the bench calibration the paper did before
its tests, equal to the part's turn-on zero-g bias). Then it sends ``CONFIG`` and starts streaming:

- each sample: ``IMU_RAW`` (mode raw or both), ``ATTITUDE`` from the onboard AHF (estimated or both);
- every second: ``STATUS``; ``MAG_RAW``/``BARO``/``GPS`` at their rates when enabled.

One sequence counter numbers every downlink frame, so the host counts lost frames of any type. The
onboard AHF runs in every mode (a mode switch finds it converged) on the same numbers the host gets:
counts converted with ``groundstation.units``, rotated to the body by the mounting, ``dt`` from the
device timestamps.

Reboot and clock jump (to test the ground station): ``reboot_after_s`` > 0 resets the board once at
that true time, as a brown-out does: the clock restarts at 0, the sequence counter at 0, the onboard
filter, mode, filter settings and gyro offsets start over, and it boots again (calibration, CONFIG).
``clock_jump_after_s`` > 0 makes the clock jump ahead by ``clock_jump_s`` at that time, the rest
going on. The truth (``on_samples``) keeps the uninterrupted device time.

Commands (``COMMAND`` frames, uplink): ``set_mode``, ``set_filter_param`` (λ_max, λ_min, low-pass,
error gain, gyro over-range in rad/s with ≤ 0 meaning off), ``request_config`` and
``calibrate_gyro`` (averaging time ``value`` s, 0 → 1 s; STATUS flag bit 0 while it runs; the
craft must be at rest, as on the real board). Each is answered with ``ACK``; ``set_mode`` and
``request_config`` are followed by ``CONFIG``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

import firmware_protocol as fp
from groundstation import mounting as mountings
from groundstation import units
from groundstation.estimation.ahf import Ahf, AhfSettings
from groundstation.estimation.base import ACC_SKIPPED, GYRO_OVERRANGE, INITIALISED, WAITING
from groundstation.sim import extra_sensors
from groundstation.sim.imu import MPU6050, ImuSamples, MPU6050Settings
from groundstation.sim.profiles import Profile, Truth
from groundstation.sim.seeds import stream

MODES = {name: value for name, value in fp.SPEC.enums["mode"].values.items()}
MODE_NAMES = {value: name for name, value in MODES.items()}
_COMMANDS = fp.SPEC.enums["command"].values
_FILTER_PARAMS = {value: name for name, value in fp.SPEC.enums["filter_param"].values.items()}
_RESULT = fp.SPEC.enums["ack_result"].values
_Q14 = 1.0 / fp.SPEC.frame("ATTITUDE").fields[1].scale
FIRMWARE_VERSION = (0, 1, 0)
PREFETCH_SAMPLES = 50


def battery_v(t_s: float) -> float:
    """The simulated battery at true time ``t_s``: a 3S LiPo over a 10-minute flight."""
    return max(10.5, 12.6 - 1.5 * t_s / 600.0)


def cpu_load_pct(mode: int) -> float:
    """The simulated board's CPU load in ``mode`` (the AHF runs in every mode; sending costs)."""
    return 25.0 if mode == MODES["raw"] else 40.0


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
class SentFrame:
    t_s: float  # true (simulation) time the frame leaves the board
    data: bytes
    t_us: int | None  # the frame's device timestamp if it has one (for latency measurements)


class Firmware:
    """Step with ``run_until(t_s)``; feed uplink frames to ``command``. Deterministic from ``seed``.

    ``on_samples(t_dev_us, truth, imu_samples)``, if given, receives every streamed sample block:
    the device time (unwrapped, µs), the truth at each read and the registers read.
    """

    def __init__(self, profile: Profile, settings=FirmwareSettings(), imu=MPU6050Settings(), ahf=AhfSettings(),
                 extra=extra_sensors.AuxSettings(), seed: int = 0, on_samples=None):
        self.profile, self.settings, self.extra = profile, settings, extra
        self.mode = MODES[settings.mode]
        self.imu = MPU6050(imu, settings.accel_fs_g, settings.gyro_fs_dps, settings.mounting, settings.rate_hz, seed)
        if settings.accel_calibrated:
            self.imu.accel_offset_g = self.imu.accel_turn_on_bias_g.copy()
        self.ahf_settings = self._boot_ahf_settings = ahf
        self.onboard = Ahf(ahf, dtype=np.float32)
        self._onboard_q: list[float] | None = None  # its last output, None before its first sample
        self._on_samples = on_samples
        self._jitter = stream(seed, "clock_jitter")
        self._extra_rng = {name: stream(seed, name) for name in ("mag", "baro", "gps")}
        self._hard_iron_ut = stream(seed, "mag_part").normal(0.0, extra.mag_hard_iron_tolerance_ut / 3.0, 3)
        self._period_s = 1.0 / settings.rate_hz
        self._drift = 1.0 + settings.clock_drift_ppm * 1e-6
        self._body_from_sensor = mountings.matrix(settings.mounting)
        self._k = 0  # next sample index
        self._ahead: dict[str, np.ndarray] = {}  # samples computed ahead (see _sampled), up to _ahead_end
        self._ahead_end = 0
        self._seq = 0
        self._epoch_us = 0  # device time (uninterrupted) at which the board's clock read 0
        self._mishaps = sorted((self._sample_at(t_s), what) for t_s, what in
                               ((settings.reboot_after_s, self._reboot), (settings.clock_jump_after_s, self._jump_clock)) if t_s > 0)
        self._last_t_dev_us: int | None = None
        self._queued: list[tuple[str, dict]] = []  # frames to send before the next sample
        self._booting = True
        self._calibration: tuple[int, int, list] | None = None  # (first k, end k, sums of gyro dps)
        if settings.boot_calibration_s > 0:
            self._start_calibration(settings.boot_calibration_s)
        else:  # a board that skips it streams its turn-on gyro bias
            self._end_boot()

    # -- time --------------------------------------------------------------------------------

    def true_time_s(self, k) -> float:
        """Nominal true time of sample ``k`` (without jitter)."""
        return k * self._period_s / self._drift

    @property
    def last_seq(self) -> int:
        """Sequence number of the last frame sent (255 before the first)."""
        return (self._seq - 1) & 0xFF

    @property
    def next_sample(self) -> int:
        """Index of the next sample the board will take."""
        return self._k

    def run_until(self, t_s: float) -> list[SentFrame]:
        """Every frame the board sends up to true time ``t_s`` (samples whose nominal time < t_s)."""
        k_end = max(self._k, math.ceil(t_s * self._drift / self._period_s - 1e-9))
        out: list[SentFrame] = []
        while self._k < k_end:
            end = k_end if self._calibration is None else min(k_end, self._calibration[1])
            if self._mishaps:
                end = min(end, self._mishaps[0][0])
            self._run_block(self._k, end, out)
            self._k = end
            if self._calibration is not None and self._k == self._calibration[1]:
                self._finish_calibration()
            while self._mishaps and self._k >= self._mishaps[0][0]:
                self._mishaps.pop(0)[1]()
        return out

    def _sample_at(self, t_s: float) -> int:
        """The first sample at or after true time ``t_s``."""
        return math.ceil(t_s * self._drift / self._period_s - 1e-9)

    def _reboot(self) -> None:
        self._epoch_us = round(self._k * self._period_s * 1e6)
        self._seq, self._queued, self._last_t_dev_us = 0, [], None
        self.mode = MODES[self.settings.mode]
        self.ahf_settings = self._boot_ahf_settings
        self.onboard, self._onboard_q = Ahf(self.ahf_settings, dtype=np.float32), None
        self.imu.gyro_offset_dps = np.zeros(3)
        self._booting, self._calibration = True, None
        if self.settings.boot_calibration_s > 0:
            self._start_calibration(self.settings.boot_calibration_s)
        else:
            self._end_boot()

    def _jump_clock(self) -> None:
        self._epoch_us -= round(self.settings.clock_jump_s * 1e6)

    # -- commands ----------------------------------------------------------------------------

    def command(self, frame: fp.Frame) -> None:
        """Obey an uplink ``COMMAND``; the ACK (and CONFIG) go out before the next sample."""
        if frame.name != "COMMAND":
            return
        command, param, value = frame["command"], frame["param"], frame["value"]
        result = _RESULT["ok"]
        follow_config = False
        if command == _COMMANDS["set_mode"]:
            if param in MODE_NAMES:
                self.mode, follow_config = param, True
            else:
                result = _RESULT["bad_value"]
        elif command == _COMMANDS["set_filter_param"]:
            result = self._set_filter_param(param, value)
        elif command == _COMMANDS["request_config"]:
            follow_config = True
        elif command == _COMMANDS["calibrate_gyro"]:
            seconds = value if value > 0 else 1.0
            if self._calibration is not None:
                result = _RESULT["busy"]
            elif not seconds <= 60.0:
                result = _RESULT["bad_value"]
            else:
                self._start_calibration(seconds)
        else:
            result = _RESULT["unsupported"]
        self._queued.append(("ACK", {"command_seq": frame.seq, "command": command, "result": result}))
        if follow_config:
            self._queued.append(("CONFIG", self._config_values()))

    def _set_filter_param(self, param: int, value: float) -> int:
        name = _FILTER_PARAMS.get(param)
        if name is None or not math.isfinite(value):
            return _RESULT["bad_value"]
        if name == "gyro_overrange":
            name, value = "gyro_overrange_rad_s", (value if value > 0 else math.inf)
        try:
            settings = dataclasses.replace(self.ahf_settings, **{name: float(value)})
            onboard = Ahf(settings, dtype=np.float32)
        except ValueError:
            return _RESULT["bad_value"]
        # Keep the attitude: a tuning change must not make the estimate jump.
        onboard.reset(q0=self._onboard_q)
        self.ahf_settings, self.onboard = settings, onboard
        return _RESULT["ok"]

    def _start_calibration(self, seconds: float) -> None:
        n = max(1, round(seconds * self.settings.rate_hz))
        self._calibration = (self._k, self._k + n, [np.zeros(3)])

    def _finish_calibration(self) -> None:
        first, end, (sum_dps,) = self._calibration
        self.imu.gyro_offset_dps = self.imu.gyro_offset_dps + sum_dps / (end - first)
        self._calibration = None
        if self._booting:
            self._end_boot()

    def _end_boot(self) -> None:
        self._booting = False
        self._queued.append(("CONFIG", self._config_values()))

    # -- frames ------------------------------------------------------------------------------

    def _config_values(self) -> dict:
        s = self.settings
        major, minor, patch = FIRMWARE_VERSION
        return {
            "protocol_version": fp.SPEC.protocol_version, "schema_fingerprint": fp.SPEC.fingerprint,
            "fw_major": major, "fw_minor": minor, "fw_patch": patch, "accel_fs_g": s.accel_fs_g,
            "gyro_fs_dps": s.gyro_fs_dps, "rate_hz": s.rate_hz, "mode": self.mode, "mounting": s.mounting,
        }

    def _emit(self, out: list, t_s: float, name: str, scaled: bool = False, **values) -> None:
        make = fp.make_scaled_frame if scaled else fp.make_frame
        out.append(SentFrame(t_s, fp.encode(make(name, seq=self._seq, **values)), values.get("t_us")))
        self._seq = (self._seq + 1) & 0xFF

    def _sample(self, k0: int, k1: int) -> dict[str, np.ndarray]:
        """Sampling instants, truth and analog readings of samples k0..k1-1 (nothing a command changes)."""
        s = self.settings
        jitter_s = np.clip(self._jitter.normal(0.0, s.sample_jitter_us * 1e-6, k1 - k0), -0.25 * self._period_s, 0.25 * self._period_s)
        t_dev_s = np.arange(k0, k1) * self._period_s + jitter_s
        truth = self.profile.truth(t_dev_s / self._drift)
        gyr_dps, acc_g, temp_c = self.imu.analog(truth)
        block = {"t_dev_us": np.rint(t_dev_s * 1e6).astype(np.int64), "gyr_dps": gyr_dps, "acc_g": acc_g, "temp_c": temp_c}
        block.update({f.name: getattr(truth, f.name) for f in dataclasses.fields(Truth)})
        return block

    def _sampled(self, k0: int, k1: int) -> tuple[np.ndarray, Truth, ImuSamples]:
        """Samples k0..k1-1 (consecutive calls), computed ahead in blocks of at least PREFETCH_SAMPLES:
        numpy costs the same for one sample as for fifty, and the bridge steps one at a time."""
        if self._ahead_end < k1:
            new = self._sample(self._ahead_end, self._ahead_end + max(PREFETCH_SAMPLES, k1 - self._ahead_end))
            self._ahead = {key: np.concatenate([self._ahead[key], new[key]]) for key in new} if self._ahead else new
            self._ahead_end += len(new["t_dev_us"])
        start = len(self._ahead["t_dev_us"]) - (self._ahead_end - k0)
        now = {key: value[start : start + k1 - k0] for key, value in self._ahead.items()}
        self._ahead = {key: value[start + k1 - k0 :] for key, value in self._ahead.items()}
        truth = Truth(**{f.name: now[f.name] for f in dataclasses.fields(Truth)})
        return now["t_dev_us"], truth, self.imu.registers(now["gyr_dps"], now["acc_g"], now["temp_c"])

    def _run_block(self, k0: int, k1: int, out: list) -> None:
        s = self.settings
        n = k1 - k0
        t_dev_us, truth, raw = self._sampled(k0, k1)
        t_true = truth.t_s
        gyr_dps = units.gyro_counts_to_dps(raw.gyr_counts, s.gyro_fs_dps)
        if self._calibration is not None:
            self._calibration[2][0] += gyr_dps.sum(axis=0)
        if self._booting:
            return
        if self._on_samples is not None:
            self._on_samples(t_dev_us, truth, raw)
        # Exactly the host's conversions (the normalised-gradient AHF amplifies even 1-ulp differences).
        gyr_body = (units.gyro_counts_to_rad_s(raw.gyr_counts, s.gyro_fs_dps) @ self._body_from_sensor.T).tolist()
        acc_body = (units.accel_counts_to_g(raw.acc_counts, s.accel_fs_g) @ self._body_from_sensor.T).tolist()
        # The filter starts with the stream: its first dt is the nominal period, as a host assumes.
        prev = self._last_t_dev_us if self._last_t_dev_us is not None else int(t_dev_us[0]) - round(self._period_s * 1e6)
        dt_s = (np.diff(t_dev_us, prepend=prev) * 1e-6).tolist()
        self._last_t_dev_us = int(t_dev_us[-1])
        # The die temperature as the firmware reports it: TEMP_OUT counts, then counts/340 + 36.53.
        temp_c = units.temperature_counts_to_c(units.temperature_c_to_counts(raw.temperature_c))
        extras = self._extra_readings(truth)
        per_status = s.rate_hz
        acc_counts, gyr_counts = raw.acc_counts.tolist(), raw.gyr_counts.tolist()
        t_true_list, t_us_list = t_true.tolist(), ((t_dev_us - self._epoch_us) & 0xFFFFFFFF).tolist()
        for i in range(n):
            t, t_us = t_true_list[i], t_us_list[i]
            for name, values in self._queued:
                self._emit(out, t, name, **values)
            self._queued.clear()
            q, diag = self.onboard.step(gyr_body[i], acc_body[i], dt_s[i])
            self._onboard_q = q
            if (k0 + i) % per_status == 0:
                self._emit_status(out, t, t_us)
            if self.mode != MODES["estimated"]:
                (ax, ay, az), (gx, gy, gz) = acc_counts[i], gyr_counts[i]
                self._emit(out, t, "IMU_RAW", t_us=t_us, acc_x=ax, acc_y=ay, acc_z=az, gyr_x=gx, gyr_y=gy, gyr_z=gz,
                           temperature=round(temp_c[i] * 100))
            if self.mode != MODES["raw"]:
                self._emit_attitude(out, t, t_us, q, diag)
            for name, every, values in extras:
                if (k0 + i) % every == 0:
                    self._emit(out, t, name, scaled=True, t_us=t_us, **{key: v[i] for key, v in values.items()})

    def _emit_status(self, out, t: float, t_us: int) -> None:
        battery = battery_v(t)
        flags = (self._calibration is not None) | ((battery < 10.8) << 1)
        # The radio's own counters are not modelled on the aircraft side (the link model acts at the ground end).
        self._emit(out, t, "STATUS", scaled=True, t_us=t_us, battery=battery, retransmits=0, lost_acks=0,
                   cpu_load=cpu_load_pct(self.mode), flags=flags)

    def _emit_attitude(self, out, t: float, t_us: int, q, diag) -> None:
        qw, qx, qy, qz = (min(max(round(float(v) * _Q14), -32768), 32767) for v in q)
        flags = (bool(diag.status & (WAITING | INITIALISED))
                 | bool(diag.status & GYRO_OVERRANGE) << 1 | bool(diag.status & ACC_SKIPPED) << 2)
        self._emit(out, t, "ATTITUDE", t_us=t_us, q_w=qw, q_x=qx, q_y=qy, q_z=qz,
                   lambda_gain=min(round(float(diag.lam) * 1000.0), 65535), flags=flags)

    def _extra_readings(self, truth) -> list[tuple[str, int, dict]]:
        """(frame name, every how many samples, {field: (n,) values}) for the enabled extra sensors."""
        s, x = self.settings, self.extra
        out = []
        if s.mag_rate_hz:
            mag = extra_sensors.magnetometer_ut(truth, x, s.mounting, self._hard_iron_ut, self._extra_rng["mag"])
            out.append(("MAG_RAW", s.rate_hz // s.mag_rate_hz, {"mag_x": mag[:, 0], "mag_y": mag[:, 1], "mag_z": mag[:, 2]}))
        if s.baro_rate_hz:
            pressure, temperature = extra_sensors.barometer(truth, x, self._extra_rng["baro"])
            out.append(("BARO", s.rate_hz // s.baro_rate_hz, {"pressure": pressure, "temperature": temperature}))
        if s.gps_rate_hz:
            solution = extra_sensors.gps(truth, x, self._extra_rng["gps"])
            solution["fix_type"] = np.full(len(truth.t_s), fp.SPEC.enums["gps_fix"].values["fix_3d"])
            solution["satellites"] = np.full(len(truth.t_s), x.gps_satellites)
            out.append(("GPS", s.rate_hz // s.gps_rate_hz, solution))
        return out
