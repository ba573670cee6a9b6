"""The product of a session, whatever made it: the live pipeline, the batch path, a flight-log reader
or the dataset reader. One shape, filled by one builder (``build_product``):

- ``tables``: every table as columns, exactly as ``catalogue`` describes them (``imu`` with every
  estimator's quaternion and diagnostics, ``onboard``, one per frame or message type, ``position``), each in
  its form (``held_dtype``: the host estimators' columns float32, sized for showing, unless made exact);
- ``events``, ``link`` (the decoder's counters), ``config``, the estimators' settings at start and end;
- ``parameters``: an autopilot's parameters, name -> value as last set (their changes are events), and
  ``parameter_defaults`` where the log says them (a MAVLink link does not);
- ``protocol``: what the link spoke ("gs", "mavlink"; None for a dataset), ``metadata``, ``damage``;
- the truth an evaluation scores against, on the sample rows, where the session has one.

Readers (exports, evaluation, the window) read the tables; what they show beyond them (angles in
degrees) is derived by one function each (``quaternion.euler_deg``). No pipeline here: this module
is the layer the readers and the makers share.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses

import numpy as np

from groundstation.autopilot.imu_rate import IMU_RATE, slow_imu_note
from groundstation.errors import UserError
from groundstation.estimation.evaluation import scores, uses_magnetometer
from groundstation.session_parts.catalogue import Catalogue, Column
from groundstation.session_parts.figures import loss_pct, rate_hz, span_s

AIDING_TABLES = {"mag": "mag_raw", "gps": "gps"}  # an aiding an estimator needs (``Estimator.needs``): the table whose rows give it
ONBOARD = "onboard"  # the aircraft's own estimate: a table, and an attitude scored beside the host estimators


@dataclasses.dataclass(frozen=True)
class LinkSummary:
    """How the link did: the decoder's counters over the whole session, and per second of host time."""

    counters: dict[str, int]  # firmware_protocol.DecoderStats fields
    per_second: dict[str, np.ndarray]  # session_parts.link.PER_SECOND_COLUMNS, each (seconds,)


@dataclasses.dataclass
class SessionData:
    metadata: dict
    tables: dict[str, dict[str, np.ndarray]]  # name -> column -> (rows,), as ``catalogue`` describes them
    catalogue: Catalogue
    filters: tuple[str, ...]  # the host estimators: their columns are in ``imu``
    protocol: str | None = None  # what the link spoke; None: no link (a dataset)
    magnetometer: bool = False  # the estimators had magnetometer readings (so heading is scored)
    link: LinkSummary | None = None  # None: not decoded from a link (a dataset, a flight log)
    config: dict | None = None  # the aircraft's last CONFIG frame
    events: list[dict] = dataclasses.field(default_factory=list)  # each with ``t_s``: seconds from the first byte
    settings_at_start: dict[str, dict[str, float]] = dataclasses.field(default_factory=dict)
    settings_at_end: dict[str, dict[str, float]] = dataclasses.field(default_factory=dict)
    damage: list[str] = dataclasses.field(default_factory=list)  # what the recording lost
    true_q: np.ndarray | None = None  # (N, 4) on the sample rows: truth rotating body vectors into true_frame
    true_frame: str = "ENU"
    moving: np.ndarray | None = None  # (N,) bool on the sample rows: the samples an evaluation scores
    parameters: dict[str, float] = dataclasses.field(default_factory=dict)  # an autopilot's: name -> last value
    parameter_defaults: dict[str, float] = dataclasses.field(default_factory=dict)  # name -> default, where the log says it
    # Host estimators whose ``imu`` columns are not in ``tables`` but made a stretch of rows at a time, forward
    # only (an export's: ``session_makers.estimate_run.Streamed``); read through ``attitudes(rows)``
    estimates: object | None = None

    @property
    def sample_table(self) -> str:
        """The table whose rows are the session's samples: ``imu``, or ``onboard`` for a flight that sent
        its attitude but no IMU samples ("estimated" mode)."""
        return "imu" if len(self.tables["imu"]["time_s"]) or ONBOARD not in self.tables else ONBOARD

    @property
    def time_s(self) -> np.ndarray:
        """(N,) session time of the samples in seconds (docs/time.md); monotonic."""
        return self.tables[self.sample_table]["time_s"]

    def __len__(self) -> int:
        return len(self.time_s)

    def imu_rate_hz(self) -> float:
        """The IMU's sample rate (``figures.rate_hz``); NaN without IMU samples."""
        return rate_hz(self.tables["imu"]["time_s"]) if "imu" in self.tables else float("nan")

    def link_loss_pct(self) -> float:
        """Frames lost, % of those sent (``figures.loss_pct``); NaN without a link (a dataset, a flight log)."""
        if self.link is None:
            return float("nan")
        return loss_pct(self.link.counters.get("frames", 0), self.link.counters.get("frames_lost", 0))

    def duration_s(self) -> float:
        """From the first sample row to the last (``figures.span_s``)."""
        return span_s(self.time_s)

    @property
    def warnings(self) -> list[str]:
        """What every command says besides its result: what the recording lost, an IMU too slow to filter (at
        the rate the figures give, ``imu_rate_hz``: not the live warning's, measured on the samples come by
        then), then the session's warnings."""
        slow = [note] if (note := slow_imu_note(self.imu_rate_hz())) else []
        return [*self.damage, *slow, *(str(e["message"]) for e in self.events
                                       if e.get("kind") in ("warning", "config_conflict") and e.get("about") != IMU_RATE)]

    def quaternion(self, name: str, rows: np.ndarray | None = None) -> np.ndarray:
        """(N, 4) w-first, body -> NED, on the sample rows (those of ``rows``): a host estimator's, or
        ``onboard`` (its rows at the same session time; NaN on the others: device time repeats after a reboot)."""
        at = slice(None) if rows is None else rows
        if name != ONBOARD:
            imu = self.tables["imu"]
            return np.column_stack([imu[f"{name}_q{c}"][at] for c in "wxyz"])
        board = self.tables[ONBOARD]
        return aligned(self.time_s[at], board["time_s"], [board[f"q{c}"] for c in "wxyz"])

    @property
    def estimated(self) -> tuple[str, ...]:
        """The host estimators that ran: ``filters``, none for a session without IMU samples."""
        return self.filters if self.sample_table == "imu" else ()

    def aiding(self) -> frozenset[str]:
        """The aiding the estimators had ("mag", "gps"; ``Estimator.needs``): a sensor with readings in the session."""
        had = {need for need, table in AIDING_TABLES.items() if len(self.tables.get(table, {}).get("time_s", ()))}
        return frozenset(had | ({"mag"} if self.magnetometer else set()))

    def has_onboard(self) -> bool:
        return ONBOARD in self.tables and bool(np.isfinite(self.tables[ONBOARD]["qw"]).any())

    def attitudes(self, rows: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Every estimate on the sample rows (those of ``rows``): the host estimators, then the aircraft's own
        when it sent one. Streamed estimates (``estimates``) are made for ``rows``, which must then follow the
        rows asked before."""
        streamed = {}
        if self.estimates is not None and self.estimated:
            if rows is None:
                raise ValueError("streamed estimates are made a stretch of rows at a time: name the rows")
            columns = self.estimates.at(rows, tuple(f"{name}_q{c}" for name in self.estimates.names for c in "wxyz"))
            streamed = {name: np.column_stack([columns[f"{name}_q{c}"] for c in "wxyz"]) for name in self.estimates.names}
        out = {name: streamed[name] if name in streamed else self.quaternion(name, rows) for name in self.estimated}
        if self.has_onboard():
            out[ONBOARD] = self.quaternion(ONBOARD, rows)
        return out

    def evaluate(self) -> dict[str, dict[str, float]]:
        """Inclination RMSE / max of every estimate against the truth (BROAD's metric), and heading RMSE /
        max of those that use the magnetometer when the session has one (``evaluation``)."""
        if self.true_q is None:
            raise UserError("this session has no truth to evaluate against (true_qw ... true_qz)")
        mask = self.moving if self.moving is not None else np.ones(len(self), dtype=bool)
        try:
            return {n: scores(q, self.true_q, mask, self.true_frame, self.magnetometer and uses_magnetometer(n))
                    for n, q in self.attitudes().items()}
        except ValueError as error:
            raise UserError(str(error)) from None


# True while a session is made for a reader that writes the estimators' values (an export, a report): every
# column held float64. A context of its own per thread: the app's loads and exports run in worker threads.
_EXACT = contextvars.ContextVar("exact_estimates", default=False)


@contextlib.contextmanager
def exact_estimates(exact: bool = True):
    """Within, sessions are made with every column in float64 (``held_dtype``): ``load_session(exact=True)``."""
    token = _EXACT.set(exact)
    try:
        yield
    finally:
        _EXACT.reset(token)


def held_dtype(column: Column) -> np.dtype:
    """The dtype a product holds ``column`` in: the catalogue's form (``Column.held``), float64 when exact."""
    return np.dtype(float if _EXACT.get() else column.held)


def event_time_s(event: dict) -> float:
    """An event's session time: the clock's own when the event carries it, else seconds from the first byte."""
    return float(event.get("session_time_s", event["t_s"]))


def build_product(metadata: dict, catalogue: Catalogue, tables: dict[str, dict[str, np.ndarray]], filters,
                  **rest) -> SessionData:
    """The one way a ``SessionData`` is made: every table the catalogue names, with exactly its columns
    in its order, each in its form (``held_dtype``: ``Column.held``, float64 for every column when made exact) (NaN
    for a column the maker has no values for; an empty table for one it never filled; none for the ``imu`` columns
    of streamed estimators, ``rest["estimates"]``); ``rest``: the
    other fields. ValueError for a table the catalogue does not describe or columns of different lengths
    (a maker's bug, not bad input)."""
    unknown = sorted(set(tables) - set(catalogue.tables))
    if unknown:
        raise ValueError(f"tables {unknown} are not in the catalogue")
    streamed = set(rest["estimates"].columns) if rest.get("estimates") is not None else set()
    filled = {}
    for info in catalogue:
        columns = tables.get(info.name, {})
        rows = len(columns["time_s"]) if "time_s" in columns else 0
        nan = np.full(rows, np.nan)
        filled[info.name] = {c.name: np.asarray(columns.get(c.name, nan), dtype=held_dtype(c)) for c in info.columns
                             if info.name != "imu" or c.name not in streamed}
        lengths = {len(v) for v in filled[info.name].values()}
        if len(lengths) > 1:
            raise ValueError(f"table {info.name}: columns of different lengths {sorted(lengths)}")
    return SessionData(metadata=dict(metadata), tables=filled, catalogue=catalogue, filters=tuple(filters), **rest)


def estimate_columns(name: str, q: np.ndarray, diagnostics: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """An estimator's run as its ``imu`` columns (``catalogue.estimator_columns``)."""
    return {**{f"{name}_q{c}": q[:, i] for i, c in enumerate("wxyz")}, **{f"{name}_{d}": v for d, v in diagnostics.items()}}


def aligned(times: np.ndarray, other_times: np.ndarray, columns: list[np.ndarray]) -> np.ndarray:
    """``columns`` (each with a row at each of ``other_times``, sorted) at the rows of ``times``: (N, k), NaN
    where no row has that time. Only the rows found are read."""
    out = np.full((len(times), len(columns)), np.nan)
    index = np.searchsorted(other_times, times)
    index = np.clip(index, 0, max(len(other_times) - 1, 0))
    hit = other_times[index] == times if len(other_times) else np.zeros(len(times), dtype=bool)
    for i, column in enumerate(columns):
        out[hit, i] = column[index[hit]]
    return out
