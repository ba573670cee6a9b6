"""Seed 000's four experiments (Fu et al. 2014, section 4.2; docs/seeds-digest.md §3) on the simulator.

- static: at rest 5 min, the AHF against the accelerometer's own angle (paper: mean abs error 0.05°);
- normal flight: the AHF against truth (paper, against a fibre-optic gyro: pitch 0.523°, roll 0.498°);
- horizontal sliding: translated at zero attitude, mean |pitch| of ECF, HF, AHF and Kalman (paper: AHF
  lowest; the table's values were lost in extraction);
- fast attitude change: flips at 550-900 °/s on a ±500 °/s gyro, which saturates; rise time, overshoot and
  steady-state error (paper: AHF fast, no overshoot, no steady-state error; Kalman slow with overshoot;
  ECF and HF slow to recover).

The filters are the defaults of ``groundstation.estimation`` (the papers' constants: AHF eq. 20, HF
β = 0.1, ECF kp 1 ki 0.3, the per-axis Kalman ``kf``, and the quaternion ``ekf``). "ahf+overrange" is
the AHF with the paper's gyro-over-range rule (λ = λ_max while any axis reads ≥ 95 % of full scale; in
words only in the paper, see ``estimation.ahf``). Pitch and roll are ZYX Euler angles (docs/conventions.md).
"""

from __future__ import annotations

import math

import numpy as np

from groundstation import quaternion, units
from groundstation.estimation import create
from groundstation.estimation.evaluation import inclination_error_rad
from groundstation.estimation.tilt import acc_pitch_roll, wrap_pi
from groundstation.experiments.report import Figure, Result, Series, Table
from groundstation.sim.offline import SimRun, simulate

NAME = "seed000"
TITLE = "Seed 000 (AHF) §4.2: static, normal flight, horizontal sliding, fast attitude change"
FILTERS = ("ahf", "hf", "ecf", "kf", "ekf")
LABELS = {"ahf": "AHF", "ahf+overrange": "AHF + over-range rule", "hf": "HF", "hf2": "HF, λ = 2 fixed", "ecf": "ECF",
          "kf": "Kalman (kf)", "ekf": "EKF"}
DURATION_S = {"static": 300.0, "flight": 120.0, "slide": 120.0, "fast": 120.0}
QUICK_DURATION_S = {"static": 10.0, "flight": 20.0, "slide": 20.0, "fast": 15.0}
SEED = 0
FAST_GYRO_FS_DPS = 500  # the 'fast' profile's flips run at 550-900 °/s
# A filter has recovered once it stays within this of the held attitude: above the AHF's ±1° hop at
# rest and the ~0.7° the part's cross-axis sensitivity leaves in every filter (see the static table).
SETTLED_DEG = 2.0
MIN_HOLD_S = 1.0  # a flip is scored only if both angles then hold this long
SMOOTH_S = 0.1  # overshoot and recovery are judged on the estimate's 0.1 s moving mean (not the AHF's hop)
FIGURE_SPAN_S = 40.0  # the time plots show the first 40 s


def run(quick: bool) -> Result:
    durations = QUICK_DURATION_S if quick else DURATION_S
    result = Result()
    for experiment in (_static, _flight, _slide, _fast):
        table, figure = experiment(durations)
        result.tables.append(table)
        if figure is not None:
            result.figures.append(figure)
    return result


def _run_filters(sim: SimRun, names, diags: dict | None = None) -> dict[str, np.ndarray]:
    """name -> (n, 3) ZYX Euler angles (yaw, pitch, roll) in degrees, each filter fresh over the run;
    ``diags``, if given, receives name -> the filter's diagnostics arrays."""
    variants = {
        "ahf+overrange": ("ahf", {"gyro_overrange_rad_s": 0.95 * units.gyro_limit_rad_s(FAST_GYRO_FS_DPS)}),
        "hf2": ("hf", {"beta": 2.0}),  # the AHF's λ_max, held
    }
    out = {}
    for name in names:
        estimator = create(*variants.get(name, (name, None)))
        q, diag = estimator.run(sim.gyr_rad_s, sim.acc_g, sim.dt_s)
        out[name] = np.degrees(quaternion.to_euler_zyx(q))
        if diags is not None:
            diags[name] = diag
    return out


def _errors_deg(euler_deg: np.ndarray, reference_deg: np.ndarray) -> np.ndarray:
    """(n, 2) pitch and roll errors in degrees, roll wrapped to ±180°."""
    return np.degrees(wrap_pi(np.radians(euler_deg[:, 1:] - reference_deg[:, 1:])))


def _truth_deg(sim: SimRun) -> np.ndarray:
    return np.degrees(quaternion.to_euler_zyx(sim.truth.q_body_to_ned))


def _static(durations) -> tuple[Table, None]:
    duration_s = durations["static"]
    sim = simulate("static", duration_s, SEED)
    truth = _truth_deg(sim)
    tilt = np.degrees([acc_pitch_roll(*a) for a in sim.acc_g.tolist()])  # (n, 2) pitch, roll
    accel = np.column_stack([np.zeros(len(tilt)), tilt])  # as (yaw, pitch, roll)
    rows = []
    for name, euler in {**_run_filters(sim, FILTERS), "accelerometer angle": accel}.items():
        vs_acc = np.abs(_errors_deg(euler, accel)).mean(axis=0)
        vs_truth = np.abs(_errors_deg(euler, truth)).mean(axis=0)
        rows.append([LABELS.get(name, name), *vs_acc, *vs_truth, "0.05 (AHF vs accelerometer)" if name == "ahf" else "-"])
    notes = [
        "The AHF's λ stays near λ_max = 2 rad/s at rest (eq. 20: small error, λ = 2 - e_a) and eq. 18 takes a "
        "step of λ·Δt along the normalised gradient whatever the error's size, so it hops about the gravity "
        "direction by ~1° on every sample; HF (β = 0.1) hops 20x less. This is why our AHF misses the paper's "
        "0.05°: the paper's onboard estimate may be smoothed, or its λ held lower at rest, which eq. 20 as "
        "written does not do.",
        "The accelerometer angle itself is noisy (400 µg/√Hz: about 0.16° per sample), so even a perfect "
        "filter reads ~0.13° against it; against truth its error is the part's cross-axis sensitivity and "
        "warm-up drift, which the bias calibration does not remove and every filter inherits.",
    ]
    columns = ["filter", "pitch vs acc (deg)", "roll vs acc (deg)", "pitch vs truth (deg)", "roll vs truth (deg)", "paper (deg)"]
    return Table(f"Static, {duration_s:.0f} s at rest: mean absolute error", columns, rows, notes), None


def _flight(durations) -> tuple[Table, None]:
    duration_s = durations["flight"]
    sim = simulate("flight", duration_s, SEED)
    truth = _truth_deg(sim)
    rows = []
    for name, euler in _run_filters(sim, FILTERS).items():
        mae = np.abs(_errors_deg(euler, truth)).mean(axis=0)
        q = quaternion.from_euler_zyx(*np.radians(euler).T)
        incl = np.degrees(inclination_error_rad(q, sim.truth.q_body_to_ned, truth_frame="NED"))
        paper = "0.523 / 0.498 (vs FOG)" if name == "ahf" else "-"
        rows.append([LABELS[name], *mae, float(np.sqrt(np.mean(incl**2))), paper])
    notes = [
        "The simulated flight tilts to ±30° within 0.5-2 s and accelerates horizontally by up to ~2 m/s², more "
        "than a craft holding a hover in the paper's test; the accelerometer then disagrees with gravity by "
        "several degrees, which every filter partly follows.",
        "A real quadrotor accelerates by tilting its thrust, so its accelerometer sees little horizontal "
        "acceleration; the simulator moves position and attitude independently, a harder case for every filter. "
        "The paper's reference is a fibre-optic gyro with its own error; ours is the simulator's exact truth.",
    ]
    columns = ["filter", "pitch MAE (deg)", "roll MAE (deg)", "inclination RMSE (deg)", "paper pitch / roll (deg)"]
    return Table(f"Normal flight, {duration_s:.0f} s: error against truth", columns, rows, notes), None


def _slide(durations) -> tuple[Table, Figure]:
    duration_s = durations["slide"]
    sim = simulate("slide", duration_s, SEED)
    truth = _truth_deg(sim)
    diags = {}
    estimates = _run_filters(sim, (*FILTERS, "hf2"), diags)
    lam = diags["ahf"]["lam"]
    mean_abs = {name: np.abs(_errors_deg(euler, truth)).mean(axis=0) for name, euler in estimates.items()}
    ranked = sorted(mean_abs, key=lambda name: mean_abs[name][0])
    rows = [[LABELS[name], *mean_abs[name], ranked.index(name) + 1, "lowest" if name == "ahf" else "-"] for name in estimates]
    peak = float(np.abs(sim.truth.acc_ned_m_s2[:, 0]).max())
    notes = [
        f"Slid along north at zero attitude with up to {peak:.1f} m/s² ({math.degrees(math.atan(peak / 9.80665)):.0f}° "
        "of apparent tilt in the accelerometer); the pitch error is what each filter takes from that.",
        "Ranked by mean |pitch|. The paper ranks AHF lowest (its table's numbers were lost in extraction); "
        f"ours does not. Against HF with λ = 2 held (the AHF's λ_max) it scores {mean_abs['ahf'][0]:.2f}° vs "
        f"{mean_abs['hf2'][0]:.2f}°; against the HF default β = 0.1 it loses. Its λ never fell below "
        f"{lam.min():.2f} rad/s (mean {lam.mean():.2f}): with λ high the AHF follows the accelerometer closely, so "
        "the disagreement eq. 20 measures stays small and λ stays high; the adaptation does not engage on a "
        "slow slide. (Eq. 18's normalised gradient turns the estimate toward the accelerometer at 2λ rad/s "
        "whatever the error.) The paper does not give its HF's λ. The EKF (accelerometer noise 0.1) trusts "
        "the accelerometer least and errs least here.",
    ]
    columns = ["filter", "mean |pitch| (deg)", "mean |roll| (deg)", "rank (pitch)", "paper"]
    table = Table(f"Horizontal sliding, {duration_s:.0f} s at zero attitude: mean absolute pitch", columns, rows, notes)
    return table, _pitch_figure("seed000_slide_pitch.png", "Horizontal sliding: pitch", sim, truth, estimates)


def _fast(durations) -> tuple[Table, Figure]:
    duration_s = durations["fast"]
    sim = simulate("fast", duration_s, SEED, gyro_fs_dps=FAST_GYRO_FS_DPS)
    truth = _truth_deg(sim)
    estimates = _run_filters(sim, (*FILTERS, "ahf+overrange"))
    moves = [(axis, m) for m in _moves(truth, round(MIN_HOLD_S / sim.dt_s)) for axis in (1, 2)
             if abs(truth[m[1], axis] - truth[m[0] - 1, axis]) >= 10.0]
    rows = []
    for name, euler in {"truth": truth, **estimates}.items():
        figures = np.array([_step_response(euler[:, axis], truth[:, axis], move, sim.dt_s) for axis, move in moves])
        rise, overshoot, steady, settle = (figures[:, k] for k in range(4))
        unsettled = int(np.isnan(settle).sum())
        median_settle = float(np.median(np.where(np.isnan(settle), np.inf, settle)))  # inf: most never recovered
        rows.append([LABELS.get(name, name), _mean(rise), _mean(overshoot), _mean(steady), median_settle,
                     f"{unsettled}/{len(settle)}"])
    notes = [
        f"{len(moves)} flips of pitch or roll between level and 45-80° at 550-900 °/s peak on a ±{FAST_GYRO_FS_DPS} °/s "
        f"gyro, each followed by at least {MIN_HOLD_S:.0f} s with both angles held: the clipped rate "
        "under-integrates each flip and the filters must recover from the accelerometer.",
        "Rise time: 10 % to 90 % of the flip from the held angle before it; overshoot beyond the new held angle, "
        f"% of the flip; steady-state error: mean |error| over the last 0.25 s of each hold; recovered: time "
        f"after the flip ends until the estimate stays within {SETTLED_DEG:.0f}° (median over the flips, n/a "
        "when most never do; 'not recovered' counts those). Overshoot and recovery use the estimate's "
        f"{SMOOTH_S:.1f} s moving mean, so the AHF's per-sample hop is not counted as overshoot.",
        "Against the paper: the AHF rises as fast as the truth and recovers at once, as claimed; its ~1° "
        "steady-state error is its hop at rest plus the part's cross-axis error (static table), not a lag. "
        "The Kalman filter is slower with the largest overshoot, and ECF and HF rise slowly, as claimed; the ECF's "
        "integral term also learns a false bias while the gyro clips. The over-range rule changes little here: "
        "eq. 20's λ already recovers within the hold.",
    ]
    columns = ["filter", "rise 10-90 % (s)", "overshoot (%)", "steady-state error (deg)", "recovered in (s)", "not recovered"]
    table = Table(f"Fast attitude change, {duration_s:.0f} s, gyro ±{FAST_GYRO_FS_DPS} °/s: step response", columns, rows, notes)
    return table, _pitch_figure("seed000_fast_pitch.png", f"Fast attitude change (gyro ±{FAST_GYRO_FS_DPS} °/s): pitch",
                                sim, truth, estimates)


def _moves(truth_deg: np.ndarray, min_hold: int) -> list[tuple[int, int, int]]:
    """(start, end, next_start) sample indices of each move of the true pitch or roll followed by a hold
    of both of at least ``min_hold`` samples: they change on samples start..end-1 and hold from end."""
    moving = (np.abs(np.diff(truth_deg[:, 1:], axis=0, prepend=truth_deg[:1, 1:])) > 1e-9).any(axis=1)
    edges = np.flatnonzero(np.diff(moving.astype(int)))
    starts, ends = edges[::2] + 1, edges[1::2] + 1
    spans = list(zip(starts, ends))
    nexts = [s for s, _ in spans[1:]] + [len(truth_deg)]
    return [(s, e, n) for (s, e), n in zip(spans, nexts) if n - e >= min_hold]


def _step_response(estimate: np.ndarray, truth: np.ndarray, move: tuple[int, int, int], dt_s: float) -> tuple[float, ...]:
    """Rise time 10-90 % (s), overshoot (% of the step), steady-state error (deg), time to recover (s)."""
    start, end, next_start = move
    before, after = truth[start - 1], truth[end]
    sign, size = math.copysign(1.0, after - before), abs(after - before)
    progress = sign * (estimate[start:next_start] - before) / size  # 0 before the step, 1 at its end
    reached = [np.flatnonzero(progress >= level) for level in (0.1, 0.9)]
    rise = (reached[1][0] - reached[0][0]) * dt_s if len(reached[1]) and len(reached[0]) else math.nan
    window = max(1, round(SMOOTH_S / dt_s))
    smooth = np.convolve(estimate[end:next_start], np.ones(window) / window, mode="valid")
    overshoot = max(0.0, float(np.max(sign * (smooth - after))) / size) * 100.0
    steady = float(np.abs(estimate[end:next_start] - after)[-round(0.25 / dt_s) :].mean())
    error = np.abs(smooth - after)
    outside = np.flatnonzero(error > SETTLED_DEG)
    if not len(outside):
        settle = 0.0
    else:
        settle = (outside[-1] + 1) * dt_s if outside[-1] < len(error) - 1 else math.nan
    return rise, overshoot, steady, settle


def _mean(values: np.ndarray) -> float:
    return float(np.nanmean(values)) if np.isfinite(values).any() else math.nan


def _pitch_figure(filename: str, title: str, sim: SimRun, truth: np.ndarray, estimates: dict[str, np.ndarray]) -> Figure:
    shown = sim.truth.t_s <= FIGURE_SPAN_S
    t = sim.truth.t_s[shown]
    series = [Series("truth", t, truth[shown, 1])]
    series += [Series(LABELS[name], t, euler[shown, 1]) for name, euler in estimates.items()]
    return Figure(filename=filename, title=title, x_label="time (s)", y_label="pitch (deg)", series=series)
