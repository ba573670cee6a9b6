"""The ellipsoid fit recovers a known hard iron and soft-iron matrix from simulated turning."""

import numpy as np
import pytest

from groundstation.estimation.magcal import fit
from groundstation.sim.extra_sensors import AuxSettings
from groundstation.sim.offline import simulate

FIELD_UT = float(np.linalg.norm(AuxSettings().mag_field_ned_ut))
SOFT = np.array([[1.10, 0.05, -0.03], [0.05, 0.90, 0.02], [-0.03, 0.02, 1.05]])  # symmetric distortion


def turning_readings(seed, soft=SOFT):
    """A flight (yaw turns, ±30° tilts) then flips (45-80° in pitch and roll): the same part (seed), its
    readings distorted by ``soft`` about the simulator's hard iron. Returns (readings, hard iron)."""
    runs = [simulate(name, 60.0, seed=seed, mag_rate_hz=100) for name in ("flight", "fast")]
    hard = runs[0].hard_iron_ut
    mag = np.vstack([r.mag_ut for r in runs])
    return (mag - hard) @ soft.T + hard, hard


@pytest.mark.parametrize("seed", [1, 2])
def test_recovers_hard_and_soft_iron(seed):
    mag, hard = turning_readings(seed)
    cal = fit(mag, field_ut=FIELD_UT)
    assert np.linalg.norm(cal.offset_ut - hard) < 0.5  # µT; readings have 0.3 µT noise per axis
    np.testing.assert_allclose(cal.soft_iron @ SOFT, np.eye(3), atol=0.01)
    radius = np.linalg.norm(cal.apply(mag), axis=1)
    assert np.nanstd(radius) < 0.5 and abs(np.nanmean(radius) - FIELD_UT) < 0.1


def test_without_a_field_strength_the_sphere_keeps_the_volume():
    mag, _ = turning_readings(3)
    cal = fit(mag)
    assert cal.field_ut == pytest.approx(FIELD_UT * np.linalg.det(SOFT) ** (1 / 3), rel=0.01)
    np.testing.assert_allclose(cal.apply([np.nan, np.nan, np.nan]), [np.nan] * 3)


def test_too_few_or_planar_readings_are_refused():
    mag, _ = turning_readings(4)
    with pytest.raises(ValueError, match="at least 9"):
        fit(mag[:8])
    with pytest.raises(ValueError, match="at least 9"):
        fit(np.full((100, 3), np.nan))
    # a level turn: the field sweeps a horizontal circle
    yaw = np.linspace(0, 2 * np.pi, 500)
    level_turn = np.column_stack([20 * np.cos(yaw), -20 * np.sin(yaw), np.full_like(yaw, 45.0)])
    with pytest.raises(ValueError, match="near a plane"):
        fit(level_turn + np.random.default_rng(0).normal(0, 0.3, level_turn.shape))
    with pytest.raises(ValueError, match="near a plane"):
        fit(np.tile([10.0, 2.0, 40.0], (50, 1)))
