"""The C AHF (gs_ahf.c) against the Python float32 AHF (estimation/ahf.py, dtype=np.float32): the same
float32 bits for every output of every sample, over a whole simulated flight and over the guard cases."""

import math
import struct

import numpy as np
import pytest

from firmware_protocol.reference import host
from groundstation.estimation.ahf import Ahf, AhfSettings
from groundstation.estimation.base import ACC_SKIPPED
from groundstation.sim.offline import simulate


def bits(values) -> list[int]:
    return [struct.unpack("<I", struct.pack("<f", float(v)))[0] for v in values]


def run_both(settings: AhfSettings, gyr, acc, dt, q0=None):
    """Steps both filters and asserts equal bits on every sample (the outputs and the accelerometer gate's
    low-passed deviation); returns the C (status, q) per sample."""
    python = Ahf(settings, dtype=np.float32)
    python.reset(q0=q0)
    c = host.Ahf32(settings, q0=None if q0 is None else [np.float32(v) for v in python._q])
    outputs = []
    for k, (g, a, d) in enumerate(zip(gyr, acc, dt)):
        q, diag = python.step(g, a, d)
        status, cq, lam, e_a, err = c.step(g, a, d)
        expected = (diag.status, bits(q), bits([diag.lam, diag.e_a, diag.gravity_error, python._acc_dev]))
        got = (status, bits(cq), bits([lam, e_a, err, c.acc_dev_g]))
        assert got == expected, f"sample {k}: C {got} != Python {expected} (inputs {g}, {a}, {d})"
        outputs.append((status, cq))
    return outputs


def test_a_whole_simulated_flight_agrees_bit_for_bit(c_core):
    run = simulate("flight", 120.0, seed=5, accel_fs_g=4, gyro_fs_dps=500)
    outputs = run_both(AhfSettings(), run.gyr_rad_s.tolist(), run.acc_g.tolist(), [run.dt_s] * len(run))
    # Not a filter stuck at its start: the flight tilts it by tens of degrees, and λ adapts.
    tilt_deg = [math.degrees(2 * math.acos(min(1.0, math.hypot(q[0], q[3])))) for _, q in outputs]
    assert len(outputs) == 12000 and max(tilt_deg) > 20.0


GATE_OFF = {}  # the default: acc_deviation_max_g = inf
GATE_ON = {"acc_deviation_max_g": 0.1, "acc_window_s": 0.5}


SHAKING = range(800, 1000)  # 2 s of ±1.2 g along body z at 25 Hz: the norm swings from 0.2 to 2.2 g


def guard_case(gate: dict) -> tuple:
    """(settings, gyr, acc, dt): 20 s of fast flight through waiting for gravity, NaN and Inf, dt <= 0 and
    dt = inf, a gap (re-initialised, yaw kept), a long interval (limited), free fall, a shock, over-range and the 2 s of ``SHAKING``."""
    run = simulate("fast", 20.0, seed=2, accel_fs_g=8, gyro_fs_dps=250)
    gyr, acc, dt = run.gyr_rad_s.tolist(), run.acc_g.tolist(), [run.dt_s] * len(run)
    acc[:3] = [[0.0, 0.0, 0.0]] * 3  # no gravity yet: waiting
    gyr[100][1] = math.nan
    acc[200] = [math.inf, 0.0, -1.0]
    dt[300], dt[301] = 0.0, -0.01
    dt[350] = math.inf  # held like NaN; it made the gate's low-passed deviation NaN for good (inf / inf)
    dt[400] = 1.5  # a gap: pitch and roll from gravity, yaw kept
    dt[450] = 0.161  # a long interval: integrated as 1.5 running intervals (the interval rule)
    acc[500] = [0.0, 0.01, -0.05]  # free fall
    acc[600] = [0.0, 2.0, -3.5]  # a shock: 4 g, one sample
    for k in SHAKING:
        acc[k][2] += 1.2 * math.sin(2 * math.pi * 25.0 * k * run.dt_s)
    settings = AhfSettings(gyro_overrange_rad_s=0.95 * math.radians(250), lambda_min=0.1, lowpass=0.8, error_gain=12.0, **gate)
    return settings, gyr, acc, dt


@pytest.mark.parametrize("gate", [GATE_OFF, GATE_ON], ids=["gate-off", "gate-on"])
def test_the_guards_agree_bit_for_bit(c_core, gate):
    """Every guard (``guard_case``) with the low-passed deviation gate off and on."""
    settings, gyr, acc, dt = guard_case(gate)
    outputs = run_both(settings, gyr, acc, dt)
    statuses = {s for s, _ in outputs}
    assert {1, 2, 4, 8, 16, 32, 64} <= {bit for s in statuses for bit in (1, 2, 4, 8, 16, 32, 64) if s & bit}
    usable = [k for k, a in enumerate(acc) if 0.2 <= math.hypot(*a) < math.inf]  # above free fall, finite
    skipped = {k for k in usable if outputs[k][0] & ACC_SKIPPED}
    if gate is GATE_OFF:  # only free fall and non-finite readings are skipped, the shock and the shaking are used
        assert not skipped
    else:  # the shaking is rejected, on both halves of its swing, and the accelerometer is used again after it
        assert len(skipped & set(SHAKING)) > 150 and not skipped - set(range(800, 1200))
        assert any(math.hypot(*acc[k]) > 1.0 for k in skipped) and any(math.hypot(*acc[k]) < 1.0 for k in skipped)
        assert 600 in usable and 600 not in skipped  # one 4 g sample moves the low-passed deviation by < 0.1 g


def test_a_given_start_attitude_is_normalised_alike(c_core):
    run = simulate("hover", 5.0, seed=9)
    run_both(AhfSettings(), run.gyr_rad_s.tolist(), run.acc_g.tolist(), [run.dt_s] * len(run), q0=(0.9, 0.1, -0.3, 0.2))


@pytest.mark.parametrize("settings", [
    AhfSettings(lambda_min=3.0), AhfSettings(lambda_min=-0.1), AhfSettings(acc_min_g=-0.1), AhfSettings(acc_min_g=1.0),
    AhfSettings(acc_deviation_max_g=0.0), AhfSettings(acc_deviation_max_g=math.nan), AhfSettings(acc_window_s=0.0),
    AhfSettings(acc_window_s=-1.0), AhfSettings(max_gap_s=0.0), AhfSettings(max_gap_s=-1.0), AhfSettings(max_gap_s=math.nan),
], ids=lambda s: str({k: v for k, v in vars(s).items() if v != getattr(AhfSettings(), k)}))
def test_invalid_settings_are_refused_by_both(c_core, settings):
    with pytest.raises(ValueError):
        Ahf(settings, dtype=np.float32)
    with pytest.raises(ValueError):
        host.Ahf32(settings)


def test_the_edges_of_the_valid_settings_are_accepted_by_both(c_core):
    settings = AhfSettings(acc_min_g=0.0, acc_deviation_max_g=1e-3, acc_window_s=math.inf, max_gap_s=1e-3)
    Ahf(settings, dtype=np.float32)
    host.Ahf32(settings)
