"""Opening a file whole: a recording of the link, an imported dataset CSV (a recording holding sample
columns), a dataset CSV read directly, or a flight log, each computed into a ``SessionData``
(``session.product``) by the maker that fits it; ``Loading`` does it in a worker thread.

Exports and evaluation read ``SessionData``; they never know the source.
"""

from __future__ import annotations

import dataclasses
import threading
from pathlib import Path

import numpy as np

from groundstation import formats, mounting, quaternion
from groundstation.autopilot.sections import attach_sections
from groundstation.session_makers.flight_log_session import FAST_IMU_FORMATS, attach_simstate_truth
from groundstation.formats import IMU_STREAMS
from groundstation.datasets import TRUE_Q, DatasetError, Trial, trial_from_columns
from groundstation.errors import UserError
from groundstation.estimation import ESTIMATORS, aiding_estimator, create, live_estimators, runnable
from groundstation.estimation.warm_up import WarmUp, warm_up
from groundstation.estimation.evaluation import run_on_trial
from groundstation.recording import Recording, open_recording
from groundstation.session_makers.batch import BatchSession, batch_replay
from groundstation.session_parts.catalogue import Catalogue, session_catalogue
from groundstation.session_parts.clock import DISCONTINUITIES
from groundstation.session_parts.estimators import slow_interpreted
from groundstation.session_makers.pipeline import Pipeline
from groundstation.session.product import (
    ONBOARD, LinkSummary, SessionData, aligned, build_product, estimate_columns, exact_estimates, held_dtype,
)
from groundstation.session_makers.replay import recorded_filters, replay
from groundstation.units import STANDARD_GRAVITY_M_S2


def load_session(path, filters=None, forced=None, progress=None, accept_config_changes: bool = False,
                 imu: str = IMU_STREAMS[0], stream_estimates: bool = False, exact: bool = False) -> SessionData:
    """Decode, import or read ``path`` by its format (``formats``) and run the estimators (``filters``; None:
    ``estimators_for``); UserError with a
    clear message on bad input. A file of no known format is tried as a recording, whose reader says
    what the file looks like instead. ``accept_config_changes``: a recording's CONFIG that changes the
    scales without a device restart applies (else the first scales are kept, and said; ``ConfigGuard``).
    ``imu``: the stream the estimators run on (``IMU_STREAMS``): "fast", a flight log's full-rate IMU.
    ``stream_estimates``: a recording's estimators are not run whole but a stretch at a time for whoever reads
    ``SessionData.attitudes(rows)`` forward (an export: its memory then does not grow with the session's
    length); other files are computed whole in any case. ``exact``: the host estimators' columns are held in
    float64, as computed (a reader that writes them: an export, a report), not in the form sized for showing
    (``catalogue.ESTIMATES_HELD``)."""
    with exact_estimates(exact):
        data = _loaded(path, filters, forced, progress, accept_config_changes, imu, stream_estimates)
    attach_sections(data)  # an autopilot's: what its controller asked for and had, battery, GPS, outputs
    return data


def _loaded(path, filters, forced, progress, accept_config_changes: bool, imu: str, stream_estimates: bool) -> SessionData:
    file_format = formats.sniff(path) or formats.FORMATS["recording"]
    filters = estimators_for(path) if filters is None else filters
    if imu != IMU_STREAMS[0]:
        if file_format.name not in FAST_IMU_FORMATS:
            raise UserError(f"{path}: --imu {imu}: a {file_format.description} has no full-rate IMU stream (only "
                            f"{formats.described([formats.FORMATS[name] for name in FAST_IMU_FORMATS])} have one)")
        return file_format.loader()(Path(path), filters, forced, progress, imu=imu)
    if file_format.name != "recording":
        if accept_config_changes:
            raise UserError(f"{path}: a {file_format.description} has no CONFIG frames whose changes could be accepted")
        return file_format.loader()(Path(path), filters, forced, progress)
    return file_format.loader()(Path(path), filters, forced, progress, accept_config_changes, stream_estimates)


def computed(recording: Recording, filters=None, forced=None, progress=None, accept_config_changes: bool = False,
             stream_estimates: bool = False) -> Pipeline | BatchSession:
    """A recording's session computed whole: the project's frames on the batch path (the same tables as
    a replay, tests/session/test_batch.py; its estimators streamed if asked, ``load_session``); an
    autopilot's MAVLink through the incremental pipeline (its front-end turns messages into stage calls
    one by one; it has no batch form)."""
    if recording.metadata.get("protocol", "gs") == "gs":
        return batch_replay(recording, filters, forced, progress, accept_config_changes, stream_estimates)
    return replay(recording, filters, forced, progress, accept_config_changes)


def trial_from_samples(samples: dict[str, np.ndarray], path) -> Trial:
    try:
        return trial_from_columns(samples, f"{path} (imported samples)")
    except DatasetError as error:
        raise UserError(str(error)) from None


def from_trial(trial: Trial, filters, settings_used, metadata: dict, origin_s: float | None = None) -> SessionData:
    """A dataset trial, run exactly as ``evaluate_trial`` runs it (the same numbers). Session time counts
    from ``origin_s``, the trial's first time (default: its first row's; an imported recording says it,
    so rows after a lost first block keep their own times)."""
    try:
        runs = run_on_trial(trial, filters, settings_used)
    except ValueError as error:
        raise UserError(str(error)) from None
    time_s = trial.time_s - (trial.time_s[0] if origin_s is None else origin_s)
    tables = session_catalogue({name: tuple(diag) for name, (_, diag) in runs.items()})
    catalogue = Catalogue({"imu": tables["imu"], ONBOARD: tables[ONBOARD]})  # a dataset has no onboard estimate: no rows
    imu = {"time_s": time_s, **{f"acc_{a}_g": trial.acc_m_s2[:, i] / STANDARD_GRAVITY_M_S2 for i, a in enumerate("xyz")},
           **{f"gyr_{a}_rad_s": trial.gyr_rad_s[:, i] for i, a in enumerate("xyz")}}
    for name, (q, diagnostics) in runs.items():
        imu.update(estimate_columns(name, q, diagnostics))
    settings = {name: dataclasses.asdict(create(name, (settings_used or {}).get(name, {})).settings) for name in runs}
    return build_product(metadata, catalogue, {"imu": imu}, runs, true_q=trial.true_q, true_frame="ENU",
                         moving=trial.moving, magnetometer=trial.mag_uT is not None, settings_at_start=settings,
                         settings_at_end=settings)


def from_pipeline(recording: Recording, pipeline: Pipeline | BatchSession) -> SessionData:
    """A recording's product: what the pipeline (or the batch path) computed, as it computed it."""
    batch = isinstance(pipeline, BatchSession)
    data = pipeline_product(recording.metadata, pipeline, list(recording.damage), pipeline.streamed if batch else None,
                            pipeline.held_estimates if batch else None)
    if recording.record_counts["sample_blocks"]:
        truth = recording.sample_columns([*TRUE_Q, "moving", "board_epoch", "board_clock_us", "time_s"])
        if "true_qw" in truth:
            attach_sensor_truth(data, truth, data.tables[data.sample_table]["device_time_us"], pipeline)
    return data


def pipeline_product(metadata: dict, pipeline: Pipeline | BatchSession, damage: list, estimates=None,
                     held: dict[str, np.ndarray] | None = None) -> SessionData:
    """A decoded session's product (a recording's, a ``.tlog``'s): the pipeline's tables, link, events and
    settings (``estimates``: the streamed ones, ``SessionData.estimates``; ``held``: ``imu`` columns the batch
    path holds apart from its table, ``BatchSession.held_estimates``); an autopilot simulator's SIMSTATE as its
    truth (``attach_simstate_truth``)."""
    t0_ns = pipeline.t0_host_ns or 0
    # A table at a time, each let go as its columns are made: never the pipeline's rows and the product's whole.
    tables = {name: table.hand_over({c.name: held_dtype(c) for c in pipeline.catalogue[name].columns})
              for name, table in pipeline.tables.items()}
    tables["imu"].update(held or {})
    data = build_product(
        metadata, pipeline.catalogue, tables,
        pipeline.filters, protocol=metadata.get("protocol", "gs"),
        link=LinkSummary(pipeline.decoder.stats.as_dict(), pipeline.link.per_second.to_dict()), config=pipeline.config,
        # An event from before the first byte (the replay's notes on the recording itself) is at its start.
        events=[{**event, "t_s": max(event["t_host_ns"] - t0_ns, 0) / 1e9} for event in pipeline.events],
        settings_at_start=pipeline.bank.at_start, settings_at_end=pipeline.settings(), damage=damage,
        parameters=dict(pipeline.parameters), magnetometer=len(pipeline.tables.get("mag_raw", ())) > 0, estimates=estimates,
    )
    if data.protocol == "mavlink":
        data.metadata["imu_choice"] = pipeline.front.imu_choice.said()
        attach_simstate_truth(data)
    return data


def attach_sensor_truth(data: SessionData, samples: dict[str, np.ndarray], device_us: np.ndarray, pipeline: Pipeline) -> None:
    """Truth stored with a simulated recording (sensor axes -> ENU) onto the body axes, sample by sample.

    The simulator says what the board's clock read at each truth row and how many resets and clock
    jumps came before (``board_clock_us``, ``board_epoch``: sim/truth_file.py); the session counts the
    same in its ``device_reset`` and ``clock_jump`` events, so each sample finds its own instant's
    truth across every restart. A recording without those columns (older) has the board's clock in
    ``time_s`` up to the first restart: the later samples get no truth rather than another instant's.
    """
    wrap = float(1 << 32)
    if "board_epoch" in samples:
        truth_key = samples["board_epoch"] * wrap + samples["board_clock_us"]
    else:
        truth_key = np.rint(samples["time_s"] * 1e6)
    restarts = [e["session_time_s"] for e in pipeline.events if e["kind"] in DISCONTINUITIES]
    sample_key = np.searchsorted(restarts, data.time_s, side="right") * wrap + np.mod(device_us, wrap)
    order = np.argsort(truth_key, kind="stable")
    truth_key = truth_key[order]
    q_sensor = aligned(sample_key, truth_key, [samples[c][order] for c in TRUE_Q])
    q_body_from_sensor = quaternion.from_matrix(mounting.matrix(pipeline.sensor.mounting))
    data.true_q = quaternion.multiply(q_sensor, quaternion.conjugate(q_body_from_sensor))
    data.true_frame = "ENU"
    if "moving" in samples:
        data.moving = aligned(sample_key, truth_key, [samples["moving"][order]])[:, 0] == 1.0



def estimators_for(path) -> tuple[str, ...] | None:
    """The estimators a file opens with when none are asked, in the app and in every command: a
    recording's own (None); for files that record none (flight logs, dataset CSVs) the live estimators
    (``live_estimators``, those the app shows) whose needs such a file meets (``formats.FILE_AIDING``).
    An export then writes those the data met (``export.request.run_export``)."""
    file_format = formats.sniff(path)
    if file_format is not None and not file_format.replayable:
        return runnable(formats.FILE_AIDING, live_estimators())
    return None


def planned_estimators(path, filters=None) -> tuple[str, ...]:
    """The estimators ``load_session(path, filters)`` runs: ``filters``, else those ``estimators_for`` the
    file, else (a recording) those it recorded."""
    if filters is not None:
        return tuple(dict.fromkeys(filters))
    named = estimators_for(path)
    if named is not None:
        return named
    return tuple(recorded_filters(open_recording(path))[0])


def not_compiled(names) -> tuple[str, ...]:
    """Those of ``names`` whose batch run would compile first (``Estimator.runs_compiled``), the aiding
    estimator first (the compass heading and the position wait for it) and the slow ones last."""
    aiding = aiding_estimator(tuple(names))
    waiting = [name for name in names if name in ESTIMATORS and not ESTIMATORS[name].runs_compiled()]
    return tuple(sorted(waiting, key=lambda name: (slow_interpreted(name), name != aiding)))


class Loading:
    """``load_session(path, filters, forced)`` in a worker thread. The window polls ``fraction`` and
    ``done``; then ``data`` is the computed session, or ``error`` says, for the user, why there is none.
    ``cancel`` stops it at its next progress report (its result is dropped in any case).

    ``compile_in_background`` (the app): never wait for numba to compile. The estimators whose batch run
    is not compiled (a first start, numba's cache empty: 30 CPU s for all) are left out (``pending``) and
    compiled by another process (``warm_up``, ``estimation.warm_up``), so the file's sensors, onboard
    estimate and compiled estimators show within seconds; the window loads the file again as the others
    are ready. Why not their source interpreted, as a live session runs it: over a whole file that takes
    17-520 µs a sample and estimator, an hour's flight at 100 Hz about 60 CPU s for the seven fast ones (twice
    what compiling every kernel costs) and minutes for ukf and sssrukf (bench/bench_first_data.out.md)."""

    def __init__(self, path, filters=None, forced=None, imu: str = IMU_STREAMS[0], compile_in_background: bool = False):
        self.path = Path(path)
        self.setup = (filters, forced)
        self.imu = imu
        self.fraction = 0.0
        self.done = False
        self.data: SessionData | None = None
        self.error: str | None = None
        self._background = compile_in_background
        self.pending: tuple[str, ...] = ()  # left out of ``data``, compiling in ``warm_up``
        self.warm_up: WarmUp | None = None
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._run, name="groundstation-load", daemon=True)
        self._thread.start()

    def _progress(self, done: int, total: int) -> None:
        if self._cancel.is_set():
            raise _Cancelled
        self.fraction = done / total if total else 0.0

    def _run(self) -> None:
        try:
            filters, forced = self._compiled_only(*self.setup) if self._background else self.setup
            self.data = load_session(self.path, filters, forced, progress=self._progress, imu=self.imu)
            self.fraction = 1.0
        except _Cancelled:
            self.error = "cancelled"
        except UserError as error:
            self.error = str(error)
        except OSError as error:
            self.error = f"{self.path}: cannot be read ({error.strerror or error})"
        except Exception as error:  # noqa: BLE001 — a reader's bug must reach the window as a message, not a traceback
            self.error = f"{self.path}: cannot be opened ({type(error).__name__}: {error})"
        self.done = True

    def _compiled_only(self, filters, forced) -> tuple:
        """``(filters, forced)`` without the estimators not compiled (``not_compiled``), which another
        process compiles meanwhile."""
        planned = planned_estimators(self.path, filters)
        self.pending = not_compiled(planned)
        if not self.pending:
            return filters, forced
        self.warm_up = warm_up(self.pending, runs_first=True)
        return (tuple(name for name in planned if name not in self.pending),
                {name: values for name, values in (forced or {}).items() if name not in self.pending})

    def cancel(self) -> None:
        self._cancel.set()

    def wait(self, timeout_s: float | None = None) -> None:
        self._thread.join(timeout_s)


class _Cancelled(Exception):
    """Raised from the progress callback to stop a load nobody waits for any more."""
