"""Seed 003 (Ma et al.): each source's angle-error spectrum on the turntable, and the multi-sensor filter.

The simulated turntable (``sim.profiles`` ``turntable``: 60 s at rest, then ±25° sines on pitch, roll and
yaw with periods 47 s, 35 s, 15 s), magnetometer at 100 Hz calibrated by the ellipsoid fit of a
calibration flight of the same part (``flight`` then ``fast``, same seed: same hard iron). Errors are
against the simulator's truth (the paper's AHRS reference), over the motion after the rest.

- Figures 1-3 of the paper: the FFT amplitude spectrum (``spectrum``) of the pitch error of the
  integrated gyro, the accelerometer tilt and the compass tilt (the field at the true heading,
  ``compass.tilt_from_field_rad``), plus the heading error of the gyro and of the compass heading.
- Figure 10: the same for the filters ahf, hf, ecf (IMU), hfm, ecfm (MARG) and mcf.
- Tables: max-abs and RMS error of pitch, roll and heading for every source and filter, the paper's
  ±0.37° / ±0.8° beside mcf; the crossover design from the spectra against mcf's defaults; the
  calibration's recovered hard iron against the simulator's.
"""

from __future__ import annotations

import math

import numpy as np

from groundstation import quaternion as quat
from groundstation.spectrum import amplitude_spectrum
from groundstation.estimation import create
from groundstation.estimation.compass import heading_rad, tilt_from_field_rad
from groundstation.estimation.magcal import fit
from groundstation.estimation.mcf import McfSettings, crossover_from_spectra, inverse_variance_weight
from groundstation.estimation.tilt import acc_pitch_roll, wrap_pi
from groundstation.experiments.report import Figure, Result, Series, Table
from groundstation.sim.offline import simulate
from groundstation.sim.profiles import TURNTABLE_REST_S

NAME = "seed003"
TITLE = "Seed 003: error spectra of gyro, accelerometer and compass; multi-sensor complementary filter"
FILTERS = ("ahf", "hf", "ecf", "hfm", "ecfm", "mcf")
PAPER_PITCH_ROLL_DEG, PAPER_HEADING_DEG = 0.37, 0.8


def _wrap_deg(angle_rad):
    return np.degrees(wrap_pi(angle_rad))


def source_errors_deg(run, mag) -> dict[str, np.ndarray]:
    """(N, 3) errors (heading, pitch, roll) in degrees of each single-sensor source; NaN where it gives none."""
    truth = quat.to_euler_zyx(run.truth.q_body_to_ned)
    gyro_q, _ = create("hf", {"beta": 0.0}).run(run.gyr_rad_s, run.acc_g, run.dt_s)  # β = 0: gyro only
    acc = np.array([acc_pitch_roll(*a) for a in run.acc_g.tolist()])
    field_ned = quat.rotate(run.truth.q_body_to_ned[0], mag[0])  # at rest, heading 0: the local field
    dip = math.atan2(field_ned[2], math.hypot(field_ned[0], field_ned[1]))
    tilt = [tilt_from_field_rad(*m, y, dip, r) for m, y, r in zip(mag.tolist(), truth[:, 0], truth[:, 2])]
    compass = np.array([(np.nan, np.nan) if t is None else t for t in tilt])
    acc_q = quat.from_euler_zyx(np.zeros(len(acc)), acc[:, 0], acc[:, 1])
    nan = np.full(len(truth), np.nan)
    return {
        # unwrapped: the drift passes ±180° on long runs, and a wrap would read as a broadband jump
        "gyro": np.degrees(np.unwrap(np.radians(_wrap_deg(quat.to_euler_zyx(gyro_q) - truth)), axis=0)),
        "accelerometer": np.column_stack([nan, _wrap_deg(acc - truth[:, 1:])]),
        "compass": np.column_stack([_wrap_deg(heading_rad(acc_q, mag) - truth[:, 0]), _wrap_deg(compass - truth[:, 1:])]),
    }


def run(quick: bool = False) -> Result:
    seed = 1
    duration_s = TURNTABLE_REST_S + (40.0 if quick else 15 * 47.0)
    tt = simulate("turntable", duration_s, seed=seed, mag_rate_hz=100)
    cal_s = 30.0 if quick else 120.0
    cal = fit(np.vstack([simulate(p, cal_s, seed=seed, mag_rate_hz=100).mag_ut for p in ("flight", "fast")]))
    mag = cal.apply(tt.mag_ut)
    truth = quat.to_euler_zyx(tt.truth.q_body_to_ned)
    errors = source_errors_deg(tt, mag)
    for name in FILTERS:
        q, _ = create(name).run(tt.gyr_rad_s, tt.acc_g, tt.dt_s, mag=mag)
        errors[name] = _wrap_deg(quat.to_euler_zyx(q) - truth)
    moving = tt.truth.t_s >= TURNTABLE_REST_S
    errors = {k: e[moving] for k, e in errors.items()}

    rows = []
    for name, e in errors.items():
        cells = []
        for axis in (1, 2, 0):
            cells += [np.nanmax(np.abs(e[:, axis])), np.sqrt(np.nanmean(e[:, axis] ** 2))] if np.isfinite(e[:, axis]).any() else [math.nan] * 2
        paper = f"±{PAPER_PITCH_ROLL_DEG} / ±{PAPER_HEADING_DEG}" if name == "mcf" else ""
        rows.append([name, *cells, paper])
    accuracy = Table(
        f"Turntable errors against truth, {duration_s - TURNTABLE_REST_S:.0f} s of motion (seed {seed})",
        ["source / filter", "pitch max (deg)", "pitch RMS (deg)", "roll max (deg)", "roll RMS (deg)",
         "heading max (deg)", "heading RMS (deg)", "paper pitch,roll / heading (deg)"],
        rows,
        notes=[
            "gyro, accelerometer, compass: single-sensor sources (compass tilt at the true heading; compass "
            "heading from the accelerometer tilt); ahf, hf, ecf have no magnetometer, so their heading drifts",
            "the paper's bounds are for its filter against an AHRS on an ADIS16385 + HMR3500; here against "
            "exact truth with a simulated MPU-6050 whose gyro warm-up drift is large",
        ],
    )

    design = _design_table(errors, tt.dt_s)
    hard = Table(
        "Ellipsoid calibration (calibration flight + flips of the same part) vs the simulator's hard iron",
        ["axis", "true (µT)", "recovered (µT)", "error (µT)"],
        [[a, float(t), float(r), float(r - t)] for a, t, r in zip("xyz", tt.hard_iron_ut, cal.offset_ut)],
        notes=[f"sphere radius {cal.field_ut:.2f} µT (simulated field {np.linalg.norm([20.0, 0.0, 45.0]):.2f} µT)"],
    )
    return Result(tables=[accuracy, design, hard], figures=_figures(errors, tt.dt_s))


def _design_table(errors, dt_s) -> Table:
    """mcf's design (mcf.py) measured on this run, beside its defaults."""
    e_gyro, e_acc, e_comp = errors["gyro"], errors["accelerometer"], errors["compass"]
    rows, d = [], McfSettings()
    ok = np.isfinite(e_comp).all(axis=1)
    w = [inverse_variance_weight(e_acc[ok, a], e_comp[ok, a]) for a in (1, 2)]
    for label, axis, wa in (("pitch", 1, w[0]), ("roll", 2, w[1])):
        blend = wa * e_acc[ok, axis] + (1 - wa) * e_comp[ok, axis]
        rows.append([f"{label} crossover (Hz)", crossover_from_spectra(e_gyro[ok, axis], blend, dt_s), d.crossover_hz])
        rows.append([f"{label} accelerometer weight w_a", wa, d.acc_weight])
    rows.append(["heading crossover (Hz)", crossover_from_spectra(e_gyro[ok, 0], e_comp[ok, 0], dt_s), d.heading_crossover_hz])
    return Table("mcf design from the error spectra (this run) vs mcf's defaults", ["quantity", "measured", "default"], rows)


def _figures(errors, dt_s) -> list[Figure]:
    def spectra(names, axis):
        out = []
        for n in names:
            e = errors[n][:, axis]
            e = e[np.isfinite(e)]
            f, a = amplitude_spectrum(e, dt_s)
            out.append(Series(n, f[1:], a[1:]))
        return out

    def figure(filename, title, names, axis):
        return Figure(filename, title, "frequency (Hz)", "error amplitude (deg)", spectra(names, axis), log_x=True, log_y=True)

    return [
        figure("seed003_fig1_gyro_pitch.png", "Fig. 1: integrated gyro pitch error spectrum", ["gyro"], 1),
        figure("seed003_fig2_accelerometer_pitch.png", "Fig. 2: accelerometer pitch error spectrum", ["accelerometer"], 1),
        figure("seed003_fig3_compass_pitch.png", "Fig. 3: compass tilt pitch error spectrum", ["compass"], 1),
        figure("seed003_heading_sources.png", "Heading error spectra: gyro and compass", ["gyro", "compass"], 0),
        figure("seed003_fig10_filters_pitch.png", "Fig. 10: filters' pitch error spectra", list(FILTERS), 1),
        figure("seed003_filters_heading.png", "Filters' heading error spectra", list(FILTERS), 0),
    ]
