"""A whole session as columns, whatever it came from: a recording of the link, an imported dataset
CSV (a recording holding sample columns), or a dataset CSV read directly.

Exports and evaluation read ``SessionData``; they never know the source.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from groundstation import mounting, quaternion
from groundstation.autopilot import LOG_SUFFIXES
from groundstation.datasets import TRUE_Q, DatasetError, Trial, read_csv, trial_from_columns
from groundstation.errors import UserError
from groundstation.estimation import create
from groundstation.estimation.evaluation import run_on_trial
from groundstation.recording import Recording, open_recording
from groundstation.session.batch import BatchSession, batch_replay
from groundstation.session.catalogue import Catalogue, session_catalogue
from groundstation.session.clock import DISCONTINUITIES
from groundstation.session.pipeline import DEFAULT_FILTERS, Pipeline
from groundstation.session.product import ONBOARD, LinkSummary, SessionData, aligned, build_product, estimate_columns
from groundstation.session.replay import check_forced, recorded_settings, replay
from groundstation.units import STANDARD_GRAVITY_M_S2

DATASET_SUFFIXES = (".csv", ".csv.gz", ".gz")


def load_session(path, filters=None, forced=None, progress=None) -> SessionData:
    """Decode, import or read ``path`` and run the estimators; UserError with a clear message on bad input."""
    path = Path(path)
    if path.suffix.lower() in LOG_SUFFIXES:  # an autopilot's flight log (.tlog, .bin, .ulg)
        from groundstation.autopilot.session import load_log

        return load_log(path, filters, forced, progress)
    if path.name.lower().endswith(DATASET_SUFFIXES):
        try:
            trial = read_csv(path)
        except DatasetError as error:
            raise UserError(str(error)) from None
        filters = filters or DEFAULT_FILTERS
        check_forced(filters, forced)
        return from_trial(trial, filters, forced, {"source": f"dataset CSV {path.name}"})
    recording = open_recording(path)
    if recording.samples and recording.chunk_count == 0:  # an imported dataset; otherwise samples are truth
        trial = trial_from_samples(recording.samples, path)
        filters = filters or recording.metadata.get("filters", DEFAULT_FILTERS)
        check_forced(filters, forced)
        settings = {**recorded_settings(recording)}
        for name, values in (forced or {}).items():
            settings[name] = {**settings.get(name, {}), **values}
        data = from_trial(trial, filters, settings, recording.metadata)
        data.damage = recording.damage
        return data
    if recording.chunk_count == 0:
        raise UserError(f"{path}: the recording holds no data")
    return from_pipeline(recording, computed(recording, filters, forced, progress))


def computed(recording: Recording, filters=None, forced=None, progress=None) -> Pipeline | BatchSession:
    """A recording's session computed whole: the project's frames on the batch path (the same tables as
    a replay, tests/session/test_batch.py); an autopilot's MAVLink through the incremental pipeline
    (its front-end turns messages into stage calls one by one; it has no batch form)."""
    if recording.metadata.get("protocol", "gs") == "gs":
        return batch_replay(recording, filters, forced, progress)
    return replay(recording, filters, forced, progress)


def trial_from_samples(samples: dict[str, np.ndarray], path) -> Trial:
    try:
        return trial_from_columns(samples, f"{path} (imported samples)")
    except DatasetError as error:
        raise UserError(str(error)) from None


def from_trial(trial: Trial, filters, settings_used, metadata: dict) -> SessionData:
    """A dataset trial, run exactly as ``evaluate_trial`` runs it (the same numbers)."""
    try:
        runs = run_on_trial(trial, filters, settings_used)
    except ValueError as error:
        raise UserError(str(error)) from None
    time_s = trial.time_s - trial.time_s[0]
    tables = session_catalogue({name: tuple(diag) for name, (_, diag) in runs.items()})
    catalogue = Catalogue({"imu": tables["imu"], ONBOARD: tables[ONBOARD]})  # a dataset has no onboard estimate: no rows
    imu = {"time_s": time_s, **{f"acc_{a}_g": trial.acc_m_s2[:, i] / STANDARD_GRAVITY_M_S2 for i, a in enumerate("xyz")},
           **{f"gyr_{a}_rad_s": trial.gyr_rad_s[:, i] for i, a in enumerate("xyz")}}
    for name, (q, diagnostics) in runs.items():
        imu.update(estimate_columns(name, q, diagnostics))
    settings = {name: dataclasses.asdict(create(name, (settings_used or {}).get(name, {})).settings) for name in runs}
    return build_product(metadata, catalogue, {"imu": imu}, runs, true_q=trial.true_q, true_frame="ENU",
                         moving=trial.moving, settings_at_start=settings, settings_at_end=settings)


def from_pipeline(recording: Recording, pipeline: Pipeline | BatchSession) -> SessionData:
    """A decoded session's product: what the pipeline (or the batch path) computed, as it computed it."""
    t0_ns = pipeline.t0_host_ns or 0
    data = build_product(
        recording.metadata, pipeline.catalogue, {name: table.to_dict() for name, table in pipeline.tables.items()},
        pipeline.filters, protocol=recording.metadata.get("protocol", "gs"),
        link=LinkSummary(pipeline.decoder.stats.as_dict(), pipeline.link.per_second.to_dict()), config=pipeline.config,
        events=[{**event, "t_s": (event["t_host_ns"] - t0_ns) / 1e9} for event in pipeline.events],
        settings_at_start=pipeline.bank.at_start, settings_at_end=pipeline.settings(), damage=list(recording.damage),
    )
    if "true_qw" in recording.samples:
        device_us = data.tables[data.sample_table]["device_time_us"]
        attach_sensor_truth(data, recording.samples, device_us, pipeline)
    return data


def attach_sensor_truth(data: SessionData, samples: dict[str, np.ndarray], device_us: np.ndarray, pipeline: Pipeline) -> None:
    """Truth stored with a simulated recording (sensor axes -> ENU, at device times) onto the body axes.

    The simulator's truth keeps the uninterrupted device time, so only samples before the first reboot
    or clock jump have theirs; the later ones get none rather than another instant's.
    """
    truth_us = np.rint(samples["time_s"] * 1e6)
    restarts = [e["session_time_s"] for e in pipeline.events if e["kind"] in DISCONTINUITIES]
    if restarts:
        device_us = np.where(data.time_s < restarts[0], device_us, np.nan)
    q_sensor = aligned(device_us, truth_us, np.column_stack([samples[c] for c in TRUE_Q]))
    q_body_from_sensor = quaternion.from_matrix(mounting.matrix(pipeline.sensor.mounting))
    data.true_q = quaternion.multiply(q_sensor, quaternion.conjugate(q_body_from_sensor))
    data.true_frame = "ENU"
    if "moving" in samples:
        data.moving = aligned(device_us, truth_us, samples["moving"][:, None])[:, 0] == 1.0
