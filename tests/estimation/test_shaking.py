"""No divergence: a minute of violent shaking, then rest; every IMU-only estimator is back within 2° of
the simulator's truth within 5 s of rest (integral wind-up or unbounded corrections would keep it off).
The paper's ahf is exempt: its λ_min of 0.2 rad/s is the paper's, and slow by design."""

import numpy as np
import pytest

from groundstation.estimation import create
from groundstation.datasets import read_csv
from groundstation.estimation.evaluation import evaluate_trial, inclination_error_rad
from groundstation.sim.offline import simulate
from groundstation.sim.profiles import REST_S, Moves, Profile
from groundstation.sim.seeds import stream

SHAKE_S, REST_AFTER_S = 60.0, 10.0
IMU_ONLY = ["hf", "ecf", "cf1", "kf", "ekf", "vqf", "ahf2"]


def shaking_profile(seed=0):
    """Position jumps of ±5 cm every 0.1 s (peaks near 6 g) and tilts of up to ±40° every 0.25 s,
    for SHAKE_S seconds after the initial rest; then level and still."""
    rng = stream(seed, "shaking test")

    def knots(step_s, amplitude):
        times = np.arange(REST_S, REST_S + SHAKE_S, step_s)
        values = rng.uniform(-amplitude, amplitude, len(times))
        values[0] = 0.0
        return Moves(np.append(times, REST_S + SHAKE_S), np.append(values, 0.0))

    channels = {axis: [knots(0.1, 0.05)] for axis in ("north", "east", "down")}
    channels |= {axis: [knots(0.25, np.radians(40.0))] for axis in ("roll", "pitch")}
    return Profile("shaking", REST_S + SHAKE_S + REST_AFTER_S, seed, channels)


@pytest.fixture(scope="module")
def shaken():
    return simulate(shaking_profile(), rate_hz=100.0)


@pytest.mark.parametrize("name", IMU_ONLY)
def test_back_within_2_degrees_5_s_after_a_minute_of_shaking(name, shaken):
    q, _ = create(name).run(shaken.gyr_rad_s, shaken.acc_g, shaken.dt_s)
    error_deg = np.degrees(inclination_error_rad(q, shaken.truth.q_body_to_ned, truth_frame="NED"))
    t = shaken.truth.t_s
    during = error_deg[(t > REST_S) & (t < REST_S + SHAKE_S)]
    assert during.max() > 1.0  # the shaking did disturb it
    settled = t >= REST_S + SHAKE_S + 5.0
    assert error_deg[settled].max() < 2.0, f"{error_deg[settled].max():.1f} deg 5 s after rest"


@pytest.mark.parametrize("name", ["ecf", "cf1", "kf"])
def test_fast_real_motion_does_not_wind_them_up(broad_dir, name):
    """BROAD dev trial 21 (fast rotation and translation combined, optical truth): unbounded integral
    and corrections made ECF 33°, CF1 17° and KF 57° RMS off (max 100°, 59°, 176°); bounded, each stays
    within the issue's limits on every sample."""
    trial = read_csv(broad_dir / "21_undisturbed_fast_combined.csv.gz")
    figures = evaluate_trial(trial, [name])[name]
    assert figures["incl_rmse_deg"] < 12.0 and figures["incl_max_deg"] < 20.0, figures


def test_hard_shaking_does_not_bias_the_accelerometer_correction(broad_dir):
    """BROAD dev trial 16 (fast translation): skipping the accelerometer whenever its norm passed 3 g
    dropped the large-norm half of every shake, so hf leaned toward the other half (12.4° RMS; 3.0°
    without the gate). Rejection now judges a low-passed deviation, and is off by default."""
    trial = read_csv(broad_dir / "16_undisturbed_fast_translation_B.csv.gz")
    assert evaluate_trial(trial, ["hf"])["hf"]["incl_rmse_deg"] < 4.0
