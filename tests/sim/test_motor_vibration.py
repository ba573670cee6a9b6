"""The simulator's motor vibration: off changes nothing; on, the vibration view finds it where it was put."""

import math

import numpy as np
import pytest

from groundstation import cli
from groundstation.analysis.vibration import find_peaks, spectrum, vibration_summary, ImuTable
from groundstation.session_makers.load import load_session
from groundstation.sim.imu import MPU6050Settings
from groundstation.sim.stream import Scenario, SimStream
from groundstation.sim.vibration import VibrationSettings, MotorVibration
from groundstation.units import STANDARD_GRAVITY_M_S2

HOVER_HZ = 30.0


def _bytes(scenario: Scenario) -> bytes:
    stream = SimStream(scenario)
    return b"".join(c.data for c in stream.advance(scenario.duration_s) + stream.flush())


def test_vibration_off_leaves_the_bytes_as_they_were():
    plain = Scenario(duration_s=8.0, seed=3)
    off = Scenario(duration_s=8.0, seed=3, imu=MPU6050Settings(vibration=VibrationSettings(0.0, 9.0, 9.0)))
    on = Scenario(duration_s=8.0, seed=3, imu=MPU6050Settings(vibration=VibrationSettings(HOVER_HZ)))
    assert _bytes(off) == _bytes(plain)
    assert _bytes(on) != _bytes(plain)


@pytest.fixture(scope="module")
def vibrating(tmp_path_factory):
    """A recorded hovering board (the static profile: 1 g of thrust throughout) with motors at 30 Hz."""
    out = tmp_path_factory.mktemp("vib") / "shake.gsrec"
    assert cli.main(["simulate", "--scenario", "static", "--duration", "40", "--seed", "2",
                     "--vibration", str(HOVER_HZ), "--out", str(out)]) == 0
    return out


def test_the_peak_is_found_at_the_motor_frequency_with_its_amplitude(vibrating):
    summary = vibration_summary(load_session(vibrating), start_s=5.0)  # after the motors spun up
    accel_z = next(p for p in summary.peaks if p.sensor == "accel" and p.axis == "z")
    assert accel_z.frequency_hz == pytest.approx(HOVER_HZ, abs=2.0)
    assert accel_z.amplitude == pytest.approx(VibrationSettings.accel_m_s2, rel=0.10)  # z gain 1 (sim/vibration.py)
    gyro_x = next(p for p in summary.peaks if p.sensor == "gyro" and p.axis == "x")
    assert gyro_x.frequency_hz == pytest.approx(HOVER_HZ, abs=2.0)
    assert gyro_x.amplitude == pytest.approx(VibrationSettings.gyro_dps, rel=0.10)
    assert summary.levels["accel"]["z"] == pytest.approx(VibrationSettings.accel_m_s2 * math.sqrt(1 + 0.5**2) / math.sqrt(2), rel=0.1)


def test_the_motor_harmonics_are_labelled_where_they_alias(vibrating):
    summary = vibration_summary(load_session(vibrating), start_s=5.0)
    accel_z = [p for p in summary.peaks if p.sensor == "accel" and p.axis == "z"]
    assert accel_z[0].label == "motor 1×"
    second = next(p for p in accel_z if p.label.startswith("motor 2×"))
    assert second.frequency_hz == pytest.approx(100.0 - 2 * HOVER_HZ, abs=2.0)  # 60 Hz sampled at 100 Hz
    assert "aliased" in second.label
    assert second.amplitude == pytest.approx(0.5 * VibrationSettings.accel_m_s2, rel=0.1)
    assert summary.notch["ardupilot"]["INS_HNTCH_FREQ"] == pytest.approx(HOVER_HZ, abs=1.0)
    assert summary.notch["ardupilot"]["INS_HNTCH_HMNCS"] == 3  # the 1st and 2nd harmonics
    assert summary.notch["px4"]["IMU_GYRO_NF0_FRQ"] == pytest.approx(HOVER_HZ, abs=1.0)


def test_the_rotor_frequency_follows_the_square_root_of_thrust():
    rate_hz, n = 1000.0, 20_000
    t = 10.0 + np.arange(n) / rate_hz  # after the spin-up
    for thrust_g in (0.64, 1.0, 1.44):
        force = np.tile([0.0, 0.0, -thrust_g * STANDARD_GRAVITY_M_S2], (n, 1))
        shake_dps, shake_m_s2 = MotorVibration(VibrationSettings(100.0))(t, force)
        peak = find_peaks(spectrum(ImuTable("sim", "accel", t, shake_m_s2)))[0]
        assert peak.frequency_hz == pytest.approx(100.0 * math.sqrt(thrust_g), abs=1.0)
        assert peak.amplitude == pytest.approx(VibrationSettings.accel_m_s2 * thrust_g, rel=0.05)  # force ∝ ω²
