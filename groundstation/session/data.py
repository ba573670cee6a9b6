"""A whole session as columns, whatever it came from: a recording of the link, an imported dataset
CSV (a recording holding sample columns), or a dataset CSV read directly.

Exports and evaluation read ``SessionData``; they never know the source.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from groundstation import formats, mounting, quaternion
from groundstation.datasets import TRUE_Q, DatasetError, Trial, trial_from_columns
from groundstation.errors import UserError
from groundstation.estimation import create
from groundstation.estimation.evaluation import run_on_trial, scores, uses_magnetometer
from groundstation.recording import Recording
from groundstation.session.batch import BatchSession, batch_replay
from groundstation.session.catalogue import Catalogue, session_catalogue
from groundstation.session.clock import DISCONTINUITIES
from groundstation.session.pipeline import Pipeline
from groundstation.session.replay import replay
from groundstation.units import STANDARD_GRAVITY_M_S2


@dataclasses.dataclass(frozen=True)
class LinkSummary:
    """How the link did: the decoder's counters over the whole session, and per second of host time."""

    counters: dict[str, int]  # firmware_protocol.DecoderStats fields
    per_second: dict[str, np.ndarray]  # session.link.PER_SECOND_COLUMNS, each (seconds,)


@dataclasses.dataclass
class SessionData:
    metadata: dict
    time_s: np.ndarray  # (N,) session time in seconds from the first sample (docs/time.md); monotonic
    estimates: dict[str, np.ndarray]  # name -> (N, 4) quaternions w-first, body -> NED
    diagnostics: dict[str, dict[str, np.ndarray]]  # name -> field -> (N,)
    sensors: dict[str, np.ndarray]  # acc_*_g, gyr_*_dps (body axes), temperature_c, each (N,)
    onboard: np.ndarray | None = None  # (N, 4) the aircraft's estimate at the same samples (NaN if none)
    true_q: np.ndarray | None = None  # (N, 4) truth rotating body vectors into true_frame
    true_frame: str = "ENU"
    moving: np.ndarray | None = None  # (N,) bool: the samples an evaluation scores
    magnetometer: bool = False  # the estimators had magnetometer readings (so heading is scored)
    damage: list[str] = dataclasses.field(default_factory=list)  # what the recording lost
    # Every table of the session as columns (``imu``, ``onboard``, one per frame, ``position``), as
    # ``catalogue`` describes them; a dataset trial has only ``imu``.
    tables: dict[str, dict[str, np.ndarray]] = dataclasses.field(default_factory=dict)
    catalogue: Catalogue | None = None
    link: LinkSummary | None = None  # None: not decoded from a link (a dataset)
    config: dict | None = None  # the aircraft's last CONFIG frame
    events: list[dict] = dataclasses.field(default_factory=list)  # each with ``t_s``: seconds from the first byte
    settings_at_start: dict[str, dict[str, float]] = dataclasses.field(default_factory=dict)
    settings_at_end: dict[str, dict[str, float]] = dataclasses.field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.time_s)

    @property
    def warnings(self) -> list[str]:
        """What every command says besides its result: what the recording lost, then the session's warnings."""
        return [*self.damage, *(str(e["message"]) for e in self.events if e.get("kind") in ("warning", "config_conflict"))]

    def evaluate(self) -> dict[str, dict[str, float]]:
        """Inclination RMSE / max of every estimator against the truth (BROAD's metric), and heading RMSE /
        max of those that use the magnetometer when the session has one (``evaluation``)."""
        if self.true_q is None:
            raise UserError("this session has no truth to evaluate against (true_qw ... true_qz)")
        mask = self.moving if self.moving is not None else np.ones(len(self), dtype=bool)
        estimates = dict(self.estimates)
        if self.onboard is not None and np.isfinite(self.onboard).any():
            estimates["onboard"] = self.onboard  # the aircraft's own AHF, scored the same way
        try:
            return {n: scores(q, self.true_q, mask, self.true_frame, self.magnetometer and uses_magnetometer(n)) for n, q in estimates.items()}
        except ValueError as error:
            raise UserError(str(error)) from None


def load_session(path, filters=None, forced=None, progress=None, accept_config_changes: bool = False) -> SessionData:
    """Decode, import or read ``path`` by its format (``formats``) and run the estimators; UserError with a
    clear message on bad input. A file of no known format is tried as a recording, whose reader says
    what the file looks like instead. ``accept_config_changes``: a recording's CONFIG that changes the
    scales without a device restart applies (else the first scales are kept, and said; ``ConfigGuard``)."""
    file_format = formats.sniff(path) or formats.FORMATS["recording"]
    if not accept_config_changes:
        return file_format.loader()(Path(path), filters, forced, progress)
    if file_format.name != "recording":
        raise UserError(f"{path}: a {file_format.description} has no CONFIG frames whose changes could be accepted")
    return file_format.loader()(Path(path), filters, forced, progress, accept_config_changes=True)


def computed(recording: Recording, filters=None, forced=None, progress=None,
             accept_config_changes: bool = False) -> Pipeline | BatchSession:
    """A recording's session computed whole: the project's frames on the batch path (the same tables as
    a replay, tests/session/test_batch.py); an autopilot's MAVLink through the incremental pipeline
    (its front-end turns messages into stage calls one by one; it has no batch form)."""
    if recording.metadata.get("protocol", "gs") == "gs":
        return batch_replay(recording, filters, forced, progress, accept_config_changes)
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
    estimates = {name: q for name, (q, _) in runs.items()}
    diagnostics = {name: diag for name, (_, diag) in runs.items()}
    acc_g = trial.acc_m_s2 / STANDARD_GRAVITY_M_S2
    sensors = {f"acc_{a}_g": acc_g[:, i] for i, a in enumerate("xyz")}
    sensors.update({f"gyr_{a}_dps": np.degrees(trial.gyr_rad_s[:, i]) for i, a in enumerate("xyz")})
    time_s = trial.time_s - (trial.time_s[0] if origin_s is None else origin_s)
    catalogue = session_catalogue({name: tuple(diag) for name, diag in diagnostics.items()})
    imu = {"time_s": time_s, **{f"acc_{a}_g": acc_g[:, i] for i, a in enumerate("xyz")},
           **{f"gyr_{a}_rad_s": trial.gyr_rad_s[:, i] for i, a in enumerate("xyz")}}
    for name, q in estimates.items():
        imu.update({f"{name}_q{c}": q[:, i] for i, c in enumerate("wxyz")})
        imu.update({f"{name}_{d}": values for d, values in diagnostics[name].items()})
    nan = np.full(len(time_s), np.nan)
    tables = {"imu": {c: imu.get(c, nan) for c in catalogue["imu"].column_names}}
    settings = {name: dataclasses.asdict(create(name, (settings_used or {}).get(name, {})).settings) for name in estimates}
    return SessionData(
        metadata=dict(metadata), time_s=time_s, estimates=estimates, diagnostics=diagnostics,
        sensors=sensors, true_q=trial.true_q, true_frame="ENU", moving=trial.moving, magnetometer=trial.mag_uT is not None,
        tables=tables, catalogue=catalogue, settings_at_start=settings, settings_at_end=settings,
    )


def from_pipeline(recording: Recording, pipeline: Pipeline | BatchSession) -> SessionData:
    if not len(pipeline.imu) and len(pipeline.onboard):
        return onboard_only(recording, pipeline)
    whole = product(pipeline)
    imu = whole["tables"]["imu"]
    estimates = {n: np.column_stack([imu[f"{n}_q{c}"] for c in "wxyz"]) for n in pipeline.filters}
    diagnostics = {n: {d: imu[f"{n}_{d}"] for d in fields} for n, fields in pipeline.bank.diagnostics().items()}
    sensors = {f"acc_{a}_g": imu[f"acc_{a}_g"] for a in "xyz"}
    sensors.update({f"gyr_{a}_dps": np.degrees(imu[f"gyr_{a}_rad_s"]) for a in "xyz"})
    sensors["temperature_c"] = imu["temperature_c"]
    device_us = imu["device_time_us"]
    onboard = None
    if len(pipeline.onboard):  # by session time: device time repeats after a reboot
        board = whole["tables"]["onboard"]
        onboard = aligned(imu["time_s"], board["time_s"], np.column_stack([board[f"q{c}"] for c in "wxyz"]))
    data = SessionData(
        metadata=dict(recording.metadata), time_s=imu["time_s"], estimates=estimates, diagnostics=diagnostics,
        sensors=sensors, onboard=onboard, damage=list(recording.damage), **whole,
        magnetometer=len(whole["tables"].get("mag_raw", {}).get("time_s", ())) > 0,
    )
    if "true_qw" in recording.samples:
        attach_sensor_truth(data, recording.samples, device_us, pipeline)
    return data


def product(pipeline: Pipeline) -> dict:
    """What a decoded session hands out besides the IMU view: every table, the link, config, events, settings."""
    t0_ns = pipeline.t0_host_ns or 0
    return dict(
        tables={name: table.to_dict() for name, table in pipeline.tables.items()},
        catalogue=pipeline.catalogue,
        link=LinkSummary(pipeline.decoder.stats.as_dict(), pipeline.link.per_second.to_dict()),
        config=pipeline.config,
        events=[{**event, "t_s": (event["t_host_ns"] - t0_ns) / 1e9} for event in pipeline.events],
        settings_at_start=pipeline.bank.at_start,
        settings_at_end=pipeline.settings(),
    )


def onboard_only(recording: Recording, pipeline: Pipeline) -> SessionData:
    """A flight in "estimated" mode: the aircraft sent its attitude but no raw IMU samples."""
    whole = product(pipeline)
    board = whole["tables"]["onboard"]
    data = SessionData(
        metadata=dict(recording.metadata), time_s=board["time_s"], estimates={}, diagnostics={}, sensors={},
        onboard=np.column_stack([board[f"q{c}"] for c in "wxyz"]), damage=list(recording.damage), **whole,
    )
    if "true_qw" in recording.samples:
        attach_sensor_truth(data, recording.samples, board["device_time_us"], pipeline)
    return data


def aligned(times: np.ndarray, other_times: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` (rows at ``other_times``, sorted) at the rows of ``times``; NaN where no row has that time."""
    out = np.full((len(times), values.shape[1]), np.nan)
    index = np.searchsorted(other_times, times)
    index = np.clip(index, 0, max(len(other_times) - 1, 0))
    hit = other_times[index] == times if len(other_times) else np.zeros(len(times), dtype=bool)
    out[hit] = values[index[hit]]
    return out


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
    q_sensor = aligned(sample_key, truth_key, np.column_stack([samples[c] for c in TRUE_Q])[order])
    q_body_from_sensor = quaternion.from_matrix(mounting.matrix(pipeline.sensor.mounting))
    data.true_q = quaternion.multiply(q_sensor, quaternion.conjugate(q_body_from_sensor))
    data.true_frame = "ENU"
    if "moving" in samples:
        data.moving = aligned(sample_key, truth_key, samples["moving"][order][:, None])[:, 0] == 1.0
