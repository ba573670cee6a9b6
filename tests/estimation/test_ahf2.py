"""AHF2 (estimation/ahf2.py): its low-pass in the almost inertial frame has the documented shape, its
time constant follows the turn rate, and on BROAD it is at least as accurate as VQF."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import signal

from groundstation.datasets import read_csv
from groundstation.estimation import create
from groundstation.estimation.ahf2 import Ahf2Settings
from groundstation.estimation.evaluation import evaluate_trial, inclination_error_rad
from groundstation.sim.imu import MPU6050Settings
from groundstation.sim.offline import simulate

# BROAD dev trials where AHF2 and VQF differ most: fast combined motion, slow translation, vibration.
TRIALS = ["21_undisturbed_fast_combined", "11_undisturbed_slow_translation_B", "27_disturbed_phone_vibration_B"]
DT_S = 0.01


def test_tilt_follows_a_swaying_force_as_a_second_order_butterworth():
    """A still, level sensor whose specific force sways horizontally (amplitude A, 0.1 Hz): the
    estimated tilt sways by A |H(jω)|, H the analog Butterworth of order 2 at ω_c = √2/τ (scipy as the
    oracle). Bias estimation off, so the response is the low-pass's alone."""
    tau_s, amplitude_g, freq_hz = 5.0, 0.1, 0.1
    t = np.arange(0.0, 200.0, DT_S)
    acc = np.column_stack([amplitude_g * np.sin(2 * np.pi * freq_hz * t), np.zeros_like(t), -np.ones_like(t)])
    est = create("ahf2", {"tau_acc_s": tau_s, "rest_bias": False, "motion_bias_ki": 0.0})
    q, _ = est.run(np.zeros_like(acc), acc, DT_S)
    w, x, y, z = q.T
    pitch_rad = np.arcsin(np.clip(2.0 * (w * y - x * z), -1.0, 1.0))
    b, a = signal.butter(2, math.sqrt(2.0) / tau_s, analog=True)
    gain = abs(signal.freqs(b, a, worN=[2 * np.pi * freq_hz])[1][0])
    steady = t > 100.0
    swing_rad = 0.5 * (pitch_rad[steady].max() - pitch_rad[steady].min())
    # |H| = 0.199 here; a first-order low-pass at τ passes 0.303, two first-order stages at τ/2 0.288
    assert swing_rad == pytest.approx(math.atan(amplitude_g * gain), rel=0.02)


def test_time_constant_halves_at_the_reference_turn_rate():
    """Turning steadily at ω_ref for many τ_rate: τ = τ_acc / (1 + ω̄/ω_ref) → τ_acc / 2; still: τ_acc."""
    n = int(60.0 / DT_S)
    est = create("ahf2", {"tau_acc_s": 5.0, "rate_ref_rad_s": 4.0, "tau_rate_s": 10.0, "rest_bias": False, "motion_bias_ki": 0.0})
    gyr = np.tile([0.0, 0.0, 4.0], (n, 1))  # yaw: gravity stays on z
    acc = np.tile([0.0, 0.0, -1.0], (n, 1))
    _, diag = est.run(gyr, acc, DT_S)
    assert diag["tau_acc_s"][0] == pytest.approx(5.0, rel=0.01)
    assert diag["tau_acc_s"][-1] == pytest.approx(2.5 * (1.0 + math.exp(-6.0) / 2.0), rel=0.01)


def test_still_after_switch_on_bias_and_tilt_settle_within_seconds():
    """A still, level sensor with a gyro bias of 0.5 °/s on x and noisy readings: rest is detected after
    1.5 s, the bias is then the mean over the rest so far (within 0.03 °/s at 3 s), and the tilt stays
    within 0.5° from the switch-on (noise on the first samples, then 1.5 s of undetected bias). Before
    (bias low-passed over 2 s from zero, low-pass started from the first sample): 0.27 °/s, 1.3°."""
    rng = np.random.default_rng(5)
    n = int(10.0 / DT_S)
    bias_rad_s = math.radians(0.5)
    gyr = rng.normal(0.0, math.radians(0.1), (n, 3)) + [bias_rad_s, 0.0, 0.0]
    acc = rng.normal(0.0, 0.005, (n, 3)) + [0.0, 0.0, -1.0]
    q, diag = create("ahf2").run(gyr, acc, DT_S)
    i3 = int(3.0 / DT_S)
    assert diag["rest"][i3] == 1.0
    assert diag["bias_x_rad_s"][i3] == pytest.approx(bias_rad_s, abs=math.radians(0.03))
    w, x, y, z = q.T
    tilt_deg = np.degrees(np.arccos(np.clip(1.0 - 2.0 * (x * x + y * y), -1.0, 1.0)))
    assert tilt_deg.max() < 0.5


def test_invalid_settings_are_refused():
    for bad in ({"rate_ref_rad_s": 0.0}, {"tau_rate_s": -1.0}, {"lambda_min": 20.0}):
        with pytest.raises(ValueError):
            create("ahf2", bad)


def test_at_least_as_accurate_as_vqf_on_broad(broad_dir):
    """Measured (bench/bench_estimators.out.md): ahf2 1.19°, 0.30°, 0.33° on these trials (1.53°, 0.30°,
    0.35° before the gyro scale was learnt in motion); VQF 1.72°, 0.42°, 0.37°. Bounds: the measured
    figures plus 0.03° for rounding across machines."""
    figures = [evaluate_trial(read_csv(broad_dir / f"{name}.csv.gz"), ["ahf2", "vqf"]) for name in TRIALS]
    ahf2 = [f["ahf2"]["incl_rmse_deg"] for f in figures]
    vqf = [f["vqf"]["incl_rmse_deg"] for f in figures]
    assert ahf2 == pytest.approx([1.19, 0.30, 0.33], abs=0.03)
    assert np.mean(ahf2) <= np.mean(vqf) - 0.05, (ahf2, vqf)


def test_no_bias_wind_up_in_ten_minutes_of_aggressive_flight():
    """Ten minutes of aggressive flight without a moment's rest (the simulator's ``aggressive``
    profile) with 1 °/s of gyro bias the boot calibration missed on every axis, and no other bias
    (no warm-up drift, no random walk), so the true bias is known: the in-motion estimate stays clear
    of its 2 °/s clamp, its mean over the last five minutes is on the true bias, and the inclination
    error over those minutes is below VQF's in the same run. Measured: |b| at most 1.52 °/s, the
    mean within 0.16 °/s, 2.1° against VQF's 2.7°. Before the integral was mapped with the low-passed
    rotation (ahf2.py, step 7) it wound up to the clamp on x and y, its mean 0.9 °/s off on y (1.1 °/s
    on x with k_i = 0.1 /s), and the error was 2.8°, above VQF's."""
    imu = MPU6050Settings(gyro_bias_tempco_dps_per_c=0.0, gyro_bias_walk_dps_rts=0.0)
    run = simulate("aggressive", 600.0, seed=0, imu=imu, gyro_bias_left_dps=1.0)
    true_bias_dps = np.degrees(np.median(run.gyr_rad_s[: int(1.0 / run.dt_s)], axis=0))  # the first second is still
    q, diag = create("ahf2").run(run.gyr_rad_s, run.acc_g, run.dt_s)
    bias_dps = np.degrees(np.column_stack([diag[f"bias_{a}_rad_s"] for a in "xyz"]))
    assert np.abs(bias_dps[int(120.0 / run.dt_s) :]).max() < 1.7, np.abs(bias_dps).max(axis=0)
    late = slice(int(300.0 / run.dt_s), None)
    assert bias_dps[late].mean(axis=0) == pytest.approx(true_bias_dps, abs=0.25)
    # the error is mostly the flight's accelerations; VQF in the same run is the reference
    rmse_deg = {}
    for name, est_q in (("ahf2", q), ("vqf", create("vqf").run(run.gyr_rad_s, run.acc_g, run.dt_s)[0])):
        error_deg = np.degrees(inclination_error_rad(est_q[late], run.truth.q_body_to_ned[late], truth_frame="NED"))
        rmse_deg[name] = np.sqrt(np.mean(error_deg**2))
    assert rmse_deg["ahf2"] < rmse_deg["vqf"], rmse_deg


def wobble(rng, still_s, wobble_s, freq_hz, amplitude_dps, axis, bias_dps, noise_dps):
    """Still for ``still_s``, a turn by 30° in one second, then turning back and forth about the same
    fixed ``axis`` (body) at ``freq_hz`` with a peak rate of ``amplitude_dps`` for ``wobble_s``: gyro
    (bias + white noise) and accelerometer (gravity in the body, exactly, plus 2 mg noise), 100 Hz; and
    where the body turns."""
    t = np.arange(0.0, still_s + 1.0 + wobble_s, DT_S)
    turning = t >= still_s
    swinging = t >= still_s + 1.0
    rate_rad_s = np.where(swinging, np.radians(amplitude_dps) * np.sin(2 * np.pi * freq_hz * (t - still_s - 1.0)), np.where(turning, np.radians(30.0), 0.0))
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    angle_rad = np.cumsum(rate_rad_s) * DT_S  # the body's turn about the axis so far
    down = np.array([0.0, 0.0, -1.0])  # specific force of a level, still body (g), turned into the body
    cos, sin = np.cos(angle_rad)[:, None], np.sin(angle_rad)[:, None]
    acc = down * cos - np.cross(axis, down) * sin + axis * (axis @ down) * (1.0 - cos)
    gyr = rate_rad_s[:, None] * axis + np.radians(bias_dps) + rng.normal(0.0, np.radians(noise_dps), (len(t), 3))
    return gyr, acc + rng.normal(0.0, 0.002, acc.shape), turning


def test_a_back_and_forth_turn_is_not_rest_and_does_not_move_the_bias():
    """Issue 33: on a slow-translation trial at 100 Hz the bias jumped to +1.58 °/s while the sensor
    turned at 7-11 °/s. A turn back and forth at 2 Hz, 9 °/s peak, about a horizontal axis: its
    low-pass (τ_rest 0.5 s) is 1.4 °/s, under the 2 °/s threshold, so a rest test on the low-passed
    gyro alone saw rest, and the first "rest" sample set the bias to the low-passed rate. The raw gyro
    against its low-pass sees the turn at once (VQF's test), and the bias stays where the still start
    put it."""
    rng = np.random.default_rng(3)
    gyr, acc, turning = wobble(rng, 5.0, 30.0, 2.0, 9.0, (1.0, 0.0, 0.0), (0.3, -0.2, 0.1), 0.1)
    q, diag = create("ahf2").run(gyr, acc, DT_S)
    assert not diag["rest"][turning].any()
    bias_dps = np.degrees(np.column_stack([diag[f"bias_{a}_rad_s"] for a in "xyz"]))
    assert np.abs(bias_dps[turning] - (0.3, -0.2, 0.1)).max() < 0.1
    w, x, y, z = q.T
    tilt_deg = np.degrees(np.arccos(np.clip(1.0 - 2.0 * (x * x + y * y), -1.0, 1.0)))
    true_tilt_deg = np.degrees(np.abs(np.cumsum(gyr[:, 0] - np.radians(0.3)) * DT_S))  # about x only
    assert np.abs(tilt_deg - true_tilt_deg)[turning].max() < 0.3


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**16),
    freq_hz=st.floats(0.3, 5.0),
    amplitude_dps=st.floats(3.0, 60.0),
    axis=st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(0.2, 1.0)),
    bias_dps=st.tuples(*[st.floats(-1.0, 1.0)] * 3),
)
def test_no_bias_step_above_the_gyro_noise_while_turning(seed, freq_hz, amplitude_dps, axis, bias_dps):
    """Still, then turning back and forth for 20 s: no one-sample change of the bias estimate is larger
    than the gyro's noise (0.1 °/s standard deviation per axis and sample) while the body turns."""
    gyr, acc, turning = wobble(np.random.default_rng(seed), 5.0, 20.0, freq_hz, amplitude_dps, axis, bias_dps, 0.1)
    _, diag = create("ahf2").run(gyr, acc, DT_S)
    bias_dps = np.degrees(np.column_stack([diag[f"bias_{a}_rad_s"] for a in "xyz"]))
    step_dps = np.abs(np.diff(bias_dps, axis=0))[turning[1:]]
    assert step_dps.max() < 0.1, step_dps.max()


def test_gyro_scale_errors_are_learnt_in_motion():
    """Five minutes of aggressive flight with a gyro whose scale is off by +0.8 %, -0.5 % and +0.6 % on
    x, y, z (and no other sensor error but noise and the boot calibration's bias): the scale estimate
    (step 7) has each axis's sign and is within 0.3 % of it over the last 100 s, and the inclination
    error there is lower than without it. Measured: 0.53 %, -0.54 %, 0.32 %; 1.28° against 1.43°."""
    imu = MPU6050Settings(gyro_bias_tempco_dps_per_c=0.0, gyro_bias_walk_dps_rts=0.0, gyro_scale_tolerance=0.0, cross_axis_tolerance=0.0,
                          accel_scale_tolerance=0.0)
    run = simulate("aggressive", 300.0, seed=0, imu=imu)
    scale_true = np.array([0.008, -0.005, 0.006])
    gyr = run.gyr_rad_s * (1.0 + scale_true)
    late = slice(int(200.0 / run.dt_s), None)
    rmse_deg = {}
    for k in (0.0, Ahf2Settings().motion_scale_k):
        q, diag = create("ahf2", {"motion_scale_k": k}).run(gyr, run.acc_g, run.dt_s)
        error_deg = np.degrees(inclination_error_rad(q[late], run.truth.q_body_to_ned[late], truth_frame="NED"))
        rmse_deg[k] = np.sqrt(np.mean(error_deg**2))
    scale = np.column_stack([diag[f"scale_{a}"] for a in "xyz"])[late].mean(axis=0)
    assert scale == pytest.approx(scale_true, abs=0.003)
    assert rmse_deg[Ahf2Settings().motion_scale_k] < 0.95 * rmse_deg[0.0], rmse_deg
