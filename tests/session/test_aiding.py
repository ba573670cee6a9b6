"""Magnetometer and GPS frames through the pipeline: converted to body axes, handed to the
estimators with the next IMU sample, and a compass heading that follows the simulator's truth yaw."""

import numpy as np

from groundstation import quaternion as quat
from groundstation.geodesy import ned_from_geodetic
from groundstation.session_parts.aiding import gps_fix
from groundstation.session_parts.catalogue import HEADING
from groundstation.session_makers.pipeline import Pipeline
from groundstation.sim.firmware import FirmwareSettings
from groundstation.sim.stream import Scenario, SimStream


def stream_through(pipeline: Pipeline, scenario: Scenario):
    """Feed a whole simulated session; returns the truth at each sample: device µs, yaw (rad), NED position (m)."""
    times, yaws, positions = [], [], []

    def keep(t_dev_us, truth, _raw, *_clock):
        times.append(np.asarray(t_dev_us, dtype=float))
        yaws.append(quat.to_euler_zyx(truth.q_body_to_ned)[:, 0])
        positions.append(truth.pos_ned_m)

    stream = SimStream(scenario, on_samples=keep)
    for chunk in stream.advance(stream.end_s) + stream.flush():
        pipeline.feed(int(chunk.t_s * 1e9), chunk.data)
    return np.concatenate(times), np.concatenate(yaws), np.concatenate(positions)


def test_compass_heading_column_follows_true_yaw_during_a_flight():
    scenario = Scenario(profile="flight", duration_s=40.0, seed=2, firmware=FirmwareSettings(mode="raw", mag_rate_hz=50))
    pipeline = Pipeline(filters=("ekf",))  # a steady tilt estimate; the heading uses only its pitch and roll
    t_us, yaw, _ = stream_through(pipeline, scenario)
    mag = pipeline.tables["mag_raw"].to_dict()
    assert len(mag["time_s"]) > 1900
    t0_us = pipeline.imu.to_dict()["device_time_us"][0]
    true_yaw = np.interp(mag["time_s"] * 1e6 + t0_us, t_us, np.unwrap(yaw))
    error_deg = np.degrees(np.angle(np.exp(1j * (np.radians(mag[HEADING.name]) - true_yaw))))
    settled = mag["time_s"] > 5.0
    assert np.abs(true_yaw[settled]).max() > np.radians(45)  # the craft turns
    # Hard iron is left uncalibrated here (up to ~10 µT on a 20 µT horizontal field), so this bounds the
    # heading loosely; it still fails for a wrong axis, sign or mounting (errors of 90-180°).
    assert np.median(np.abs(error_deg[settled])) < 25.0


class Probe:
    """An estimator stand-in that only records what the pipeline hands over (the pipeline is under test)."""

    name = "probe"

    def __init__(self, inner):
        self.inner, self.calls = inner, []
        self.Diagnostics, self.settings = inner.Diagnostics, inner.settings
        self.estimates_gyro_bias = inner.estimates_gyro_bias

    def step(self, gyr, acc, dt_s, mag=None, gps=None):
        self.calls.append((mag, gps))
        return self.inner.step(gyr, acc, dt_s, mag, gps)


def test_each_gps_fix_and_mag_reading_reaches_the_estimators_once():
    scenario = Scenario(profile="hover", duration_s=10.0, seed=3,
                        firmware=FirmwareSettings(mode="raw", mag_rate_hz=50, gps_rate_hz=10))
    pipeline = Pipeline(filters=("ahf",))
    probe = pipeline.estimators["ahf"] = Probe(pipeline.estimators["ahf"])
    stream_through(pipeline, scenario)
    mags = [m for m, _ in probe.calls if m is not None]
    fixes = [g for _, g in probe.calls if g is not None]
    # Every reading but possibly the last (it may arrive after the last IMU sample) is handed over.
    assert len(pipeline.tables["mag_raw"]) - 1 <= len(mags) <= len(pipeline.tables["mag_raw"])
    assert len(pipeline.tables["gps"]) - 1 <= len(fixes) <= len(pipeline.tables["gps"])
    gps = pipeline.tables["gps"].to_dict()
    assert np.allclose([f.vel_n_m_s for f in fixes], gps["vel_n_m_s"][: len(fixes)])
    heading_difference = np.array([f.heading_rad for f in fixes]) - np.radians(gps["heading_deg"][: len(fixes)])
    assert np.allclose(np.sin(heading_difference), 0.0, atol=1e-9) and np.all(np.cos(heading_difference) > 0)
    # A level craft's field: down component positive (NED, northern hemisphere), horizontal ~20 µT.
    assert np.median([m[2] for m in mags]) > 30.0


def test_a_fix_without_heading_passes_nan_heading():
    values = {"vel_n": 1.0, "vel_e": 2.0, "vel_d": 0.5, "heading": 655.35}
    fix = gps_fix(values)
    assert fix[:3] == (1.0, 2.0, 0.5) and np.isnan(fix.heading_rad)
    assert np.isclose(gps_fix({**values, "heading": 270.0}).heading_rad, -np.pi / 2)


def test_fused_position_follows_truth_closer_than_the_raw_gps_and_barometer():
    scenario = Scenario(profile="flight", duration_s=60.0, seed=6,
                        firmware=FirmwareSettings(mode="raw", baro_rate_hz=25, gps_rate_hz=10))
    pipeline = Pipeline(filters=("ahf",))
    t_us, _, true_pos = stream_through(pipeline, scenario)
    t0_us = pipeline.imu.to_dict()["device_time_us"][0]
    fused = pipeline.tables["position"].to_dict()
    gps = pipeline.tables["gps"].to_dict()

    def truth_at(time_s):
        return np.column_stack([np.interp(time_s * 1e6 + t0_us, t_us, true_pos[:, k]) for k in range(3)])

    # Both start from their first reading (GPS origin, barometer ground), so compare the scatter of the error.
    settled = fused["time_s"] > 10.0
    fused_error = np.column_stack([fused[f"pos_{a}_m"] for a in "ned"])[settled] - truth_at(fused["time_s"][settled])
    origin = (gps["lat_deg"][0], gps["lon_deg"][0], gps["alt_m"][0])
    gps_ned = ned_from_geodetic(gps["lat_deg"], gps["lon_deg"], gps["alt_m"], origin)
    gps_error = (gps_ned - truth_at(gps["time_s"]))[gps["time_s"] > 10.0]
    assert np.ptp(true_pos[:, 0]) > 10.0  # the craft really travels
    horizontal_fused, horizontal_gps = np.std(fused_error[:, :2], axis=0), np.std(gps_error[:, :2], axis=0)
    assert np.all(horizontal_fused < 0.8 * horizontal_gps), (horizontal_fused, horizontal_gps)
    assert np.std(fused_error[:, 2]) < 0.3  # barometer 0.17 m noise, smoothed


def test_the_aiding_estimator_is_a_named_setting_not_the_first_of_the_filters(tmp_path):
    """The compass heading and the position come from the estimator the session names, wherever it stands
    in the filters, live and from a recording (which records the name); unnamed, AHF2 when it runs."""
    from groundstation.session_makers.load import load_session
    from tests.simulated import simulated_chunks, write_recording

    chunks = simulated_chunks(8.0, seed=4, mode="raw", mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=10)

    def aided_tables(pipeline):
        for t_host_ns, data in chunks:
            pipeline.feed(t_host_ns, data)
        return {name: pipeline.tables[name].to_dict() for name in ("mag_raw", "position")}

    alone = aided_tables(Pipeline(("ekf",)))
    named = aided_tables(Pipeline(("hf", "ekf"), aiding="ekf"))
    first = aided_tables(Pipeline(("hf", "ekf")))  # neither AHF2 nor named: the first, as recordings before the name
    assert len(alone["position"]["time_s"]) > 100 and len(alone["mag_raw"]["time_s"]) > 300
    for table in alone:
        for column, values in alone[table].items():
            np.testing.assert_array_equal(named[table][column], values)
    assert not np.array_equal(first["mag_raw"][HEADING.name], alone["mag_raw"][HEADING.name])
    assert Pipeline(("hf", "ahf2")).bank.aiding == "ahf2"

    path = tmp_path / "named.gsrec"
    write_recording(path, chunks, {"filters": ["hf", "ekf"], "aiding_estimator": "ekf"})
    write_recording(tmp_path / "alone.gsrec", chunks, {"filters": ["ekf"]})
    recorded, only = load_session(path).tables, load_session(tmp_path / "alone.gsrec").tables  # the batch path
    for table in ("mag_raw", "position"):
        for column, values in only[table].items():
            np.testing.assert_array_equal(recorded[table][column], values)


def test_heading_and_position_hold_a_piece_of_samples_not_copies_of_the_session(monkeypatch):
    """Issue 35: the aiding stage over a session's columns (the batch path's, a flight log's) takes, beyond
    what it returns, less than its output again: the position filter's inputs are made a piece of samples at
    a time (was 4.8x the output: every input held whole, for an hour of 100 Hz ~100 MB)."""
    import tracemalloc

    from groundstation.session_parts import aiding

    rng = np.random.default_rng(35)
    n = 200_000
    monkeypatch.setattr(aiding, "_PIECE", 8192)  # a piece of a session of hours to this one's minutes
    keys = lambda every, offset: np.arange(0, n, every) + offset  # noqa: E731 - readings between samples
    stream = aiding.merged([(np.arange(n, dtype=float), aiding.SAMPLE), (np.array([n / 2 + 0.1]), aiding.RESTART),
                            (keys(2, 0.5), aiding.MAG), (keys(4, 0.25), aiding.BARO), (keys(20, 0.75), aiding.GPS)])
    m = n // 20
    gps = {"fix_type": np.full(m, 3.0), "lat": 47 + 1e-5 * rng.standard_normal(m), "lon": 8 + 1e-5 * rng.standard_normal(m),
           "alt": 400 + rng.standard_normal(m), "vel_n": rng.standard_normal(m), "vel_e": rng.standard_normal(m),
           "vel_d": rng.standard_normal(m), "heading": np.full(m, 10.0)}
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    args = (stream, 30 * rng.standard_normal((n // 2, 3)), 101325 + rng.standard_normal(n // 4), gps, q,
            rng.standard_normal((n, 3)), np.full(n, 0.01))
    aiding.heading_and_position(*args)  # the compiled kernels loaded
    tracemalloc.start()
    try:
        out = aiding.heading_and_position(*args)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    returned = sum(np.asarray(o).nbytes for o in out)
    assert len(out[1]) > n - 10
    assert peak < 2 * returned
