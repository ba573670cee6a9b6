"""The C AHF (gs_ahf.c) against the Python float32 AHF (estimation/ahf.py, dtype=np.float32): the same
float32 bits for every output of every sample, over a whole simulated flight and over the guard cases."""

import math
import struct

import numpy as np
import pytest

from firmware_protocol.reference import host
from groundstation.estimation.ahf import Ahf, AhfSettings
from groundstation.sim.offline import simulate


def bits(values) -> list[int]:
    return [struct.unpack("<I", struct.pack("<f", float(v)))[0] for v in values]


def run_both(settings: AhfSettings, gyr, acc, dt, q0=None):
    """Steps both filters and asserts equal bits on every sample; returns the C (status, q) per sample."""
    python = Ahf(settings, dtype=np.float32)
    python.reset(q0=q0)
    c = host.Ahf32(settings, q0=None if q0 is None else [np.float32(v) for v in python._q])
    outputs = []
    for k, (g, a, d) in enumerate(zip(gyr, acc, dt)):
        q, diag = python.step(g, a, d)
        status, cq, lam, e_a, err = c.step(g, a, d)
        expected = (diag.status, bits(q), bits([diag.lam, diag.e_a, diag.gravity_error]))
        got = (status, bits(cq), bits([lam, e_a, err]))
        assert got == expected, f"sample {k}: C {got} != Python {expected} (inputs {g}, {a}, {d})"
        outputs.append((status, cq))
    return outputs


def test_a_whole_simulated_flight_agrees_bit_for_bit(c_core):
    run = simulate("flight", 120.0, seed=5, accel_fs_g=4, gyro_fs_dps=500)
    outputs = run_both(AhfSettings(), run.gyr_rad_s.tolist(), run.acc_g.tolist(), [run.dt_s] * len(run))
    # Not a filter stuck at its start: the flight tilts it by tens of degrees, and λ adapts.
    tilt_deg = [math.degrees(2 * math.acos(min(1.0, math.hypot(q[0], q[3])))) for _, q in outputs]
    assert len(outputs) == 12000 and max(tilt_deg) > 20.0


def test_the_guards_agree_bit_for_bit(c_core):
    """Waiting for gravity, NaN and Inf, dt <= 0, a gap (re-initialised, yaw kept), free fall, shocks, over-range."""
    run = simulate("fast", 20.0, seed=2, accel_fs_g=8, gyro_fs_dps=250)
    gyr, acc, dt = run.gyr_rad_s.tolist(), run.acc_g.tolist(), [run.dt_s] * len(run)
    acc[:3] = [[0.0, 0.0, 0.0]] * 3  # no gravity yet: waiting
    gyr[100][1] = math.nan
    acc[200] = [math.inf, 0.0, -1.0]
    dt[300], dt[301] = 0.0, -0.01
    dt[400] = 1.5  # a gap: pitch and roll from gravity, yaw kept
    acc[500] = [0.0, 0.01, -0.05]  # free fall
    acc[600] = [0.0, 2.0, -3.5]  # a shock
    settings = AhfSettings(gyro_overrange_rad_s=0.95 * math.radians(250), lambda_min=0.1, lowpass=0.8, error_gain=12.0)
    outputs = run_both(settings, gyr, acc, dt)
    statuses = {s for s, _ in outputs}
    assert {1, 2, 4, 8, 16, 32} <= {bit for s in statuses for bit in (1, 2, 4, 8, 16, 32) if s & bit}


def test_a_given_start_attitude_is_normalised_alike(c_core):
    run = simulate("hover", 5.0, seed=9)
    run_both(AhfSettings(), run.gyr_rad_s.tolist(), run.acc_g.tolist(), [run.dt_s] * len(run), q0=(0.9, 0.1, -0.3, 0.2))


@pytest.mark.parametrize("settings", [AhfSettings(lambda_min=3.0), AhfSettings(lambda_min=-0.1), AhfSettings(acc_min_g=3.0)])
def test_invalid_settings_are_refused_by_both(c_core, settings):
    with pytest.raises(ValueError):
        Ahf(settings, dtype=np.float32)
    with pytest.raises(ValueError):
        host.Ahf32(settings)
