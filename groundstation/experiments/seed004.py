"""Seed 004: position from accelerometer + barometer + GPS, raw aids vs single vs dual channel.

The paper (Qi et al. 2022, flight test, figures 7-9) reports the fluctuation of the position
estimate before and after its fusion: height 1 m -> 0.4 m, horizontal 1.2 m -> 0.5 m ("about 60%
better"); in simulation (figure 6) accelerometer integration alone diverges, the single channel
(proportional loops) bounds it but keeps a steady error, the dual channel (integral loop added)
removes it and converges faster. Here, on the simulated hover and flight, with the true attitude and
with AHF's: fluctuation = standard deviation of the estimate's error against truth after the first
10 s (the loops' start), horizontal = RMS over north and east. Filters: ``groundstation.position``.
"""

from __future__ import annotations

import numpy as np

from groundstation.estimation import create
from groundstation.experiments.report import Figure, Result, Series, Table
from groundstation.position import DualChannel, SingleChannel, linear_acc_ned_m_s2
from groundstation.sim.offline import simulate

NAME = "seed004"
TITLE = "Seed 004: accelerometer + barometer + GPS position fusion (single vs dual channel)"

SETTLE_S = 10.0
BIAS_M_S2 = 0.2  # injected vertical accelerometer bias for the steady-error table
PAPER_HEIGHT_M = (1.0, 0.4)  # before, after (flight test)
PAPER_HORIZONTAL_M = (1.2, 0.5)


def run(quick: bool = False) -> Result:
    duration_s = 40.0 if quick else 120.0
    fluct = Table(
        "Position fluctuation (std of the error against truth after 10 s), m",
        ["profile", "attitude", "estimate", "height (m)", "horizontal (m)", "height vs raw (%)", "horizontal vs raw (%)", "paper height (m)", "paper horizontal (m)"],
        [],
        notes=[
            "paper: flight test, 400 samples, 'fluctuation amplitude' before -> after its fusion; ours: simulator truth, std",
            "the simulator's GPS error is white (1 m σ, independent fixes) and its barometer's too (0.17 m): a "
            "complementary filter averages white error above its crossover, so the fused error falls as the crossover "
            "falls. A real receiver's error is correlated over tens of seconds (multipath, atmosphere) and a real "
            "barometer drifts with wind and temperature: below the crossover such error passes through unchanged, so "
            "on real sensors the gain is smaller than here; our horizontal ~50% is close to the paper's 58% only "
            "because the crossovers are high (designed for AHF's tilt error), not because the error models agree",
            "with AHF's attitude the horizontal acceleration carries g × the tilt error (several tenths of m/s² in the "
            "flight's manoeuvres): the default crossovers are designed for that (groundstation.position.complementary)",
            "accelerometer only = the same filter with no aids: its error grows as b t²/2; RMS over the whole run",
            "height: ours 0.17 m -> 0.05 m (~70%), paper 1 m -> 0.4 m (60%): the same direction; the paper's raw "
            "height is worse (a real barometer in prop wash), and its figure includes the position controller's "
            "tracking ('control accuracy'), which the simulator's scripted truth has not",
            "dual vs single: on white aid noise the dual channel's extra integral pole passes slightly more noise "
            "(its kp is larger); its gain is the bias removal (next table) and the paper's faster convergence",
        ],
    )
    figures = []
    for profile, seed in (("hover", 41), ("flight", 42)):
        sim = simulate(profile, duration_s, seed=seed, baro_rate_hz=25, gps_rate_hz=10)
        settle = int(SETTLE_S / sim.dt_s)
        truth = sim.truth.pos_ned_m
        raw = _raw_errors(sim, settle)
        attitudes = {"truth": sim.truth.q_body_to_ned, "ahf": create("ahf").run(sim.gyr_rad_s, sim.acc_g, sim.dt_s)[0]}
        fluct.rows.append([profile, "-", "raw baro / GPS", *raw, 0.0, 0.0, PAPER_HEIGHT_M[0], PAPER_HORIZONTAL_M[0]])
        for attitude, q in attitudes.items():
            acc = linear_acc_ned_m_s2(sim.acc_g, q)
            estimates = _estimates(sim, acc)
            for label, pos in estimates.items():
                err = pos - truth
                if label == "accelerometer only":  # no meaningful gain over the raw aids: it diverges
                    row = [_rms(err[:, 2]), _rms(err[:, :2]), "", ""]
                else:
                    h, xy = _std(err[settle:, 2]), _std(err[settle:, :2])
                    row = [h, xy, _gain(raw[0], h), _gain(raw[1], xy)]
                paper = PAPER_HEIGHT_M[1], PAPER_HORIZONTAL_M[1]
                fluct.rows.append([profile, attitude, label, *row, *(paper if "dual" in label else ("", ""))])
            if profile == "flight" and attitude == "ahf":
                figures += _figures(sim, estimates)
    return Result(tables=[fluct, _steady_error_table(duration_s)], figures=figures)


def _estimates(sim, acc) -> dict[str, np.ndarray]:
    nan1, nan3 = np.full(len(sim), np.nan), np.full((len(sim), 3), np.nan)
    return {
        "accelerometer only": DualChannel().run(acc, sim.dt_s, nan1, nan3)[0],
        "single channel": SingleChannel().run(acc, sim.dt_s, sim.baro_alt_m, sim.gps_pos_ned_m)[0],
        "dual channel": DualChannel().run(acc, sim.dt_s, sim.baro_alt_m, sim.gps_pos_ned_m)[0],
        "dual + GPS velocity": DualChannel().run(acc, sim.dt_s, sim.baro_alt_m, sim.gps_pos_ned_m, sim.gps[:, :3])[0],
    }


def _steady_error_table(duration_s: float) -> Table:
    """The paper's figure 6 claim: a constant accelerometer bias leaves the single channel a steady error."""
    sim = simulate("hover", duration_s, seed=43, baro_rate_hz=25, gps_rate_hz=10)
    acc = linear_acc_ned_m_s2(sim.acc_g, sim.truth.q_body_to_ned)
    tail = slice(len(sim) // 2, None)
    rows = []
    for cls in (SingleChannel, DualChannel):
        shift = cls().run(acc + [0.0, 0.0, BIAS_M_S2], sim.dt_s, sim.baro_alt_m)[0] - cls().run(acc, sim.dt_s, sim.baro_alt_m)[0]
        kv = cls().baro_gains.kv_1_s2
        rows.append([cls.__name__, float(np.mean(shift[tail, 2])), BIAS_M_S2 / kv if cls is SingleChannel else 0.0])
    return Table(
        f"Steady height error from a {BIAS_M_S2} m/s² accelerometer bias (hover, barometer aid, second half of the run)",
        ["filter", "mean error (m)", "analytic (m)"],
        rows,
        notes=[
            "analytic: b / kv for the proportional loops, 0 with the integral; the mean over all samples is slightly "
            "below b / kv because each reading takes the fraction kp Δ of the error off",
            "paper (figure 6, simulation): the single channel keeps a steady error, the dual channel lowers it; agrees",
        ],
    )


def _figures(sim, estimates) -> list[Figure]:
    t, truth = sim.truth.t_s, sim.truth.pos_ned_m
    baro, gps = ~np.isnan(sim.baro_alt_m), ~np.isnan(sim.gps_pos_ned_m[:, 0])
    height = Figure("seed004_height.png", "Height on the simulated flight (AHF attitude)", "time (s)", "height (m)", [
        Series("truth", t, -truth[:, 2]),
        Series("barometer", t[baro], sim.baro_alt_m[baro]),
        Series("single channel", t, -estimates["single channel"][:, 2]),
        Series("dual channel", t, -estimates["dual channel"][:, 2]),
    ])  # fmt: skip
    north = Figure("seed004_north.png", "North position on the simulated flight (AHF attitude)", "time (s)", "north (m)", [
        Series("truth", t, truth[:, 0]),
        Series("GPS", t[gps], sim.gps_pos_ned_m[gps, 0]),
        Series("single channel", t, estimates["single channel"][:, 0]),
        Series("dual channel", t, estimates["dual channel"][:, 0]),
    ])  # fmt: skip
    return [height, north]


def _raw_errors(sim, settle: int) -> tuple[float, float]:
    truth = sim.truth.pos_ned_m[settle:]
    baro_err = sim.baro_alt_m[settle:] + truth[:, 2]
    gps_err = sim.gps_pos_ned_m[settle:, :2] - truth[:, :2]
    return _std(baro_err[~np.isnan(baro_err)]), _std(gps_err[~np.isnan(gps_err[:, 0])])


def _std(err: np.ndarray) -> float:
    """Standard deviation; for (n, 2) the RMS over both axes of the centred error."""
    err = err.reshape(len(err), -1)
    return float(np.sqrt(np.mean(np.var(err, axis=0))))


def _rms(err: np.ndarray) -> float:
    err = err.reshape(len(err), -1)
    return float(np.sqrt(np.mean(err**2)))


def _gain(raw: float, value: float) -> float:
    """Improvement over the raw aid in percent (the paper's 'about 60%')."""
    return 100.0 * (1.0 - value / raw)
