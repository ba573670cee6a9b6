"""The MPU-6050 model against independent expectations: gravity, noise densities, saturation."""

import dataclasses

import numpy as np
from scipy import signal

from groundstation import mounting, units
from groundstation.sim.imu import MPU6050, MPU6050Settings
from groundstation.sim.profiles import make_profile

RATE_HZ = 100.0
# Only white noise left: no per-part errors, no drift.
NOISE_ONLY = dataclasses.replace(
    MPU6050Settings(), gyro_bias_tolerance_dps=0.0, accel_bias_tolerance_mg=(0.0, 0.0, 0.0), gyro_scale_tolerance=0.0,
    accel_scale_tolerance=0.0, cross_axis_tolerance=0.0, gyro_bias_tempco_dps_per_c=0.0,
    accel_bias_tempco_mg_per_c=(0.0, 0.0, 0.0), gyro_bias_walk_dps_rts=0.0, accel_bias_walk_ug_rts=0.0,
)


def rest_samples(settings, seconds, mount=mounting.DEFAULT_MOUNTING, accel_fs_g=2, gyro_fs_dps=250, seed=5):
    imu = MPU6050(settings, accel_fs_g, gyro_fs_dps, mount, RATE_HZ, seed)
    truth = make_profile("static", seconds, seed).truth(np.arange(0.0, seconds, 1.0 / RATE_HZ))
    return imu.sample(truth)


def test_at_rest_the_accelerometer_reads_one_g_up_for_any_mounting():
    for index in (mounting.DEFAULT_MOUNTING, 0, 13, 22):
        raw = rest_samples(NOISE_ONLY, 20.0, index)
        acc_g = units.accel_counts_to_g(raw.acc_counts, 2).mean(axis=0)
        up_in_sensor = mounting.body_to_sensor([0.0, 0.0, -1.0], index)  # body up = -z (FRD)
        assert np.allclose(acc_g, up_in_sensor, atol=1e-3), (index, acc_g)
        assert abs(units.gyro_counts_to_dps(raw.gyr_counts, 250).mean()) < 0.01


def test_noise_densities_match_the_datasheet_values():
    settings = MPU6050Settings()  # full model: drift and biases must not spoil the white-noise band
    raw = rest_samples(settings, 600.0)
    gyr_dps = units.gyro_counts_to_dps(raw.gyr_counts, 250)
    acc_g = units.accel_counts_to_g(raw.acc_counts, 2)
    f, gyr_psd = signal.welch(gyr_dps, fs=RATE_HZ, nperseg=512, axis=0, detrend="linear")
    _, acc_psd = signal.welch(acc_g, fs=RATE_HZ, nperseg=512, axis=0, detrend="linear")
    band = (f > 2.0) & (f < 45.0)
    gyr_density = np.sqrt(gyr_psd[band].mean(axis=0))
    acc_density_ug = np.sqrt(acc_psd[band].mean(axis=0)) * 1e6
    assert np.allclose(gyr_density, settings.gyro_noise_dps_rthz, rtol=0.04), gyr_density
    assert np.allclose(acc_density_ug, settings.accel_noise_ug_rthz, rtol=0.04), acc_density_ug


def test_turn_on_biases_follow_the_datasheet_tolerances():
    bias = np.array([MPU6050(MPU6050Settings(), 2, 250, 1, RATE_HZ, seed).gyro_turn_on_bias_dps for seed in range(300)])
    assert abs(bias.std() - 20.0 / 3.0) < 0.6 and abs(bias.mean()) < 0.8


def test_counts_saturate_at_full_scale_instead_of_wrapping():
    imu = MPU6050(NOISE_ONLY, 2, 250, mounting.DEFAULT_MOUNTING, RATE_HZ, 1)
    profile = make_profile("fast", 60.0, 2)
    t = np.arange(0.0, 60.0, 1.0 / RATE_HZ)
    raw = imu.sample(profile.truth(t))
    true_dps = np.degrees(mounting.body_to_sensor(profile.truth(t).rate_body_rad_s))
    over = np.abs(true_dps) > 32767 / 131.0
    assert over.any()
    assert np.array_equal(raw.gyr_counts[over], np.where(true_dps[over] > 0, 32767, -32768))
    inside = np.abs(true_dps) < 240.0
    assert np.abs(units.gyro_counts_to_dps(raw.gyr_counts, 250)[inside] - true_dps[inside]).max() < 0.3
