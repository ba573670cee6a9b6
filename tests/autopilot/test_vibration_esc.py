"""Motor peaks labelled against ESC telemetry: a DataFlash log written here with a 1 kHz IMU shaken at the
ESC's RPM / 60 and its second harmonic, and a tone of something else; the notch tracks the ESC RPM."""

import numpy as np
import pytest

from groundstation.analysis.vibration import vibration_summary
from groundstation.session_makers.flight_log_session import load_log

from mavlink_helpers import write_dataflash

RPM = 4200.0  # 70 Hz
OTHER_HZ = 113.0  # not a harmonic of 70 Hz


@pytest.fixture(scope="module")
def esc_log(tmp_path_factory):
    t_s = np.arange(10_000) / 1000.0
    rotor_hz = RPM / 60.0
    gyr_x = 0.05 * np.sin(2 * np.pi * rotor_hz * t_s) + 0.02 * np.sin(2 * np.pi * 2 * rotor_hz * t_s + 1.0) \
        + 0.03 * np.sin(2 * np.pi * OTHER_HZ * t_s)
    time_us = (5_000_000 + t_s * 1e6).astype(int)
    imu = [(int(t), 0, g, 0.0, 0.0, 0.0, 0.0, -9.80665) for t, g in zip(time_us, gyr_x)]
    esc = [(int(t), 0, int(RPM), 15.8, 12.0) for t in time_us[::100]]
    path = tmp_path_factory.mktemp("esc") / "esc.bin"
    write_dataflash(path, {"IMU": ("QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ", imu),
                           "ESC": ("QBiff", "TimeUS,Instance,RPM,Volt,Curr", esc)})
    return path


def test_peaks_at_the_esc_rpm_harmonics_are_motor_peaks_and_the_notch_follows_the_esc(esc_log):
    summary = vibration_summary(load_log(esc_log, ["ahf"]))
    assert summary.motor["rotor_hz"] == pytest.approx(RPM / 60.0)
    gyro_x = {round(p.frequency_hz): p for p in summary.peaks if p.sensor == "gyro" and p.axis == "x"}
    assert gyro_x[70].label == "motor 1× (ESC rpm)" and gyro_x[70].amplitude == pytest.approx(np.degrees(0.05), rel=0.03)
    assert gyro_x[140].label == "motor 2× (ESC rpm)"
    assert gyro_x[113].label == ""
    notch = summary.notch["ardupilot"]
    assert notch["INS_HNTCH_FREQ"] == pytest.approx(70.0) and notch["INS_HNTCH_MODE"] == 3 and notch["INS_HNTCH_HMNCS"] == 3
