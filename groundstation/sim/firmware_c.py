"""The simulated flight board running the reference firmware's C core: firmware in the loop.

Everything physical is ``firmware.Firmware``'s (crystal drift, sampling jitter, the MPU-6050 and its
offset registers, the truth, the battery); what the firmware does with each sample is the C core of
``firmware_protocol/reference`` (the code flashed on the STM32), called through ctypes: boot and
commanded gyro calibration, the onboard AHF, the frames and the answers to commands. For equal
scenarios the bytes equal the Python model's (tests/firmware/test_core.py).

The core reads the MPU-6050 only, like the reference board: no magnetometer, barometer or GPS.
"""

from __future__ import annotations

import firmware_protocol as fp
from firmware_protocol.reference import host
from groundstation import units
from groundstation.sim.firmware import FIRMWARE_VERSION, MODES, Firmware, FirmwareSettings, SentFrame, battery_v, cpu_load_pct

_TIMESTAMPED = {t.id for t in fp.SPEC.frames if "t_us" in t.field_names}


class CFirmware(Firmware):
    """``Firmware``'s interface (``run_until``, ``command``, ...) with the C core deciding every frame."""

    def __init__(self, profile, settings=FirmwareSettings(), *args, **kwargs):
        if settings.mag_rate_hz or settings.baro_rate_hz or settings.gps_rate_hz:
            raise ValueError("the reference C firmware reads the MPU-6050 only: no magnetometer, barometer or GPS")
        self._core: host.FlightCore | None = None  # the base class's __init__ starts the boot calibration
        super().__init__(profile, settings, *args, **kwargs)
        self._core = self._power_up()

    def _power_up(self) -> host.FlightCore:
        """The core as the board starts it: fresh, with the calibration it kept over the reset."""
        s = self.settings
        self.onboard = None  # the estimate is the core's
        return host.FlightCore(
            rate_hz=s.rate_hz, accel_fs_g=s.accel_fs_g, gyro_fs_dps=s.gyro_fs_dps, mounting=s.mounting,
            mode=MODES[s.mode], boot_calibration_s=s.boot_calibration_s, fw_version=FIRMWARE_VERSION,
            ahf=self._boot_ahf_settings, stored_gyro_offset_dps=self.stored_gyro_offset_dps,
        )

    def _reboot(self) -> None:
        super()._reboot()
        self._core = self._power_up()

    # The core calibrates and boots itself: the Python model's bookkeeping of both stays idle.
    def _start_calibration(self, seconds: float) -> None:
        pass

    def _end_boot(self) -> None:
        pass

    def command(self, frame: fp.Frame) -> None:
        """The uplink frame, back in its wire bytes, to the core (answered before the next sample)."""
        self._core.uplink(fp.encode(frame))

    def _run_block(self, k0: int, k1: int, out: list) -> None:
        core = self._core
        for k in range(k0, k1):
            # One sample at a time: a calibration that ends here changes the registers of the next.
            t_dev_us, truth, raw = self._sampled(k, k + 1)
            t, t_us = float(truth.t_s[0]), (int(t_dev_us[0]) - self._epoch_us) & 0xFFFFFFFF
            if not core.booting and self._on_samples is not None:
                self._on_samples(t_dev_us, truth, raw, t_dev_us - self._epoch_us, self._clock_epoch)
            temperature = int(units.temperature_c_to_counts(raw.temperature_c)[0])
            registers = (*raw.acc_counts[0].tolist(), *raw.gyr_counts[0].tolist(), temperature)
            data = core.sample(t_us, registers, battery_v(t), cpu_load_pct(core.mode))
            for frame in host.split_frames(data):
                out.append(SentFrame(t, frame, t_us if frame[2] in _TIMESTAMPED else None))
                self._seq = (frame[3] + 1) & 0xFF
            offset_dps = core.take_gyro_offset()
            if offset_dps is not None:  # written to the chip, and kept for the next boot (over a reset)
                self.imu.gyro_offset_dps = self.imu.gyro_offset_dps + offset_dps
                self.stored_gyro_offset_dps = self.imu.gyro_offset_dps.copy()
