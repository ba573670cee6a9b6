"""The simulated flight board: sampling clock, MPU-6050, onboard AHF in float32, frames, commands.

Timing. The board's crystal runs ``clock_drift_ppm`` fast: device time = true time × (1 + drift).
Sample k is read at device time ``k / rate_hz`` plus an interrupt-latency jitter (normal, σ
``sample_jitter_us``) and stamped with that device time in µs (``t_us`` wraps at 2³²). The truth is
taken at the true instant of each read, so the host sees real clock drift and jitter.

Boot. At power-up the board averages the gyro for ``boot_calibration_s`` (every profile starts at
rest) and writes the result into the chip's offset registers, as flight firmwares do; it writes the
stored accelerometer offsets too (``accel_calibrated``: the bench calibration the paper did before
its tests, equal to the part's turn-on zero-g bias). The average is used only if the craft was still
over the window (``still``: as ArduPilot's ``AP_InertialSensor::_init_gyro`` skips an average taken
while the accelerometer changed); otherwise the board writes its last calibration, which it keeps
over resets (the STM32 port: in its backup registers), or none if it never had one. ``CONFIG.gyro_calibration`` says which. Then it
sends ``CONFIG`` and starts streaming:

- each sample: ``IMU_RAW`` (mode raw or both), ``ATTITUDE`` from the onboard AHF (estimated or both);
- every second: ``STATUS``; ``MAG_RAW``/``BARO``/``GPS`` at their rates when enabled.

One sequence counter numbers every downlink frame, so the host counts lost frames of any type. The
onboard AHF runs in every mode (a mode switch finds it converged) on the same numbers the host gets:
counts converted with ``groundstation.units``, rotated to the body by the mounting, ``dt`` from the
device timestamps.

Reboot and clock jump (to test the ground station): ``reboot_after_s`` > 0 resets the board once at
that true time, as a brown-out does: the clock restarts at 0, the sequence counter at 0, the onboard
filter, mode, filter settings and the chip's gyro offset registers start over, and it boots again
(calibration, CONFIG); only the stored calibration survives. ``clock_jump_after_s`` > 0 makes the
clock jump ahead by ``clock_jump_s`` at that time, the rest going on. The truth (``on_samples``)
keeps the uninterrupted device time and says what the board's clock read.

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
from groundstation.sim.settings import MODES, FirmwareSettings

MODE_NAMES = {value: name for name, value in MODES.items()}
_COMMANDS = fp.SPEC.enums["command"].values
_FILTER_PARAMS = {value: name for name, value in fp.SPEC.enums["filter_param"].values.items()}
_RESULT = fp.SPEC.enums["ack_result"].values
_Q14 = 1.0 / fp.SPEC.frame("ATTITUDE").fields[1].scale
GYRO_CALIBRATION = fp.SPEC.enums["gyro_calibration"].values
# Still enough to calibrate at boot: over the window, the RMS deviation from the mean of the gyro and of
# the accelerometer (the three axes together). At rest the MPU-6050's noise is 0.06 deg/s and 5 mg at
# 100 Hz (0.19 deg/s, 15 mg at 1 kHz); a turn, a tilt or a flight's vibration is far above. A steady
# rotation about gravity looks still, as on ArduPilot. The C core has the same numbers (gs_flight.h).
STILL_GYRO_RMS_DPS = 0.5
STILL_ACCEL_RMS_G = 0.03
FIRMWARE_VERSION = (0, 1, 0)
PREFETCH_SAMPLES = 50


def battery_v(t_s: float) -> float:
    """The simulated battery at true time ``t_s``: a 3S LiPo over a 10-minute flight."""
    return max(10.5, 12.6 - 1.5 * t_s / 600.0)


def cpu_load_pct(mode: int) -> float:
    """The simulated board's CPU load in ``mode`` (the AHF runs in every mode; sending costs)."""
    return 25.0 if mode == MODES["raw"] else 40.0


def within_rms(n: int, sums, squares, lsb_per_unit: float, limit: float) -> bool:
    """Whether ``n`` samples of three axes with these count sums and sums of squares (exact integers)
    deviate from their mean by at most ``limit`` RMS (physical units, ``lsb_per_unit`` counts each):
    Σ_axes (n·Σx² - (Σx)²) = n² × the summed variance, in double in this order, as gs_flight.c's."""
    spread = 0.0
    for total, square in zip(sums, squares):
        spread += float(n) * float(square) - float(total) * float(total)
    bound = limit * lsb_per_unit * float(n)
    return spread <= bound * bound


@dataclasses.dataclass
class Calibration:
    """A gyro calibration running over samples ``first`` .. ``end`` - 1: the gyro average, and the
    count sums that say whether the craft was still."""

    first: int
    end: int
    sum_dps: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    counts: dict[str, list[int]] = dataclasses.field(default_factory=lambda: {k: [0, 0, 0] for k in ("gyr", "gyr2", "acc", "acc2")})

    def add(self, gyr_dps: np.ndarray, raw: ImuSamples) -> None:
        self.sum_dps += gyr_dps.sum(axis=0)
        for name, counts in (("gyr", raw.gyr_counts), ("acc", raw.acc_counts)):
            counts = counts.astype(np.int64)
            self.counts[name] = [a + int(b) for a, b in zip(self.counts[name], counts.sum(axis=0))]
            self.counts[name + "2"] = [a + int(b) for a, b in zip(self.counts[name + "2"], (counts * counts).sum(axis=0))]

    def still(self, accel_fs_g: int, gyro_fs_dps: int) -> bool:
        n, c = self.end - self.first, self.counts
        return (within_rms(n, c["gyr"], c["gyr2"], units.GYRO_LSB_PER_DPS[gyro_fs_dps], STILL_GYRO_RMS_DPS)
                and within_rms(n, c["acc"], c["acc2"], units.ACCEL_LSB_PER_G[accel_fs_g], STILL_ACCEL_RMS_G))


@dataclasses.dataclass(frozen=True)
class SentFrame:
    t_s: float  # true (simulation) time the frame leaves the board
    data: bytes
    t_us: int | None  # the frame's device timestamp if it has one (for latency measurements)


class Firmware:
    """Step with ``run_until(t_s)``; feed uplink frames to ``command``. Deterministic from ``seed``.

    ``on_samples(t_dev_us, truth, imu_samples, board_us, board_epoch)``, if given, receives every
    streamed sample block: the device time (uninterrupted, µs), the truth at each read, the registers
    read, what the board's clock read (µs, before the 32-bit wrap) and ``clock_epoch``.
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
        self._clock_epoch = 0
        self._mishaps = sorted((self._sample_at(t_s), what) for t_s, what in
                               ((settings.reboot_after_s, self._reboot), (settings.clock_jump_after_s, self._jump_clock)) if t_s > 0)
        self._last_t_us: int | None = None  # the board's timestamp of its last sample
        self._queued: list[tuple[str, dict]] = []  # frames to send before the next sample
        self.stored_gyro_offset_dps: np.ndarray | None = None  # the last calibration: survives resets
        self._boot()

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
            end = k_end if self._calibration is None else min(k_end, self._calibration.end)
            if self._mishaps:
                end = min(end, self._mishaps[0][0])
            self._run_block(self._k, end, out)
            self._k = end
            if self._calibration is not None and self._k == self._calibration.end:
                self._finish_calibration()
            while self._mishaps and self._k >= self._mishaps[0][0]:
                self._mishaps.pop(0)[1]()
        return out

    def _sample_at(self, t_s: float) -> int:
        """The first sample at or after true time ``t_s``."""
        return math.ceil(t_s * self._drift / self._period_s - 1e-9)

    @property
    def clock_epoch(self) -> int:
        """How many times the board's clock restarted or jumped so far (the truth's ``board_epoch``)."""
        return self._clock_epoch

    def _boot(self) -> None:
        """Power-up: the gyro calibration (streaming starts after it), or none (then the turn-on bias)."""
        self._boot_k = self._k  # the board counts its samples from power-up (STATUS every second)
        self._booting, self._calibration = True, None
        self.gyro_calibration = GYRO_CALIBRATION["none"]
        if self.settings.boot_calibration_s > 0:
            self._start_calibration(self.settings.boot_calibration_s)
        else:  # a board that skips it streams its turn-on gyro bias
            self._end_boot()

    def _reboot(self) -> None:
        self._epoch_us = round(self._k * self._period_s * 1e6)
        self._clock_epoch += 1
        self._seq, self._queued, self._last_t_us = 0, [], None
        self.mode = MODES[self.settings.mode]
        self.ahf_settings = self._boot_ahf_settings
        self.onboard, self._onboard_q = Ahf(self.ahf_settings, dtype=np.float32), None
        self.imu.gyro_offset_dps = np.zeros(3)
        self._boot()

    def _jump_clock(self) -> None:
        self._epoch_us -= round(self.settings.clock_jump_s * 1e6)
        self._clock_epoch += 1

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
        self._calibration = Calibration(self._k, self._k + n)

    def _finish_calibration(self) -> None:
        c, s = self._calibration, self.settings
        self._calibration = None
        if not self._booting or c.still(s.accel_fs_g, s.gyro_fs_dps):
            # a commanded one is trusted: the user was told to keep the craft still
            self.imu.gyro_offset_dps = self.imu.gyro_offset_dps + c.sum_dps / (c.end - c.first)
            self.gyro_calibration = GYRO_CALIBRATION["boot" if self._booting else "command"]
            self.stored_gyro_offset_dps = self.imu.gyro_offset_dps.copy()
        elif self.stored_gyro_offset_dps is not None:  # moving at boot: the registers are 0, write the stored one
            self.imu.gyro_offset_dps = self.stored_gyro_offset_dps.copy()
            self.gyro_calibration = GYRO_CALIBRATION["stored"]
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
            "gyro_calibration": self.gyro_calibration,
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
            self._calibration.add(gyr_dps, raw)
        if self._booting:
            return
        if self._on_samples is not None:
            self._on_samples(t_dev_us, truth, raw, t_dev_us - self._epoch_us, self._clock_epoch)
        # Exactly the host's conversions (the normalised-gradient AHF amplifies even 1-ulp differences).
        gyr_body = (units.gyro_counts_to_rad_s(raw.gyr_counts, s.gyro_fs_dps) @ self._body_from_sensor.T).tolist()
        acc_body = (units.accel_counts_to_g(raw.acc_counts, s.accel_fs_g) @ self._body_from_sensor.T).tolist()
        # The filter starts with the stream: its first dt is the nominal period, as a host assumes.
        # dt from the board's own 32-bit timestamps as a signed difference, as the C core: a clock jump
        # is a jump of dt too.
        t_us_all = (t_dev_us - self._epoch_us) & 0xFFFFFFFF
        prev = self._last_t_us if self._last_t_us is not None else int(t_us_all[0]) - round(self._period_s * 1e6)
        dt_us = (np.diff(t_us_all, prepend=prev) + (1 << 31)) % (1 << 32) - (1 << 31)
        dt_s = (dt_us * 1e-6).tolist()
        self._last_t_us = int(t_us_all[-1])
        # The die temperature as the firmware reports it: TEMP_OUT counts, then counts/340 + 36.53.
        temp_c = units.temperature_counts_to_c(units.temperature_c_to_counts(raw.temperature_c))
        extras = self._extra_readings(truth)
        per_status = s.rate_hz
        acc_counts, gyr_counts = raw.acc_counts.tolist(), raw.gyr_counts.tolist()
        t_true_list, t_us_list = t_true.tolist(), t_us_all.tolist()
        for i in range(n):
            t, t_us = t_true_list[i], t_us_list[i]
            for name, values in self._queued:
                self._emit(out, t, name, **values)
            self._queued.clear()
            q, diag = self.onboard.step(gyr_body[i], acc_body[i], dt_s[i])
            self._onboard_q = q
            if (k0 + i - self._boot_k) % per_status == 0:
                self._emit_status(out, t, t_us)
            if self.mode != MODES["estimated"]:
                (ax, ay, az), (gx, gy, gz) = acc_counts[i], gyr_counts[i]
                self._emit(out, t, "IMU_RAW", t_us=t_us, acc_x=ax, acc_y=ay, acc_z=az, gyr_x=gx, gyr_y=gy, gyr_z=gz,
                           temperature=round(temp_c[i] * 100))
            if self.mode != MODES["raw"]:
                self._emit_attitude(out, t, t_us, q, diag)
            for name, every, values in extras:
                if (k0 + i - self._boot_k) % every == 0:
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
